"""The exported module's runtime (models/_export_runtime.py): it is the text the export
copies, and its polynomial rules equal NumPy's."""

from __future__ import annotations

import ast

import numpy as np

from blockid.blocks import (
    Polynomial,
)
from blockid.models import (
    Wiener,
)


# ----------------------------------------------------------------------------- the runtime
def test_the_exported_runtime_is_the_runtime_module_below_its_marker():
    """The interpreter is a real module (linted, covered); the export copies it whole."""
    from importlib.resources import files

    from blockid.models import export as export_module

    m = Wiener("u", "y", output_block=Polynomial([1.0, 0.2], constant=False),
               na=1, nb=1, nk=1, a=[-0.5], b=[1.0])  # fmt: skip
    text = files("blockid.models").joinpath("_export_runtime.py").read_text(encoding="utf-8")
    runtime = text[text.index(export_module._MARKER) + len(export_module._MARKER) :]
    source = export_module.to_python_module(m)
    assert source.endswith(runtime) and "def simulate(u, y0=None)" in runtime
    ast.parse(source)


def test_the_runtime_polynomial_rules_equal_numpys():
    from numpy.polynomial import polynomial as P

    from blockid.models import _export_runtime as rt

    c = [0.3, -1.0, 0.5, 0.25]
    x = np.linspace(-2, 2, 9)
    assert np.allclose(rt._polyval(x, c), P.polyval(x, c), rtol=1e-14, atol=1e-14)
    assert np.allclose(rt._derivative(c), P.polyder(c))
    assert np.allclose(rt._derivative([2.0]), [0.0])
