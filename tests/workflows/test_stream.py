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
