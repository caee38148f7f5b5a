"""``blockid stream`` (:mod:`blockid.cli.streaming`): online learning from a pipe (the
library's sessions: ``tests/workflows/test_stream.py``).

The claim of issue 9: a 50 000-sample Hammerstein-Wiener record streamed with paper B's
key-term RLS ends with the estimates of ``blockid fit`` with the same options and
``--passes 1`` to 1e-9. One run goes end to end through a real pipe (a subprocess fed on
standard input); the rest drive the command with typer's CliRunner.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from blockid.cli.fit import fit
from blockid.cli.streaming import stream
from blockid.models import ARX, load_model, save_model

from reference import (
    GLITCH_ROW,
    PLANT_221,
    arx_csv_text,
    csv_text,
    flat_parameters,
    key_term_hw_record,
    record_221,
)

runner = CliRunner()

# cli/main.py registers the commands; this test builds the same registration on its own
app = typer.Typer(add_completion=False, rich_markup_mode=None)
app.command("stream")(stream)
app.command("fit")(fit)


@app.callback()
def _root() -> None:
    """Test app."""


# the same app in a fresh interpreter, for the run through a real pipe
_APP = """
import typer
from blockid.cli.streaming import stream
app = typer.Typer(add_completion=False)
app.command("stream")(stream)
@app.callback()
def _root():
    "Test app."
app()
"""

HW = [
    "--structure",
    "hammerstein-wiener",
    "--method",
    "key-term-rls",
    "--na",
    "3",
    "--nb",
    "3",
    "--nk",
    "8",
]
HW += ["--forgetting", "0.999", "--passes", "1", "--no-normalize"]


def _lines(text: str) -> list[dict]:
    return [json.loads(line) for line in text.splitlines()]


# nk=0: a huge input fails the update of its own sample (phi^T P phi overflows), so the
# divergence tests see the sample refused, not an estimate ruined by an accepted one
ARX_ARGS = ["-u", "u", "-y", "y", "--na", "1", "--nb", "2", "--nk", "0"]


# ----------------------------------------------------------------------------- the claim
@pytest.mark.slow  # 50 000 samples through a real pipe; the shorter stream tests stay
def test_a_piped_hw_record_ends_with_the_one_pass_fit(tmp_path):
    """50 000 samples through a real pipe; final estimates = ``fit --passes 1`` (1e-9)."""
    csv = tmp_path / "hw.csv"
    csv.write_text(csv_text(*key_term_hw_record(50_000)))
    out = tmp_path / "online.json"
    with csv.open() as stdin:
        run = subprocess.run(
            [sys.executable, "-c", _APP, "stream", "-u", "u", "-y", "y", *HW, "-o", str(out)],
            stdin=stdin,
            capture_output=True,
            text=True,
            timeout=120,
        )
    assert run.returncode == 0, run.stderr
    lines = _lines(run.stdout)
    assert len(lines) == 50_001
    assert [line["k"] for line in lines[:-1]] == list(range(50_000))
    assert lines[0]["prediction"] == {"y": None}  # before the first update
    final = lines[-1]
    assert final["final"] is True and final["n_samples"] == 50_000

    r = runner.invoke(app, ["fit", str(csv), "-u", "u", "-y", "y", *HW, "--json"])
    assert r.exit_code == 0, r.output
    offline = json.loads(r.stdout)["model"]["parameters"]
    assert final["parameters"].keys() == offline.keys()
    np.testing.assert_allclose(
        flat_parameters(final["parameters"]), flat_parameters(offline), rtol=0, atol=1e-9
    )
    saved = load_model(out).to_dict()["parameters"]
    np.testing.assert_allclose(flat_parameters(saved), flat_parameters(offline), rtol=0, atol=1e-9)
    assert f"model written to {out}" in run.stderr


# ----------------------------------------------------------------------------- lines
def test_every_n_samples_the_parameters_named_as_in_model_files():
    r = runner.invoke(
        app, ["stream", *ARX_ARGS, "--method", "rls", "--every", "100"], input=arx_csv_text()
    )
    assert r.exit_code == 0, r.output
    lines = _lines(r.stdout)
    params = [line for line in lines if "parameters" in line and "final" not in line]
    assert [p["k"] for p in params] == [99, 199, 299]
    assert params[-1]["parameters"] == lines[-1]["parameters"]
    np.testing.assert_allclose(lines[-1]["parameters"]["y"]["a"]["y"], [-0.5], atol=1e-6)
    np.testing.assert_allclose(lines[-1]["parameters"]["y"]["b"]["u"], [0.0, 2.0], atol=1e-6)
    y5 = float(arx_csv_text().splitlines()[6].split(",")[1])  # row k=5 (after the header)
    assert lines[5]["error"]["y"] == y5 - lines[5]["prediction"]["y"]


def test_default_method_is_the_structures_recursive_one():
    r = runner.invoke(app, ["stream", *ARX_ARGS], input=arx_csv_text(50))
    assert r.exit_code == 0, r.output
    assert _lines(r.stdout)[-1]["n_samples"] == 50


@pytest.mark.parametrize("delimiter", [";", "\t"])
def test_a_semicolon_or_tab_stream_in_windows_1252_reads_as_fit_reads_its_file(delimiter):
    """A spreadsheet's export (``;`` or tabs, Latin-1 names): the same estimate as the
    comma-separated UTF-8 stream of the same numbers."""
    text = arx_csv_text(200)
    plain = runner.invoke(app, ["stream", *ARX_ARGS], input=text)
    body = text.replace("u", "débit_u").replace(",", delimiter)
    other = runner.invoke(
        app,
        ["stream", *[("débit_u" if a == "u" else a) for a in ARX_ARGS]],
        input=body.encode("cp1252"),
    )
    assert plain.exit_code == 0 and other.exit_code == 0, other.output
    a, b = _lines(plain.stdout)[-1]["parameters"], _lines(other.stdout)[-1]["parameters"]
    assert a["y"]["a"] == b["y"]["a"] and a["y"]["b"]["u"] == b["y"]["b"]["débit_u"]


def test_json_lines_input():
    rows = [line.split(",") for line in arx_csv_text(200).splitlines()[1:]]
    jsonl = "".join(
        json.dumps({"t": i, "u": float(u), "y": float(y)}) + "\n" for i, (u, y) in enumerate(rows)
    )
    r = runner.invoke(app, ["stream", *ARX_ARGS, "--format", "jsonl"], input=jsonl)
    assert r.exit_code == 0, r.output
    csv = runner.invoke(app, ["stream", *ARX_ARGS], input=arx_csv_text(200))
    assert r.stdout == csv.stdout


def _with_bad_rows() -> str:
    lines = arx_csv_text(100).splitlines()
    lines[11] = "x,1.0"  # row k=10: not a number
    lines[31] = "1e300,0.5"  # row k=30: the recursion diverges
    lines[41] = "1.0"  # row k=40: a field missing
    return "\n".join(lines) + "\n"


def test_bad_rows_and_divergence_are_lines_and_the_stream_goes_on():
    """Without the guard (which would reject row 30 before it diverges): a row that
    cannot be read is skipped, a diverging one is taken in without learning from it."""
    r = runner.invoke(app, ["stream", *ARX_ARGS, "--no-guard"], input=_with_bad_rows())
    assert r.exit_code == 0, r.output
    lines = _lines(r.stdout)
    errors = [line for line in lines if "error_message" in line]
    assert [(e["k"], e["line"]) for e in errors] == [(10, 12), (30, 32), (40, 42)]
    assert "'u' is 'x', not a number" in errors[0]["error_message"]
    assert "diverged" in errors[1]["error_message"]
    assert "last good estimate" in errors[1]["error_message"]
    assert "1 fields" in errors[2]["error_message"]
    assert lines[-1]["n_samples"] == 98  # the two unreadable rows are not taken in
    # still near the plant (a skipped row leaves a wrong lag in the next regressors)
    np.testing.assert_allclose(flat_parameters(lines[-1]["parameters"]), [-0.5, 0.0, 2.0], atol=0.1)
    assert "Traceback" not in r.output


def test_stop_on_error_ends_at_the_first_failure(tmp_path):
    out = tmp_path / "m.json"
    args = ["stream", *ARX_ARGS, "--stop-on-error", "-o", str(out)]
    r = runner.invoke(app, args, input=_with_bad_rows())
    assert r.exit_code == 1
    lines = _lines(r.stdout)
    assert lines[-2]["k"] == 10 and "error_message" in lines[-2]
    assert lines[-1] == {**lines[-1], "final": True, "n_samples": 10, "stopped": True}
    assert not out.exists()


def test_model_written_at_the_end_and_not_replaced_without_force(tmp_path):
    out = tmp_path / "m.json"
    r = runner.invoke(app, ["stream", *ARX_ARGS, "-o", str(out)], input=arx_csv_text())
    assert r.exit_code == 0, r.output
    doc = json.loads(out.read_text())
    assert doc["estimation"]["online"] is True and doc["estimation"]["n_samples"] == 300
    assert doc["model"]["parameters"] == _lines(r.stdout)[-1]["parameters"]
    again = runner.invoke(app, ["stream", *ARX_ARGS, "-o", str(out)], input=arx_csv_text())
    assert again.exit_code == 2 and "exists; pass --force" in again.stderr
    assert again.stdout == ""  # refused before reading a line
    forced = runner.invoke(
        app, ["stream", *ARX_ARGS, "-o", str(out), "--force"], input=arx_csv_text(80)
    )
    assert forced.exit_code == 0 and json.loads(out.read_text())["estimation"]["n_samples"] == 80


def test_start_model_sets_theta0(tmp_path):
    start = ARX(["u"], ["y"], na=1, nb=1, nk=1, a={"y": {"y": [-0.25]}}, b={"y": {"u": [1.5]}})
    # its orders apply where none are given
    path = save_model(start, tmp_path / "start.json")
    r = runner.invoke(app, ["stream", "-u", "u", "-y", "y", "--model", str(path)], input="u,y\n")
    assert r.exit_code == 0, r.output
    nothing = dict.fromkeys(
        ["rejected", "held", "diverged", "relented", "restarted", "outliers"], 0
    )
    assert _lines(r.stdout) == [
        {
            "final": True,
            "parameters": start.to_dict()["parameters"],
            "n_samples": 0,
            "guard": {"threshold": 10.0, **nothing},
        }
    ]


@pytest.mark.parametrize(
    ("args", "stdin", "message"),
    [
        (["--max-nfev", "3"], "u,y\n", "max_nfev not used by arx with method rls"),
        (["--method", "batch"], "u,y\n", "not recursive"),
        (["--structure", "output-error"], "u,y\n", "output-error has no recursive method"),
        (["--passes", "3"], "u,y\n", "(option --passes)"),
        (["--input-scale", "2"], "u,y\n", "give both input_scale and output_scale"),
        (["--format", "xml"], "u,y\n", "format 'xml' is unknown"),
        ([], "t,y\n1,2\n", "u missing"),
        ([], "", "the stream is empty"),
    ],
)
def test_usage_errors_are_one_line(args, stdin, message):
    r = runner.invoke(app, ["stream", "-u", "u", "-y", "y", *args], input=stdin)
    assert r.exit_code == 2, r.output
    assert r.stderr.startswith("error: ") and message in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


# ----------------------------------------------------------------------------- a live plant
# Issue 37: one glitch of a live plant stopped the stream for good (every later row an
# error line, exit 0) or ruined the model; a constant input or one row wrote a model.
ARGS_221 = ["-u", "u", "-y", "y", "--na", "2", "--nb", "2", "--nk", "1"]


def _learned_rows(lines: list[dict]) -> list[int]:
    """Rows the estimator learned from: sample lines without "not_learned"."""
    return [line["k"] for line in lines if "prediction" in line and "not_learned" not in line]


@pytest.mark.parametrize(
    ("signal", "value"), [("y", 1e8), ("u", 1e12), ("u", 1e300)], ids=["y1e8", "u1e12", "u1e300"]
)
def test_one_glitch_of_a_live_plant_leaves_the_estimate_of_the_clean_record(
    tmp_path, signal, value
):
    """Learning resumes within 50 rows of the glitch and learns from every row after
    it; the model written is within 5 % of the glitch-free run's, parameter by
    parameter. (Before: y 1e8 ruined the model, b = [-5.6e5, 1.6e5]; an input glitch
    made every later row an error line and the model stopped at row 70.)"""
    u, y = record_221()
    clean = runner.invoke(app, ["stream", *ARGS_221, "-o", str(tmp_path / "clean.json")],
                          input=csv_text(u, y))  # fmt: skip
    assert clean.exit_code == 0, clean.output
    (u if signal == "u" else y)[GLITCH_ROW, 0] = value
    out = tmp_path / "glitch.json"
    r = runner.invoke(app, ["stream", *ARGS_221, "-o", str(out)], input=csv_text(u, y))
    assert r.exit_code == 0, r.output
    lines = _lines(r.stdout)
    after = [k for k in _learned_rows(lines) if k > GLITCH_ROW]
    assert after[0] <= GLITCH_ROW + 50
    assert after == list(range(after[0], 400))  # learning goes on, every row
    glitch, truth = (
        flat_parameters(load_model(p).to_dict()["parameters"])
        for p in (out, tmp_path / "clean.json")
    )
    np.testing.assert_allclose(glitch, truth, rtol=0.05)
    assert lines[-1]["guard"]["rejected"] >= 1


def test_a_stream_that_never_recovers_exits_non_zero_and_writes_no_model(tmp_path):
    """From row 200 on the input is 1e300: the guard rejects it, steps aside after a
    while (a change that lasts), the recursion diverges at every row learned. The
    estimate never recovers: exit status 2, no model file, one line saying why.
    (Before: exit 0 and the model of row 200, though 200 rows were never learned.)"""
    u, y = record_221()
    u[200:, 0] = 1e300
    out = tmp_path / "m.json"
    r = runner.invoke(app, ["stream", *ARGS_221, "-o", str(out)], input=csv_text(u, y))
    assert r.exit_code == 2, r.output
    assert not out.exists()
    error = [line for line in r.stderr.splitlines() if line.startswith("error:")]
    assert len(error) == 1 and "diverged at row" in error[0] and "did not recover" in error[0]
    assert f"no model written to {out}" in error[0]
    assert "problem" in _lines(r.stdout)[-1]


@pytest.mark.parametrize(
    ("rows", "message"),
    [
        (slice(None), "input 'u' is constant over the stream (1 at every sample"),
        (slice(0, 1), "looks back 2 samples, so it needs more than 2 samples"),
    ],
    ids=["constant-input", "one-row"],
)
def test_a_never_excited_stream_exits_non_zero_and_keeps_the_users_file(tmp_path, rows, message):
    """A constant input, or one row, as ``fit`` refuses them (its message): exit status
    2 with one line, with or without -o, and a file given with --force is left as it
    was. (Before: exit 0, a model of zeros or of a rank-deficient regression written.)"""
    u, y = record_221()
    if rows == slice(None):
        u[:] = 1.0
        y = PLANT_221.simulate(u)
    text = csv_text(u[rows], y[rows])
    out = tmp_path / "m.json"
    out.write_text("the user's file")
    r = runner.invoke(app, ["stream", *ARGS_221, "-o", str(out), "--force"], input=text)
    assert r.exit_code == 2, r.output
    assert out.read_text() == "the user's file"
    assert r.stderr.count("error: ") == 1 and message in r.stderr
    assert f"no model written to {out}" in r.stderr
    bare = runner.invoke(app, ["stream", *ARGS_221], input=text)
    assert bare.exit_code == 2 and message in bare.stderr


# ----------------------------------------------------------------------------- checkpoints
def _model_text(path) -> str:
    doc = json.loads(path.read_text())
    return json.dumps(doc["model"]), json.dumps(doc["estimation"]["learner"]["state"])


@pytest.mark.parametrize(
    "args",
    [["--na", "3", "--nb", "3", "--nk", "2", "--method", "rls", "--forgetting", "0.99"], HW],
    ids=["arx", "hammerstein-wiener"],
)
def test_a_checkpoint_resumes_exactly_where_the_stream_stopped(tmp_path, args):
    """Issue 21: stop after 700 samples, resume from the file with the rest: the same
    model and learner state, bit for bit, as one uninterrupted stream; a checkpoint is
    written every N samples on the way."""
    u, y = key_term_hw_record(1500, seed=3)
    text = csv_text(u, y).splitlines()
    head, first, rest = text[0], text[1:701], text[701:]
    whole, part, resumed = (tmp_path / n for n in ("whole.json", "part.json", "resumed.json"))
    base = ["stream", "-u", "u", "-y", "y", *args]
    r = runner.invoke(app, [*base, "-o", str(whole)], input="\n".join([head, *first, *rest]))
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, [*base, "--checkpoint", "250", "-o", str(part)],
                      input="\n".join([head, *first[:600]]))  # fmt: skip
    assert r.exit_code == 0, r.output
    learner = json.loads(part.read_text())["estimation"]["learner"]
    assert learner["rows"] == 600 and learner["state"]["n_samples"] == 600
    # resumed from a checkpoint written mid-stream (after 500 samples): the file as
    # it was then, with the 200 samples after it fed again
    r = runner.invoke(app, [*base, "--checkpoint", "500", "-o", str(part), "--force"],
                      input="\n".join([head, *first[:650]]))  # fmt: skip
    doc = json.loads(part.read_text())
    mid = tmp_path / "mid.json"
    assert doc["estimation"]["learner"]["rows"] == 650  # the end of input writes it too
    r = runner.invoke(app, [*base, "--checkpoint", "500", "-o", str(mid)],
                      input="\n".join([head, *first[:500]]))  # fmt: skip
    assert json.loads(mid.read_text())["estimation"]["learner"]["rows"] == 500
    r = runner.invoke(app, ["stream", "-u", "u", "-y", "y", "--model", str(mid), "-o",
                            str(resumed)], input="\n".join([head, *first[500:], *rest]))  # fmt: skip
    assert r.exit_code == 0, r.output
    assert _lines(r.stdout)[0]["k"] == 500  # rows numbered on
    assert _model_text(resumed) == _model_text(whole)
    # options that differ from the checkpoint's are refused, naming them
    r = runner.invoke(app, ["stream", "-u", "u", "-y", "y", "--model", str(mid), "--nb", "1"],
                      input=head)  # fmt: skip
    assert r.exit_code == 2 and "resume it with the same options" in r.stderr


def test_a_reader_that_closes_stdout_does_not_lose_the_learned_model(tmp_path):
    """The plant's reader goes away (stdout closed): the stream stops as on SIGPIPE,
    writes the model and the learner state, says where to resume, exits 128 + 13."""
    import signal

    u, y = key_term_hw_record(800, seed=4)
    text = csv_text(u, y).splitlines()
    out = tmp_path / "piped.json"
    arx = ["-u", "u", "-y", "y", "--na", "3", "--nb", "3", "--nk", "2", "--method", "rls"]
    proc = subprocess.Popen([sys.executable, "-c", _APP, "stream", *arx, "-o", str(out)],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)  # fmt: skip
    proc.stdin.write("\n".join(text[:201]) + "\n")
    proc.stdin.flush()
    for _ in range(200):
        assert proc.stdout.readline()
    proc.stdout.close()  # the reader goes away
    try:
        proc.stdin.write("\n".join(text[201:]) + "\n")
        proc.stdin.close()
    except BrokenPipeError:  # the stream stopped before it read them all
        pass
    err = proc.stderr.read()
    assert proc.wait(timeout=60) == 128 + signal.SIGPIPE, err
    assert "stopped by SIGPIPE" in err and f"--model {out}" in err
    assert json.loads(out.read_text())["estimation"]["learner"]["state"]["n_samples"] >= 200


def test_sigterm_writes_the_model_and_the_learner_state(tmp_path):
    """Issue 21: SIGTERM (or Ctrl-C) on ``stream -o FILE`` threw the learned model away;
    now it is written, and resuming from it ends where one uninterrupted stream ends."""
    import signal
    import time

    u, y = key_term_hw_record(800, seed=4)
    text = csv_text(u, y).splitlines()
    head, rows = text[0], text[1:]
    out, whole = tmp_path / "stopped.json", tmp_path / "whole.json"
    arx = ["-u", "u", "-y", "y", "--na", "3", "--nb", "3", "--nk", "2", "--method", "rls"]
    proc = subprocess.Popen([sys.executable, "-c", _APP, "stream", *arx, "-o", str(out)],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)  # fmt: skip
    proc.stdin.write("\n".join([head, *rows[:300]]) + "\n")
    proc.stdin.flush()
    seen = 0
    deadline = time.monotonic() + 60
    while seen < 300 and time.monotonic() < deadline:
        if proc.stdout.readline():
            seen += 1
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + signal.SIGTERM, err
    assert "stopped by SIGTERM" in err and f"--model {out}" in err
    assert "the data rows from row 300 on" in err  # where the resumed stream starts
    assert json.loads(out.read_text())["estimation"]["learner"]["state"]["n_samples"] == 300
    r = runner.invoke(app, ["stream", *arx, "-o", str(whole)], input="\n".join([head, *rows]))
    assert r.exit_code == 0
    resumed = tmp_path / "resumed.json"
    r = runner.invoke(app, ["stream", "-u", "u", "-y", "y", "--model", str(out), "-o",
                            str(resumed)], input="\n".join([head, *rows[300:]]))  # fmt: skip
    assert r.exit_code == 0, r.output
    assert _model_text(resumed) == _model_text(whole)


def test_a_block_model_of_two_inputs_and_outputs_streams_to_the_learners_model(tmp_path):
    """``--structure block-state-space --method rls``: the model written at the end is
    the online learner's of the same samples, its cubic blocks those of the plant."""
    from blockid.fitting.online import online_estimator

    rng = np.random.default_rng(7)
    u = rng.uniform(-1.5, 1.5, (800, 2))
    w = np.column_stack([u[:, 0] + 0.3 * u[:, 0] ** 2, u[:, 1] - 0.4 * u[:, 1] ** 3])
    y = np.zeros((800, 2))
    for t in range(1, 800):
        y[t] = [
            0.5 * y[t - 1, 0] + w[t - 1, 0] + 0.2 * w[t - 1, 1],
            0.3 * y[t - 1, 1] + w[t - 1, 1],
        ]
    text = "u1,u2,y1,y2\n" + "\n".join(",".join(map(repr, row)) for row in np.c_[u, y].tolist())
    out = tmp_path / "live.json"
    args = ["stream", "-u", "u1", "-u", "u2", "-y", "y1", "-y", "y2", "--structure",
            "block-state-space", "--method", "rls", "--na", "1", "--nb", "1", "--nk", "1",
            "-o", str(out)]  # fmt: skip
    r = runner.invoke(app, args, input=text + "\n")
    assert r.exit_code == 0, r.output
    online = online_estimator("block-state-space", "rls", {"na": 1, "nb": 1, "nk": 1},
                              ["u1", "u2"], ["y1", "y2"])  # fmt: skip
    online.partial_fit(u, y)
    saved = load_model(out)
    assert saved.to_dict() == online.model().to_dict()
    np.testing.assert_allclose(saved.input_blocks[0].coefficients, [0, 1, 0.3, 0], atol=1e-6)
    np.testing.assert_allclose(saved.input_blocks[1].coefficients, [0, 1, 0, -0.4], atol=1e-6)
    assert _lines(r.stdout)[-1]["parameters"]["nx"] == 2 + 2  # y(t-1) and w(t-1)


def test_a_stream_that_learned_nothing_writes_no_model(tmp_path):
    """Every row refused (here: a column of text): the end writes no model of zeros."""
    out = tmp_path / "m.json"
    r = runner.invoke(app, ["stream", *ARX_ARGS, "-o", str(out)], input="u,y\nx,1\ny,2\n")
    assert r.exit_code == 2 and "no sample was learned" in r.stderr
    assert not out.exists()
