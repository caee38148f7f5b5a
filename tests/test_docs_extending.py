"""docs/extending.md runs as written: its code blocks, in order, with their printed output."""

import contextlib
import io
import re
from pathlib import Path

import pytest

DOC = Path(__file__).resolve().parents[1] / "docs" / "extending.md"


def _blocks(text: str) -> list[tuple[str, str]]:
    """(kind, body) of every fenced block, kind 'python' or 'text'."""
    return re.findall(r"```(python|text)\n(.*?)```", text, flags=re.S)


def test_the_extending_page_runs_and_prints_what_it_shows():
    blocks = _blocks(DOC.read_text())
    assert sum(k == "python" for k, _ in blocks) >= 4
    namespace: dict = {"__name__": "docs_extending"}
    printed = ""
    checked = 0
    for kind, body in blocks:
        if kind == "python":
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                exec(compile(body, str(DOC), "exec"), namespace)  # noqa: S102
            printed = out.getvalue()
        else:
            assert printed.strip() == body.strip()
            checked += 1
    assert checked == 2
    # the fitted tanh output block recovered the truth to within the noise
    assert namespace["fit"].model.parameters["gain"] == pytest.approx(2.0, abs=0.01)


def test_a_user_block_is_chosen_by_name_through_the_registry():
    import numpy as np

    from blockid.blocks.base import StaticBlock
    from blockid.fitting.registry import OPTIONS

    class Cubic(StaticBlock):
        kind = "test-cubic"

        def __init__(self, c: float = 0.0) -> None:
            self.c = float(c)

        @property
        def parameters(self):
            return {"c": self.c}

        @classmethod
        def template(cls, c: float = 0.0):
            return cls(c)

        def __call__(self, x):
            x = np.asarray(x, dtype=float)
            return x + self.c * x**3

    block = OPTIONS["output_block"].convert("test-cubic:c=0.25")
    assert type(block) is Cubic and block.c == 0.25
    # numerical defaults: the Jacobian and derivative of x + c x^3
    x = np.array([-1.0, 0.5, 2.0])
    np.testing.assert_allclose(block.jacobian(x)[:, 0], x**3, rtol=1e-6)
    np.testing.assert_allclose(block.derivative(x), 1 + 0.75 * x**2, rtol=1e-6)
    np.testing.assert_allclose(block.inverse_on(block(x), (-3.0, 3.0)), x, atol=1e-12)
