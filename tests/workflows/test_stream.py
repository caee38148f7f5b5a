"""blockid.workflows.stream: a session's events, its checkpoints among them."""

from __future__ import annotations

import numpy as np

from blockid.workflows.stream import Checkpoint, Final, StreamSession


def _lines(n: int, seed: int = 0) -> list[str]:
    """An ARX(2, 2, 1) record as CSV lines, header first."""
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 1.5 * y[k - 1] - 0.7 * y[k - 2] + u[k - 1] + 0.5 * u[k - 2]
    y += 0.01 * rng.standard_normal(n)
    return ["u,y", *(f"{a:.17g},{b:.17g}" for a, b in zip(u, y, strict=True))]


def test_a_checkpoint_comes_after_every_nth_sample_learned_not_before():
    session = StreamSession(_lines(620), "arx", ["u"], ["y"], method="rls",
                            options={"na": 2, "nb": 2, "nk": 1}, checkpoint=250)  # fmt: skip
    events = list(session)
    points = [e for e in events if isinstance(e, Checkpoint)]
    assert [p.record["n_samples"] for p in points] == [250, 500]
    assert [p.record["learner"]["rows"] for p in points] == [250, 500]
    assert [p.k for p in points] == [249, 499]  # the row of the 250th sample: row 249
    assert isinstance(events[-1], Final) and events[-1].n_samples == 620


def test_a_starting_model_whose_block_key_term_rls_cannot_learn_is_refused_by_name():
    """Key-term RLS learns paper B's polynomial blocks; a Hammerstein model with a
    saturation input block cannot seed it, and the stream says so (it used to fail with
    AttributeError: 'Saturation' object has no attribute 'order')."""
    import pytest

    from blockid.blocks import Saturation
    from blockid.errors import ParameterError
    from blockid.models import Hammerstein

    model = Hammerstein("u", "y", input_block=Saturation(-0.5, 0.5, 1.0), na=1, nb=2, nk=1,
                        a=[-0.6], b=[1.0, 0.3])  # fmt: skip
    u = np.random.default_rng(0).uniform(-1, 1, 60)
    lines = ["u,y", *(f"{a!r},{b!r}" for a, b in zip(u, model.simulate(u)[:, 0], strict=True))]
    with pytest.raises(ParameterError, match="input block is a 'saturation' block"):
        list(StreamSession(lines, "hammerstein", ["u"], ["y"], initial=model))
