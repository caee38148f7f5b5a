"""The commands added after the malformed-input suite, attacked as a careless or hostile
user would (issue 37, items 5 and 6): ``bla``, ``design``, ``residuals``, ``predict
--horizon`` and the report's BLA section.

Each case runs one command line in a fresh folder holding a noise record (good.csv), a
periodic record (per.csv: an odd multisine of 2 realisations x 3 periods of 64 samples
through a low-pass and a cubic), an ARX model without a sampling time (model.json) and
the same model at 0.05 s (model_ts.json). Refused cases: exit status 2, one line on
stderr that holds the expected words (the problem and the flag), no traceback, every
file that existed unchanged. Legitimate edge cases: exit status 0, no traceback, no
NaN or infinity printed, every file that existed unchanged unless ``--force`` names it.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from blockid.cli.main import app
from blockid.models import ARX, save_model

runner = CliRunner()

N = 300
PER = ["per.csv", "-u", "u", "-y", "y", "--time-column", "t", "--experiment-column", "realisation"]
GOOD = ["good.csv", "-u", "u", "-y", "y"]


def _rows(u: np.ndarray, y: np.ndarray, dt: float = 0.05) -> str:
    return "".join(f"{k * dt:.2f},{float(u[k])!r},{float(y[k])!r}\n" for k in range(u.size))


def _write(name: str, text: str) -> Callable[[Path], None]:
    def make(d: Path) -> None:
        (d / name).write_text(text)

    return make


def _table(name: str, u: Callable[[int], float], y: Callable[[int], float], n: int = 100):
    """``name`` with columns t, u, y of ``n`` rows from the two functions of the row."""
    k = np.arange(n)
    return _write(name, "t,u,y\n" + _rows(np.array([u(i) for i in k]), np.array([y(i) for i in k])))


def _files(*names: str) -> Callable[[Path], None]:
    """Files and folders of an earlier run: ``old.json``, ``afile``, ``figs/bla.png``..."""

    def make(d: Path) -> None:
        for name in names:
            path = d / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(b"earlier")

    return make


@dataclass
class Case:
    id: str
    args: list[str]
    expect: list[str]
    make: Callable[[Path], None] | None = None


SINE = _table("bad.csv", np.sin, np.cos)
ONE_STEP_TS = ["residuals", "model_ts.json", "bad.csv", "--ts", "0.1"]

REFUSED = [
    # ------------------------------------------------------------------ bla: data
    Case(
        "bla empty file",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["bad.csv is empty"],
        _write("bad.csv", ""),
    ),  # fmt: skip
    Case(
        "bla header only",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["no data rows"],
        _write("bad.csv", "t,u,y\n"),
    ),  # fmt: skip
    Case(
        "bla constant input",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["input", "constant"],
        _table("bad.csv", lambda k: 1.0, np.sin),
    ),  # fmt: skip
    Case(
        "bla zero input and output",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["constant"],
        _table("bad.csv", lambda k: 0.0, lambda k: 0.0),
    ),  # fmt: skip
    Case(
        "bla nan cell",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["column 'u'", "line 7"],
        _table("bad.csv", lambda k: np.nan if k == 5 else np.sin(k), np.cos),
    ),  # fmt: skip
    Case(
        "bla inf cell",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["column 'u'", "infinite"],
        _table("bad.csv", lambda k: np.inf if k == 5 else np.sin(k), np.cos),
    ),  # fmt: skip
    Case(
        "bla text column",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["'x0' is not a number"],
        _write("bad.csv", "t,u,y\n" + "".join(f"{k},x{k},{k}\n" for k in range(50))),
    ),  # fmt: skip
    Case("bla column missing", ["bla", "per.csv", "-u", "U", "-y", "y"], ["no column 'U'"]),
    Case("bla two inputs", ["bla", *PER, "-u", "t"], ["one input to one output"]),
    Case(
        "bla experiment column is the input",
        ["bla", "per.csv", "-u", "u", "-y", "y", "--experiment-column", "u"],
        ["experiment_column 'u'"],
    ),  # fmt: skip
    Case("bla range past the end", ["bla", *PER, "--range", "500:"], ["--range 500:"]),
    Case("bla ts zero", ["bla", *PER, "--ts", "0"], ["--ts"]),
    # ------------------------------------------------------------------ bla: periods
    Case("bla period zero", ["bla", *GOOD, "--period", "0"], ["period", "--period"]),
    Case("bla period negative", ["bla", *GOOD, "--period", "-5"], ["period", "--period"]),
    Case(
        "bla period of two samples",
        ["bla", *GOOD, "--period", "2"],
        ["period of 2 samples", "--period"],
    ),  # fmt: skip
    Case(
        "bla one sample a period",
        ["bla", *GOOD, "--periods", "300"],
        ["period of 1 samples", "--periods"],
    ),  # fmt: skip
    Case(
        "bla period longer than the record",
        ["bla", *GOOD, "--period", "301"],
        ["300 samples", "--period"],
    ),  # fmt: skip
    Case("bla period huge", ["bla", *GOOD, "--period", "99999999999999999"], ["--period"]),
    Case("bla periods zero", ["bla", *GOOD, "--periods", "0"], ["--periods"]),
    Case(
        "bla periods do not divide",
        ["bla", *GOOD, "--periods", "7"],
        ["not a whole number of 7 periods", "--period"],
    ),  # fmt: skip
    Case(
        "bla period and periods disagree",
        ["bla", *GOOD, "--period", "100", "--periods", "2"],
        ["make 200 samples", "--periods"],
    ),  # fmt: skip
    Case("bla one period one realisation", ["bla", *GOOD, "--period", "300"], ["no variance"]),
    Case(
        "bla every period transient",
        ["bla", *PER, "--transient-periods", "3"],
        ["drop every period", "--transient-periods"],
    ),  # fmt: skip
    Case(
        "bla transient periods negative",
        ["bla", *PER, "--transient-periods", "-1"],
        ["--transient-periods"],
    ),  # fmt: skip
    Case(
        "bla found period does not divide",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["repeats every 6 samples", "welch", "--method"],
        _table("bad.csv", np.sin, lambda k: 3.0, n=200),
    ),  # fmt: skip
    Case(
        "bla no period for robust",
        ["bla", *GOOD, "--method", "robust"],
        ["no period found", "--period"],
    ),  # fmt: skip
    Case(
        "bla welch with a period",
        ["bla", *PER, "--method", "welch", "--period", "64"],
        ["--period", "robust"],
    ),  # fmt: skip
    Case("bla method unknown", ["bla", *GOOD, "--method", "Welch"], ["--method 'Welch'"]),
    # ------------------------------------------------------------------ bla: options
    Case("bla bands zero", ["bla", *PER, "--bands", "0"], ["bands must be >= 1", "--bands"]),
    Case("bla bands text", ["bla", *PER, "--bands", "abc"], ["LOW:HIGH", "--bands"]),
    Case("bla bands reversed", ["bla", *PER, "--bands", "5:3"], ["0 <= LOW < HIGH"]),
    Case("bla bands above nyquist", ["bla", *PER, "--bands", "60:80"], ["holds no line"]),
    Case("bla bands nan", ["bla", *PER, "--bands", "nan:5"], ["--bands"]),
    Case(
        "bla bands overlap", ["bla", *PER, "--bands", "1:30,20:40"], ["overlap", "--bands"]
    ),  # fmt: skip
    Case("bla bands semicolons", ["bla", *PER, "--bands", "10:20;30:40"], ["--bands"]),
    Case("bla confidence zero", ["bla", *PER, "--confidence", "0"], ["--confidence"]),
    Case("bla confidence one", ["bla", *PER, "--confidence", "1"], ["--confidence"]),
    Case("bla confidence two", ["bla", *PER, "--confidence", "2"], ["--confidence"]),
    Case("bla confidence nan", ["bla", *PER, "--confidence", "nan"], ["--confidence"]),
    Case("bla segment too small", ["bla", *GOOD, "--segment", "4"], [">= 8", "--segment"]),
    Case(
        "bla segment longer than the record",
        ["bla", *GOOD, "--segment", "301"],
        ["at most 300", "--segment"],
    ),  # fmt: skip
    Case("bla segment the whole record", ["bla", *GOOD, "--segment", "300"], ["--segment"]),
    Case(
        "bla one row",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["more data"],
        _write("bad.csv", "t,u,y\n0,1,2\n"),
    ),  # fmt: skip
    Case("bla fit one number", ["bla", *PER, "--fit", "2"], ["NA,NB", "--fit"]),
    Case("bla fit negative", ["bla", *PER, "--fit", "-1,2"], ["--fit"]),
    Case("bla fit no numerator", ["bla", *PER, "--fit", "0,0"], ["NB must be 1"]),
    Case(
        "bla fit orders above the lines",
        ["bla", *PER, "--fit", "50,50"],
        ["too few for 50 + 50", "--fit"],
    ),  # fmt: skip
    Case("bla fit huge order", ["bla", *PER, "--fit", "99999999999,1"], ["--fit"]),
    # ------------------------------------------------------------------ bla: outputs
    Case(
        "bla output exists",
        ["bla", *PER, "-o", "old.json"],
        ["old.json exists", "--force"],
        _files("old.json"),
    ),  # fmt: skip
    Case(
        "bla output folder missing",
        ["bla", *PER, "-o", "missing/out.json"],
        ["folder missing does not exist"],
    ),  # fmt: skip
    Case(
        "bla output under a file",
        ["bla", *PER, "-o", "afile/out.json"],
        ["afile is a file"],
        _files("afile"),
    ),  # fmt: skip
    Case("bla output named csv", ["bla", *PER, "-o", "out.csv"], ["JSON", "out.json"]),
    Case("bla output over the data", ["bla", *PER, "-o", "per.csv", "--force"], ["JSON"]),
    Case(
        "bla figure exists",
        ["bla", *PER, "--plot", "figs"],
        ["figs/bla.png", "--force"],
        _files("figs/bla.png"),
    ),  # fmt: skip
    Case(
        "bla figure folder is a file",
        ["bla", *PER, "--plot", "afile"],
        ["afile is a file"],
        _files("afile"),
    ),  # fmt: skip
    # ------------------------------------------------------------------ design
    Case("design kind unknown", ["design", "sine"], ["unknown excitation 'sine'"]),
    Case("design samples missing", ["design", "multisine"], ["needs samples", "--samples"]),
    Case("design samples one", ["design", "multisine", "--samples", "1"], ["--samples"]),
    Case("design samples two", ["design", "multisine", "--samples", "2"], ["no line"]),
    Case(
        "design samples huge", ["design", "multisine", "--samples", "99999999999"], ["--samples"]
    ),  # fmt: skip
    Case(
        "design periods huge",
        ["design", "multisine", "--samples", "64", "--periods", "100000000"],
        ["--periods"],
    ),  # fmt: skip
    Case(
        "design realisations huge",
        ["design", "multisine", "--samples", "64", "--realisations", "100000000"],
        ["--realisations"],
    ),  # fmt: skip
    Case(
        "design prbs longest and slowest",
        ["design", "prbs", "--order", "24", "--clock", "1000", "--periods", "1000"],
        ["samples"],
    ),  # fmt: skip
    Case(
        "design f-max above nyquist",
        ["design", "multisine", "--samples", "64", "--f-max", "0.6"],
        ["Nyquist", "--f-max"],
    ),  # fmt: skip
    Case(
        "design f-max zero",
        ["design", "multisine", "--samples", "64", "--f-max", "0"],
        ["no line", "--f-max"],
    ),  # fmt: skip
    Case(
        "design band between lines",
        ["design", "multisine", "--samples", "64", "--f-min", "0.301", "--f-max", "0.31"],
        ["no line"],
    ),  # fmt: skip
    Case(
        "design f-min above f-max",
        ["design", "multisine", "--samples", "64", "--f-min", "0.4", "--f-max", "0.3"],
        ["f_min", "--f-min"],
    ),  # fmt: skip
    Case(
        "design f-max nan",
        ["design", "multisine", "--samples", "64", "--f-max", "nan"],
        ["--f-max"],
    ),  # fmt: skip
    Case("design fs zero", ["design", "multisine", "--samples", "64", "--fs", "0"], ["--fs"]),
    Case(
        "design fs and ts disagree",
        ["design", "multisine", "--samples", "64", "--fs", "10", "--ts", "0.2"],
        ["disagree"],
    ),  # fmt: skip
    Case(
        "design rms zero", ["design", "multisine", "--samples", "64", "--rms", "0"], ["--rms"]
    ),  # fmt: skip
    Case(
        "design rms overflows",
        ["design", "multisine", "--samples", "64", "--rms", "1e308"],
        ["--rms"],
    ),  # fmt: skip
    Case(
        "design rms underflows",
        ["design", "multisine", "--samples", "64", "--rms", "1e-320"],
        ["--rms"],
    ),  # fmt: skip
    Case(
        "design crest iterations negative",
        ["design", "multisine", "--samples", "64", "--crest-iterations", "-1"],
        ["--crest-iterations"],
    ),  # fmt: skip
    Case(
        "design crest iterations endless",
        ["design", "multisine", "--samples", "64", "--crest-iterations", "100000000"],
        ["--crest-iterations"],
    ),  # fmt: skip
    Case(
        "design group one",
        ["design", "odd-multisine", "--samples", "64", "--group", "1"],
        ["--group"],
    ),  # fmt: skip
    Case("design prbs order 25", ["design", "prbs", "--order", "25"], ["2..24", "--order"]),
    Case(
        "design prbs levels equal",
        ["design", "prbs", "--order", "5", "--levels", "1,1"],
        ["LOW < HIGH", "--levels"],
    ),  # fmt: skip
    Case(
        "design prbs levels overflow",
        ["design", "prbs", "--order", "5", "--levels", "-1e200,1e300"],
        ["--levels"],
    ),  # fmt: skip
    Case(
        "design prbs realisations",
        ["design", "prbs", "--order", "5", "--realisations", "2"],
        ["prbs takes no realisations"],
    ),  # fmt: skip
    Case(
        "design random-binary clock does not divide",
        ["design", "random-binary", "--samples", "64", "--clock", "100"],
        ["whole number of bits"],
    ),  # fmt: skip
    Case(
        "design seed negative",
        ["design", "multisine", "--samples", "64", "--seed", "-1"],
        ["--seed"],
    ),  # fmt: skip
    Case(
        "design name empty", ["design", "multisine", "--samples", "64", "--name", ""], ["--name"]
    ),  # fmt: skip
    Case(
        "design name clashes", ["design", "multisine", "--samples", "64", "--name", "t"], ["clash"]
    ),  # fmt: skip
    Case(
        "design output exists",
        ["design", "multisine", "--samples", "64", "-o", "old.csv"],
        ["old.csv exists"],
        _files("old.csv"),
    ),  # fmt: skip
    Case(
        "design output folder missing",
        ["design", "multisine", "--samples", "64", "-o", "missing/x.csv"],
        ["does not exist"],
    ),  # fmt: skip
    # ------------------------------------------------------------------ residuals
    Case(
        "residuals other columns",
        ["residuals", "model.json", "bad.csv"],
        ["no column 'u'"],
        _write("bad.csv", "t,a,b\n0,1,2\n0.05,1,2\n"),
    ),  # fmt: skip
    Case(
        "residuals one row",
        ["residuals", "model.json", "bad.csv"],
        ["only 1"],
        _write("bad.csv", "t,u,y\n0,1,2\n"),
    ),  # fmt: skip
    Case(
        "residuals too short for the lags",
        ["residuals", "model.json", "good.csv", "--range", "0:30"],
        ["too few", "--lags"],
    ),  # fmt: skip
    Case(
        "residuals lags zero", ["residuals", "model.json", "good.csv", "--lags", "0"], ["--lags"]
    ),  # fmt: skip
    Case(
        "residuals lags above the record",
        ["residuals", "model.json", "good.csv", "--lags", "100000"],
        ["--lags"],
    ),  # fmt: skip
    Case(
        "residuals constant input",
        ["residuals", "model.json", "bad.csv"],
        ["constant"],
        _table("bad.csv", lambda k: 1.0, np.sin),
    ),  # fmt: skip
    Case(
        "residuals confidence one",
        ["residuals", "model.json", "good.csv", "--confidence", "1"],
        ["--confidence"],
    ),  # fmt: skip
    Case(
        "residuals mode unknown",
        ["residuals", "model.json", "good.csv", "--mode", "free"],
        ["--mode 'free'"],
    ),  # fmt: skip
    Case(
        "residuals other sampling time",
        ONE_STEP_TS,
        ["0.05", "--ts"],
        _write("bad.csv", "u,y\n" + "".join(f"{np.sin(k)!r},{np.cos(k)!r}\n" for k in range(100))),
    ),  # fmt: skip
    Case(
        "simulate other sampling time",
        ["simulate", "model_ts.json", "bad.csv", "--ts", "0.1"],
        ["0.05", "--ts"],
        _write("bad.csv", "u,y\n1,2\n2,3\n1,1\n3,1\n"),
    ),  # fmt: skip
    Case(
        "predict horizon other sampling time",
        ["predict", "model_ts.json", "bad.csv", "--ts", "0.1", "--horizon", "2"],
        ["0.05", "--ts"],
        _write("bad.csv", "u,y\n1,2\n2,3\n1,1\n3,1\n"),
    ),  # fmt: skip
    Case(
        "residuals time column of another step",
        ["residuals", "model_ts.json", "bad.csv", "--time-column", "t"],
        ["0.05", "0.1"],
        lambda d: (d / "bad.csv").write_text(
            "t,u,y\n" + _rows(np.sin(np.arange(100.0)), np.cos(np.arange(100.0)), dt=0.1)
        ),
    ),  # fmt: skip
    Case("residuals model is a table", ["residuals", "good.csv", "good.csv"], ["not valid JSON"]),
    Case("residuals model missing", ["residuals", "nope.json", "good.csv"], ["does not exist"]),
    Case(
        "residuals figure exists",
        ["residuals", "model.json", "good.csv", "--plot", "figs"],
        ["figs/residuals.png"],
        _files("figs/residuals.png"),
    ),  # fmt: skip
    # ------------------------------------------------------------------ predict --horizon
    Case(
        "predict horizon zero",
        ["predict", "model.json", "good.csv", "--horizon", "0"],
        ["--horizon"],
    ),  # fmt: skip
    Case(
        "predict horizon negative",
        ["predict", "model.json", "good.csv", "--horizon", "-1"],
        ["--horizon"],
    ),  # fmt: skip
    Case(
        "predict horizon text",
        ["predict", "model.json", "good.csv", "--horizon", "1.5"],
        ["--horizon"],
    ),  # fmt: skip
    Case(
        "predict horizon output exists",
        ["predict", "model.json", "good.csv", "--horizon", "5", "-o", "old.csv"],
        ["old.csv exists"],
        _files("old.csv"),
    ),  # fmt: skip
    Case(
        "predict horizon figure exists",
        ["predict", "model.json", "good.csv", "--horizon", "5", "--plot", "figs"],
        ["figs/prediction.png"],
        _files("figs/prediction.png"),
    ),  # fmt: skip
]


@dataclass
class Legit:
    id: str
    args: list[str]
    #: Words that must be in the standard output (or in the file named ``-o``).
    expect: list[str]
    make: Callable[[Path], None] | None = None
    #: Words that must be on standard error (a warning); none expected otherwise.
    warns: list[str] | None = None


REPORT = ["report", "bad.csv", "-u", "u", "-y", "y", "--estimation", "0:40", "--validation",
          "40:60", "--structures", "arx", "--na", "1", "--nb", "1", "--nk", "1", "-o", "r.html"]  # fmt: skip

ACCEPTED = [
    Legit("bla bands partly above nyquist", ["bla", *PER, "--bands", "1:100"], ["1 - 100"]),
    Legit("bla bands sharing an edge", ["bla", *PER, "--bands", "1:20,20:48"], ["20 - 48"]),
    Legit("bla more bands than lines", ["bla", *PER, "--bands", "1000"], ["lines"]),
    Legit("bla confidence tiny", ["bla", *PER, "--confidence", "1e-300"], ["distortion"]),
    Legit("bla fit delay beyond the period", ["bla", *PER, "--fit", "1,1,100"], ["z^-100"]),
    Legit("bla fit no poles", ["bla", *PER, "--fit", "0,1"], ["b_0"]),
    Legit(
        "bla output replaced with force",
        ["bla", *PER, "-o", "old.json", "--force"],
        ["results written to old.json"],
        _files("old.json"),
    ),  # fmt: skip
    Legit("bla figure in new folders", ["bla", *PER, "--plot", "a/b"], ["a/b/bla.png"]),
    Legit("design three samples", ["design", "multisine", "--samples", "3"], ["lines (1"]),
    Legit(
        "design crest iterations at the limit",
        ["design", "multisine", "--samples", "16", "--crest-iterations", "10000"],
        ["crest factor"],
    ),  # fmt: skip
    Legit(
        "design rms large", ["design", "multisine", "--samples", "64", "--rms", "1e100"], ["1e+100"]
    ),  # fmt: skip
    Legit(
        "design f-max at nyquist",
        ["design", "multisine", "--samples", "64", "--f-max", "0.5"],
        ["every line"],
    ),  # fmt: skip
    Legit(
        "predict horizon longer than the record",
        ["predict", "model.json", "good.csv", "--horizon", "100000"],
        ["100000"],
    ),  # fmt: skip
    Legit(
        "predict horizon on three rows",
        ["predict", "model.json", "bad.csv", "--horizon", "5"],
        ["arx"],
        _write("bad.csv", "t,u,y\n0,1,2\n0.05,2,3\n0.1,1,1\n"),
        warns=["fit_percent of output 'y' is undefined"],
    ),  # fmt: skip
    Legit(
        "residuals constant output",
        ["residuals", "model.json", "bad.csv"],
        ["verdict"],
        _table("bad.csv", np.sin, lambda k: 2.0),
    ),  # fmt: skip
    Legit(
        "report square wave input",
        REPORT,
        ["Best linear approximation"],
        _table("bad.csv", lambda k: 1.0 if k % 2 else -1.0, np.cos, n=60),
    ),  # fmt: skip
    Legit(
        "report period of four samples",
        REPORT,
        ["Best linear approximation"],
        _table("bad.csv", lambda k: [1, -1, 2, 0.5][k % 4], np.cos, n=60),
    ),  # fmt: skip
]


@pytest.fixture
def folder(tmp_path, monkeypatch):
    rng = np.random.default_rng(0)
    u = rng.standard_normal(N)
    plant = ARX(["u"], ["y"], 2, 2, 1, a={"y": {"y": [-1.2, 0.35]}}, b={"y": {"u": [1.0, 0.4]}})
    y = plant.simulate(u)[:, 0] + 0.01 * rng.standard_normal(N)
    (tmp_path / "good.csv").write_text("t,u,y\n" + _rows(u, y))
    save_model(plant, tmp_path / "model.json")
    plant.sampling_time = 0.05
    save_model(plant, tmp_path / "model_ts.json")
    from scipy import signal

    from blockid.design import multisine

    x = multisine(64, sampling_time=0.01, f_max=30.0, odd=True, periods=3, realisations=2,
                  seed=5)  # fmt: skip
    frame = x.to_frame("u")
    b, a = signal.butter(2, 0.4)
    out = [signal.lfilter(b, a, r["u"].to_numpy()) for _, r in frame.groupby("realisation")]
    v = np.concatenate(out)
    frame["y"] = v + 0.3 * v**3 + 0.005 * rng.standard_normal(v.size)
    frame.to_csv(tmp_path / "per.csv", index=False)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _snapshot(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in root.rglob("*") if p.is_file()}


def test_cases_are_many_and_named_once():
    ids = [c.id for c in REFUSED + ACCEPTED]
    assert len(ids) == len(set(ids))
    assert {c.args[0] for c in REFUSED} >= {"bla", "design", "residuals", "predict"}


@pytest.mark.parametrize("case", [pytest.param(c, id=c.id) for c in REFUSED])
def test_refused(case, folder):
    if case.make is not None:
        case.make(folder)
    before = _snapshot(folder)
    r = runner.invoke(app, case.args)
    err = r.stderr
    assert r.exit_code == 2, f"exit {r.exit_code}; stderr: {err}; exception: {r.exception!r}"
    assert "Traceback" not in err and "Traceback" not in r.stdout
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    for words in case.expect:
        assert words.lower() in err.lower(), f"{words!r} not in {err!r}"
    assert _snapshot(folder) == before, "a file was written or changed"


@pytest.mark.parametrize("case", [pytest.param(c, id=c.id) for c in ACCEPTED])
def test_accepted(case, folder):
    if case.make is not None:
        case.make(folder)
    before = _snapshot(folder)
    r = runner.invoke(app, case.args)
    assert r.exit_code == 0, f"stderr: {r.stderr}; exception: {r.exception!r}"
    assert "Traceback" not in r.stderr and "Traceback" not in r.stdout
    text = r.stdout
    if "-o" in case.args and case.args[0] == "report":
        text = re.sub(r"base64,[A-Za-z0-9+/=]+", "", (folder / "r.html").read_text())
    for words in case.expect:
        assert words in text, f"{words!r} not in the output"
    for bad in (" nan ", " inf ", "NaN", "Infinity"):
        assert bad not in text, f"{bad!r} in the output"
    if case.warns is None:
        assert r.stderr == "", r.stderr
    else:
        assert all(w in r.stderr for w in case.warns), r.stderr
        assert "free run" not in r.stderr, r.stderr
    after = _snapshot(folder)
    forced = case.args[case.args.index("-o") + 1] if "--force" in case.args else None
    assert {k: after[k] for k in before if k != forced} == {
        k: v for k, v in before.items() if k != forced
    }, "an existing file was changed"


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
@pytest.mark.parametrize(
    "args",
    [
        ["bla", *PER, "--json"],
        ["design", "multisine", "--samples", "64"],
        ["residuals", "model.json", "good.csv"],
    ],  # fmt: skip
    ids=["bla", "design", "residuals"],
)
def test_a_full_standard_output_is_one_line(args, folder):
    """``> /dev/full``: one line naming standard output, exit 1, no traceback."""
    import subprocess
    import sys

    with open("/dev/full", "w") as full:
        run = subprocess.run([sys.executable, "-m", "blockid.cli.main", *args], stdout=full,
                             stderr=subprocess.PIPE, text=True, timeout=120)  # fmt: skip
    assert run.returncode == 1
    assert run.stderr.strip().splitlines() == [
        "error: cannot write standard output: No space left on device"
    ]
