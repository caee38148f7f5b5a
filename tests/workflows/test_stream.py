"""blockid.workflows.stream: a session's events (its checkpoints among them), the samples
it reads, a diverging row put back, and a stream with given scales against the one-pass
fit (the command: ``tests/cli/test_streaming.py``)."""

from __future__ import annotations

import json

import numpy as np

from blockid.data import Dataset
from blockid.fitting.key_term import fit_key_term_rls
from blockid.workflows.stream import (
    Checkpoint,
    Failure,
    Final,
    Step,
    StreamSession,
    read_samples,
    stream_identification,
)

from reference import (
    GLITCH_ROW,
    arx_csv_text,
    csv_text,
    flat_parameters,
    key_term_hw_record,
    record_221,
)


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


# nk=0: a huge input fails the update of its own sample (phi^T P phi overflows), so the
# divergence tests see the sample refused, not an estimate ruined by an accepted one
ARX_OPTS = {"na": 1, "nb": 2, "nk": 0}


def test_given_scales_end_with_the_scaled_one_pass_fit():
    """``fit`` has no flag for the scales: the library equivalence instead."""
    u, y = key_term_hw_record(20_000, seed=2)
    opts = {"na": 3, "nb": 3, "nk": 8, "forgetting": 0.999}
    lines = csv_text(u, y).splitlines()
    scales = {"input_scale": 0.6, "output_scale": 0.4}
    *_, final = stream_identification(
        lines, "hammerstein-wiener", ["u"], ["y"], options={**opts, **scales}
    )
    data = Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"])
    offline = fit_key_term_rls(data, "hammerstein-wiener", passes=1, scales=(0.6, 0.4), **opts)
    np.testing.assert_allclose(
        flat_parameters(final.parameters),
        flat_parameters(offline.model.to_dict()["parameters"]),
        rtol=0,
        atol=1e-9,
    )


def test_nothing_is_read_ahead():
    """Each sample is answered before the next line is asked for (a live pipe)."""
    asked = []

    def lines():
        for i, text in enumerate(arx_csv_text(20).splitlines()):
            asked.append(i)
            yield text

    events = stream_identification(lines(), "arx", ["u"], ["y"], options=ARX_OPTS)
    for event in events:
        if isinstance(event, Step):
            assert asked[-1] == event.k + 1  # the header is line 0
    assert isinstance(event, Final)


def test_read_samples_reports_bad_rows():
    rows = list(
        read_samples(
            ['{"u": 1, "y": 2}', "[1]", "{bad", '{"u": null, "y": 1}', '{"y": 1}'],
            ["u"],
            ["y"],
            "jsonl",
        )
    )
    assert rows[0].u == (1.0,) and rows[0].problem is None
    assert [r.problem for r in rows[1:]] == [
        "line 2 is a JSON list, not an object",
        "line 3 is not JSON (Expecting property name enclosed in double quotes)",
        "line 4: 'u' is None, not a number",
        "line 5 has no 'u'",
    ]


def test_a_diverging_row_puts_back_the_last_good_estimate_and_learning_goes_on():
    """Without the guard, a diverging row (here an input of 1e300 in its own regressor)
    is a failure line; the estimate confirmed good before it comes back, the row and
    the one whose regressor reaches back to it are taken in without learning, and
    learning goes on: the stream ends where a learner fed so by hand ends, bit for bit.
    (Before, the row was dropped: the rows after it had the wrong lags.)"""
    from blockid.fitting.online import online_estimator

    lines = arx_csv_text(120).splitlines()
    lines[71] = "1e300,0.5"  # row k=70
    events = list(stream_identification(lines, "arx", ["u"], ["y"], options=ARX_OPTS, guard=None))
    failures = [e for e in events if isinstance(e, Failure)]
    assert [e.k for e in failures] == [70]
    assert "diverged" in failures[0].message and "is restored" in failures[0].message
    good = int(failures[0].message.split("(of row ")[1].split(")")[0])
    held = [e for e in events if isinstance(e, Step) and e.not_learned]
    assert [e.k for e in held] == [71] and "reach back to row 70" in held[0].not_learned
    final = events[-1]
    assert final.n_samples == 120 and final.problem is None
    assert final.guard == {**final.guard, "diverged": 1, "held": 1}

    rows = [tuple(map(float, line.split(","))) for line in lines[1:]]
    by_hand = online_estimator("arx", "rls", ARX_OPTS, ["u"], ["y"])
    snapshot = by_hand.snapshot()  # the start's, unless a later one is confirmed
    for k, (u, y) in enumerate(rows):
        if k == 70:
            by_hand.rewind(snapshot)
        by_hand.update(u, y, learn=k not in (70, 71))
        if k == good:  # the estimate after row ``good``
            snapshot = by_hand.snapshot()
    assert final.parameters == by_hand.parameters()
    np.testing.assert_allclose(flat_parameters(final.parameters), [-0.5, 0.0, 2.0], atol=1e-6)


def test_a_checkpoint_inside_a_glitch_resumes_with_the_guard_where_it_stood():
    """Issue 37: the guard's state (its scale, ranges, the rows still held, the last good
    estimate) is in the checkpoint: stopped one row after a glitch, resumed, the stream
    ends as the uninterrupted one, held row and guard counts included."""
    from blockid.workflows.stream import StreamSession

    u, y = record_221()
    y[GLITCH_ROW, 0] = 1e8
    lines = csv_text(u, y).splitlines()
    session = StreamSession
    whole = list(session(lines, "arx", ["u"], ["y"], options=dict(na=2, nb=2, nk=1)))
    part = session(lines[: GLITCH_ROW + 3], "arx", ["u"], ["y"], options=dict(na=2, nb=2, nk=1))
    assert [e.k for e in part if isinstance(e, Step) and e.not_learned] == [70, 71]
    learner = json.loads(json.dumps(part.saved()[1]["learner"]))  # through the file
    resumed = list(session([lines[0], *lines[GLITCH_ROW + 3 :]], "arx", ["u"], ["y"],
                           resume=learner))  # fmt: skip
    assert resumed[0].k == 72 and "reach back to row 70" in resumed[0].not_learned
    assert resumed[-1].parameters == whole[-1].parameters
    assert resumed[-1].guard == whole[-1].guard == {**whole[-1].guard, "rejected": 1, "held": 2}
