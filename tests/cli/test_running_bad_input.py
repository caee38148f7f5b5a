"""Bad input to ``simulate`` and ``predict`` (:mod:`blockid.cli.running`): one table of
:class:`~cli.bad_input.Case` per command, each refused in one readable line with exit
status 2, no file written or changed (:func:`cli.bad_input.refused`). ``predict
--horizon``'s edge cases that it accepts are in a second table
(:func:`cli.bad_input.accepted`)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import pytest

from blockid.models import ARX, save_model
from cli.bad_input import (
    Accepted,
    Case,
    accepted,
    bad_model,
    figures,
    files,
    first_rows,
    folder_with_a_file,
    nan_parameter,
    parameter,
    params,
    refused,
    with_cell,
    write,
)


def _chain_model(change: Callable[[dict], None]) -> Callable[[Path], None]:
    """A Hammerstein model file (u -> y) as bad.json, edited by ``change``."""

    def make(d: Path) -> None:
        from blockid.blocks import TwoSegmentPolynomial
        from blockid.models import Hammerstein

        block = TwoSegmentPolynomial([0.0, 1.0], [0.0, -0.5])
        model = Hammerstein("u", "y", input_block=block, na=1, nb=1, nk=1, a=[-0.5])
        save_model(model, d / "bad.json")
        doc = json.loads((d / "bad.json").read_text())
        change(doc)
        (d / "bad.json").write_text(json.dumps(doc))

    return make


def _cyclic_network(d: Path) -> None:
    s1 = ARX(["v2"], ["v1"], 1, 1, 1, a={"v1": {"v1": [-0.5]}}, b={"v1": {"v2": [0.5]}})
    s2 = ARX(["v1"], ["v2"], 1, 1, 1, a={"v2": {"v2": [-0.5]}}, b={"v2": {"v1": [0.5]}})
    doc = json.loads((d / "network.json").read_text())
    doc["model"]["subsystems"] = [
        {"name": "S1", "model": s1.to_dict()},
        {"name": "S2", "model": s2.to_dict()},
    ]
    (d / "bad.json").write_text(json.dumps(doc))


def _state_space_model(change: Callable[[dict], None]) -> Callable[[Path], None]:
    """A linear state-space model file (u -> y, two states) as bad.json, edited."""

    def make(d: Path) -> None:
        from blockid.models import StateSpace

        A, B, C, D = [[0.5, 0.1], [0.0, 0.3]], [[1.0], [0.5]], [[1.0, 0.0]], [[0.0]]
        save_model(StateSpace(["u"], ["y"], A, B, C, D), d / "bad.json")
        doc = json.loads((d / "bad.json").read_text())
        change(doc["model"])
        (d / "bad.json").write_text(json.dumps(doc))

    return make


SIMULATE = [
    # ------------------------------------------------------------------ files
    Case(
        "file folder as data simulate",
        ["simulate", "model.json", "records", "--json"],
        ["records is a folder"],
        folder_with_a_file("records"),
    ),
    # ------------------------------------------------------------------ values
    Case(
        "value huge simulate",
        ["simulate", "model.json", "bad.csv", "--json"],
        ["column 'u', data row 4", "too large"],
        with_cell(3, 1, "1e300"),
    ),
    Case(
        "value NaN simulate",
        ["simulate", "model.json", "bad.csv", "--json"],
        ["column 'u', data row 3", "missing value"],
        with_cell(2, 1, "NaN"),
    ),
    Case(
        "value two rows simulate",
        ["simulate", "model.json", "bad.csv", "--json"],
        ["has only 2"],
        first_rows(2),
    ),
    Case(
        "ts zero simulate",
        ["simulate", "model.json", "good.csv", "--ts", "0", "--json"],
        ["positive number of seconds"],
    ),
    # ------------------------------------------------------------------ ranges
    Case(
        "range simulate beyond",
        ["simulate", "model.json", "good.csv", "--range", "250:400", "--json"],
        ["--range 250:400 does not fit"],
    ),
    Case(
        "range simulate reversed",
        ["simulate", "model.json", "good.csv", "--range", "200:100", "--json"],
        ["--range", "'200:100' is empty"],
    ),
    # ------------------------------------------------------------------ model files
    Case(
        "model missing",
        ["simulate", "none.json", "good.csv", "--json"],
        ["model file none.json does not exist"],
    ),
    Case(
        "model not JSON",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["not valid JSON"],
        lambda d: (d / "bad.json").write_text("{oops"),
    ),
    Case(
        "model other format",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["not a blockid model file"],
        lambda d: (d / "bad.json").write_text('{"format": "other"}'),
    ),
    Case(
        "model version",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["version 99"],
        bad_model(lambda doc: doc.update(version=99)),
    ),
    Case(
        "model NaN parameter",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["non-finite parameter", "parameters.y.a.y[0] is nan"],
        bad_model(nan_parameter),
    ),
    Case(
        "model unknown structure",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["unknown model structure 'magic'"],
        bad_model(lambda doc: doc["model"].update(structure="magic")),
    ),
    Case(
        "model incomplete",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["damaged or incomplete"],
        bad_model(lambda doc: doc["model"].pop("orders")),
    ),
    Case(
        "model signals not in data",
        ["simulate", "network.json", "good.csv", "--json"],
        ["no column 'u1'"],
    ),
    Case(
        "model truncated",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json is not valid JSON", "damaged"],
        lambda d: (d / "bad.json").write_text((d / "model.json").read_text()[:200]),
    ),
    Case(
        "model empty file",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["model file bad.json is empty"],
        write("bad.json", ""),
    ),
    Case(
        "model JSON array",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["not a blockid model file"],
        write("bad.json", "[1, 2, 3]"),
    ),
    Case(
        "model binary",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json is not a text file"],
        write("bad.json", bytes(range(128, 256)) * 4),
    ),
    Case(
        "model data file given as model",
        ["simulate", "good.csv", "good.csv", "--json"],
        ["good.csv is not valid JSON"],
    ),
    Case(
        "model is a folder",
        ["simulate", "models", "good.csv", "--json"],
        ["models is a folder, not a model file"],
        folder_with_a_file("models"),
    ),
    Case(
        "model entry null",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "model"],
        bad_model(lambda doc: doc.update(model=None)),
    ),
    Case(
        "model structure missing",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["unknown model structure None"],
        bad_model(lambda doc: doc["model"].pop("structure")),
    ),
    Case(
        "model parameters text",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "damaged"],
        bad_model(lambda doc: parameter(doc, "a", "abc")),
    ),
    Case(
        "model parameters wrong length",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "a"],
        bad_model(lambda doc: parameter(doc, "a", [0.1, 0.2, 0.3, 0.4, 0.5])),
    ),
    Case(
        "model parameter booleans",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["parameters.y.b.u must be a list of numbers", "[True, False]"],
        bad_model(lambda doc: parameter(doc, "b", [True, False])),
    ),
    Case(
        "model orders a word",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "na"],
        bad_model(lambda doc: doc["model"]["orders"].update(na="two")),
    ),
    Case(
        "model unstable diverges",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["the model output is not finite", "diverged"],
        bad_model(lambda doc: parameter(doc, "a", [-30.0, 0.0])),
    ),
    Case(
        "model chain with two inputs",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["names 2 inputs", "one input and one output"],
        _chain_model(lambda doc: doc["model"].update(inputs=["u", "u2"])),
    ),
    Case(
        "model chain block unknown",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "magic"],
        _chain_model(lambda doc: doc["model"]["chain"][0].update(kind="magic")),
    ),
    Case(
        "model arx input renamed",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "damaged"],
        bad_model(lambda doc: doc["model"].update(inputs=["u", "w"])),
    ),
    Case(
        "model outputs empty",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "output"],
        bad_model(lambda doc: doc["model"].update(outputs=[])),
    ),
    Case(
        "model sampling time negative",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json has sampling_time -1", "positive number of seconds"],
        bad_model(lambda doc: doc["model"].update(sampling_time=-1)),
    ),
    Case(
        "model state-space matrix shapes",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "B must have shape (2, 1), got (2, 2)"],
        _state_space_model(lambda m: m.update(B=[[1.0, 2.0], [0.5, 0.1]])),
    ),
    Case(
        "model state-space scale zero",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "scales must be positive"],
        _state_space_model(lambda m: m["normalisation"].update(input_scale=[0.0])),
    ),
    Case(
        "model network subsystem damaged",
        ["simulate", "bad.json", "net.csv", "--json"],
        ["bad.json", "subsystem 'S1'", "orders"],
        lambda d: (d / "bad.json").write_text(
            (d / "network.json").read_text().replace('"orders"', '"orderz"', 1)
        ),
    ),
    # ------------------------------------------------------------------ options
    Case(
        "option table exists",
        ["simulate", "model.json", "good.csv", "-o", "good.csv"],
        ["good.csv exists; pass --force"],
    ),
    Case(
        "option table type",
        ["simulate", "model.json", "good.csv", "-o", "out.xlsx"],
        ["unknown table type"],
    ),
    Case(
        "option simulate plot figure exists",
        ["simulate", "model.json", "good.csv", "--plot", "figs", "--json"],
        ["figs/simulation.png", "pass --force"],
        figures("figs", "simulation.png"),
    ),
    Case(
        "option simulate band too wide",
        ["simulate", "model.json", "good.csv", "--band", "1.5", "--json"],
        ["--band must be a confidence level between 0 and 1", "1.5"],
    ),
    Case(
        "option simulate band without covariance",
        ["simulate", "model.json", "good.csv", "--band", "0.95", "--json"],
        ["model.json holds no parameter covariance", "standard errors"],
    ),
    Case(
        "option simulate initial-samples negative",
        ["simulate", "model.json", "good.csv", "--initial-samples", "-1", "--json"],
        ["initial", "-1", "--initial-samples"],
    ),
    # ------------------------------------------------------------------ networks
    Case(
        "network cyclic model file",
        ["simulate", "bad.json", "net.csv", "--json"],
        ["cycle: 'S1' -> v1 -> 'S2' -> v2 -> 'S1'"],
        _cyclic_network,
    ),
    # ------------------------------------------------------------------ values
    Case(
        "simulate other sampling time",
        ["simulate", "model_ts.json", "bad.csv", "--ts", "0.1"],
        ["0.05", "--ts"],
        write("bad.csv", "u,y\n1,2\n2,3\n1,1\n3,1\n"),
    ),  # fmt: skip
]

PREDICT = [
    # ------------------------------------------------------------------ values
    Case(
        "value NaN predict",
        ["predict", "model.json", "bad.csv", "--json"],
        ["column 'y', data row 40", "is empty"],
        with_cell(39, 2, ""),
    ),
    # ------------------------------------------------------------------ ranges
    Case(
        "range predict not a range",
        ["predict", "model.json", "good.csv", "--range", "first half", "--json"],
        ["--range expects START:STOP"],
    ),
    Case(
        "range predict beyond the record",
        ["predict", "model.json", "good.csv", "--range", "0:301", "--json"],
        ["--range 0:301 does not fit", "300 samples"],
    ),
    # ------------------------------------------------------------------ model files
    Case(
        "model JSON null",
        ["predict", "bad.json", "good.csv", "--json"],
        ["not a blockid model file"],
        write("bad.json", "null"),
    ),
    Case(
        "model parameter null",
        ["predict", "bad.json", "good.csv", "--json"],
        ["bad.json", "parameters.y.b.u must be a list of numbers", "[None, 0.4]"],
        bad_model(lambda doc: parameter(doc, "b", [None, 0.4])),
    ),
    Case(
        "model infinite parameter",
        ["predict", "bad.json", "good.csv", "--json"],
        ["non-finite parameter", "parameters.y.b.u[1] is inf"],
        bad_model(lambda doc: parameter(doc, "b", [1.0, float("inf")])),
    ),
    Case(
        "model state-space not square",
        ["predict", "bad.json", "good.csv", "--json"],
        ["bad.json", "A must be a square matrix"],
        _state_space_model(lambda m: m.update(A=[[0.5, 0.1]])),
    ),
    # ------------------------------------------------------------------ options
    Case(
        "option predict plot figure exists",
        ["predict", "model.json", "good.csv", "--plot", "figs", "--json"],
        ["figs/prediction.png", "pass --force"],
        figures("figs", "prediction.png"),
    ),
    Case(
        "option predict band",
        ["predict", "model.json", "good.csv", "--band", "0.95", "--json"],
        ["--band applies to simulate only"],
    ),
    Case(
        "option predict output exists",
        ["predict", "model.json", "good.csv", "-o", "model.json"],
        ["model.json exists; pass --force"],
    ),
    # ------------------------------------------------------------------ values
    Case(
        "predict horizon other sampling time",
        ["predict", "model_ts.json", "bad.csv", "--ts", "0.1", "--horizon", "2"],
        ["0.05", "--ts"],
        write("bad.csv", "u,y\n1,2\n2,3\n1,1\n3,1\n"),
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
        files("old.csv"),
    ),  # fmt: skip
    Case(
        "predict horizon figure exists",
        ["predict", "model.json", "good.csv", "--horizon", "5", "--plot", "figs"],
        ["figs/prediction.png"],
        files("figs/prediction.png"),
    ),  # fmt: skip
]

PREDICT_ACCEPTED = [
    Accepted(
        "predict horizon longer than the record",
        ["predict", "model.json", "good.csv", "--horizon", "100000"],
        ["100000"],
    ),  # fmt: skip
    Accepted(
        "predict horizon on three rows",
        ["predict", "model.json", "bad.csv", "--horizon", "5"],
        ["arx"],
        write("bad.csv", "t,u,y\n0,1,2\n0.05,2,3\n0.1,1,1\n"),
        warns=["fit_percent of output 'y' is undefined"],
    ),  # fmt: skip
]


@pytest.mark.parametrize("case", params(SIMULATE, PREDICT))
def test_refused(case, workdir):
    refused(case, workdir)


@pytest.mark.parametrize("case", params(PREDICT_ACCEPTED))
def test_accepted(case, workdir):
    accepted(case, workdir)
