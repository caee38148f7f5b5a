"""blockid.defaults: each shared default is written once, and every signature that
states one says the same."""

import inspect
import re

import pytest

from blockid.defaults import DEGREE, RECURSIVE, recursive_default
from blockid.estimators.adaptive import AdaptiveWeightedRLS
from blockid.estimators.hierarchical import HierarchicalRLS
from blockid.estimators.rls import RecursiveLeastSquares
from blockid.fitting.arx import fit_arx, make_estimator
from blockid.fitting.backlash import fit_backlash_aw_rls
from blockid.fitting.initial import initial_estimate
from blockid.fitting.key_term import fit_key_term_rls
from blockid.fitting.registry import OPTIONS
from blockid.fitting.simulation_error import fit_simulation_error
from blockid.models.block import HammersteinWiener

#: (callable, estimator in RECURSIVE whose defaults it states)
SIGNATURES = [
    (RecursiveLeastSquares, "rls"),
    (HierarchicalRLS, "hierarchical-rls"),
    (AdaptiveWeightedRLS, "aw-rls"),
    (fit_arx, "aw-rls"),
    (make_estimator, "aw-rls"),
    (fit_backlash_aw_rls, "backlash-aw-rls"),
    (fit_key_term_rls, "key-term-rls"),
]


@pytest.mark.parametrize(("fn", "estimator"), SIGNATURES, ids=lambda x: getattr(x, "__name__", x))
def test_signatures_state_the_tables_defaults(fn, estimator):
    params = inspect.signature(fn).parameters
    stated = {k: v for k, v in RECURSIVE[estimator].items() if k in params}
    assert any(params[k].default is not None for k in stated), fn.__name__
    for option, value in stated.items():
        # None: "the method's default", looked up in the table when the method is known
        if params[option].default is not None:
            assert params[option].default == value, (fn.__name__, option)


@pytest.mark.parametrize(
    "fn",
    [fit_key_term_rls, fit_simulation_error, initial_estimate, HammersteinWiener.default_blocks],
)
def test_the_polynomial_degree_is_the_tables(fn):
    params = inspect.signature(fn).parameters
    assert params["r1"].default == DEGREE and params["r2"].default == DEGREE


def test_the_help_states_the_tables_values():
    helps = {name: o.help for name, o in OPTIONS.items()}
    assert f"{RECURSIVE['backlash-aw-rls']['eps1']:g} for backlash" in helps["eps1"]
    assert "1e5 for aw-rls" in helps["initial_covariance"]
    assert "1e6 for key-term-rls" in helps["initial_covariance"]


def test_an_unknown_default_is_named():
    with pytest.raises(KeyError, match="'eps1' for the 'rls' estimator"):
        recursive_default("rls", "eps1")


def test_a_method_default_left_open_is_the_tables():
    from blockid.fitting.arx import make_estimator

    for method in ("rls", "aw-rls", "hierarchical-rls"):
        est = make_estimator(method)
        assert est.initial_covariance == RECURSIVE[method]["initial_covariance"], method


#: docs/models.md "Methods in detail": (method, structures column) -> estimator
DOC_ROWS = {
    ("rls", "arx, block-state-space (on the input powers)"): "rls",
    ("aw-rls", "arx"): "aw-rls",
    ("hierarchical-rls", "arx"): "hierarchical-rls",
    ("key-term-rls", "hammerstein, wiener, hammerstein-wiener"): "key-term-rls",
    ("aw-rls", "backlash"): "backlash-aw-rls",
}


def _same(text, value):
    text = text.strip().strip("`")
    try:
        return float(text) == float(value)
    except ValueError:
        return text == value


def test_the_docs_methods_table_states_the_tables_defaults():
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[1] / "docs" / "models.md").read_text()
    seen = set()
    for line in doc.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 5:
            continue
        key = (cells[0].strip("`"), cells[1])
        if key not in DOC_ROWS:
            continue
        seen.add(key)
        flags = [f.replace("-", "_") for f in re.findall(r"`--([a-z0-9-]+)`", cells[3])]
        values = cells[4].split(", ")
        assert len(flags) == len(values), line
        table = {**RECURSIVE[DOC_ROWS[key]], "r1": DEGREE, "r2": DEGREE}
        for flag, text in zip(flags, values, strict=True):
            if flag in table:
                assert _same(text, table[flag]), (key, flag, text, table[flag])
    assert seen == set(DOC_ROWS)
