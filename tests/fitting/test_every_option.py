"""Every option of every method, off its default, changes the fit as it says.

Generated from the registry (:data:`blockid.fitting.registry.STRUCTURES`): for every
(structure, method, option) the structure's plant is fitted through
:func:`blockid.fitting.fit_model` once with the option left out and once with a
non-default value, and :data:`EXPECT` says how the second result must differ from
the first (not only that it ran). An option some method takes without an entry in
:data:`EXPECT`, or a (structure, method) without a case in
:data:`plants_for_options.CASES`, fails a test here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pytest

from blockid.blocks import Integrator, Polynomial
from blockid.errors import BlockidError, EstimationError
from blockid.fitting import fit_model
from blockid.fitting.arx import regressor_scale
from blockid.fitting.registry import OPTIONS, STRUCTURES
from blockid.fitting.result import FitResult
from blockid.fitting.simulation_error import simulation_mse
from blockid.models import ARX
from blockid.models.block import ChainModel
from plants_for_options import CASES, Case, record, recursion_vector

import reference

Outcome = FitResult | BlockidError


# ----------------------------------------------------------------------------- helpers
def _theta(result: FitResult) -> np.ndarray:
    model = result.model
    return model.parameter_vector(0) if isinstance(model, ARX) else model.free_parameters()


def _differs(default: FitResult, changed: FitResult) -> None:
    a, b = _theta(default), _theta(changed)
    assert a.shape != b.shape or not np.allclose(a, b, rtol=1e-9, atol=1e-12), (a, b)


def _same(default: FitResult, changed: FitResult) -> None:
    np.testing.assert_allclose(_theta(changed), _theta(default), rtol=1e-12, atol=1e-14)


def _orders(model: Any) -> tuple[int, int, int]:
    if isinstance(model, ARX):
        return int(model.na[0, 0]), int(model.nb[0, 0]), int(model.nk[0, 0])
    return model.linear_orders()  # of all linear blocks together


def _n_coefficients(model: Any, letter: str) -> int:
    if isinstance(model, ARX):
        return sum(name.startswith(f"{letter}[") for name in model.parameter_names(0))
    # a, b of one linear block; a1, b1, a2, b2 of several
    return sum(len(v) for k, v in model.parameters.items() if k.rstrip("0123456789") == letter)


def _offsets(model: Any) -> tuple[float, float]:
    return float(np.ravel(model.input_offset)[0]), float(np.ravel(model.output_offset)[0])


def _means(case: Case) -> tuple[float, float]:
    e = case.data().experiments[0]
    return float(np.mean(e.u)), float(np.mean(e.y))


def _regression(case: Case, model: ARX) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ARX regressor, target and the column scales the recursive methods use."""
    data = case.data()
    e = data.experiments[0]
    Phi, target = model.regressors(e.u, e.y, 0)
    return Phi, target, regressor_scale(model, 0, "rms", data)


def _one_step_mse(case: Case, model: Any) -> float:
    e = case.data().experiments[0]
    lag = model.max_lag
    return float(np.mean((e.y[lag:, 0] - model.predict(e.u, e.y)[lag:, 0]) ** 2))


def _least_squares(case: Case) -> ARX:
    orders = {k: case.options[k] for k in ("na", "nb", "nk")}
    return fit_model(case.data(), "arx", **orders).model


def _raised(outcome: Outcome, text: str) -> None:
    assert isinstance(outcome, EstimationError), outcome
    assert text in str(outcome), str(outcome)


def _returned(outcome: Outcome) -> FitResult:
    assert isinstance(outcome, FitResult), outcome
    return outcome


# ----------------------------------------------------------------------------- checks
# Each check is called as check(case, default, changed, value); ``default`` is the fit
# with the option left out (or the error it raised), ``changed`` the fit with ``value``.


def _check_na(case, default, changed, value):
    assert _orders(default.model)[0] == case.options["na"]
    assert _orders(changed.model)[0] == value == _n_coefficients(changed.model, "a")


def _check_nb(case, default, changed, value):
    assert _orders(default.model)[1] == case.options["nb"]
    assert _orders(changed.model)[1] == value
    # b_0 .. b_nb-1 of one linear block; a chain of several has one more per block
    extra = 0 if isinstance(changed.model, ARX) else len(changed.model.linear_blocks) - 1
    assert _n_coefficients(changed.model, "b") == value + extra


def _check_nk(case, default, changed, value):
    # on a record delayed by one more sample, the larger delay fits better
    assert _orders(changed.model)[2] == value
    if isinstance(default, BlockidError):
        return
    assert _orders(default.model)[2] == case.options["nk"]
    _differs(default, changed)
    if isinstance(changed.model, ChainModel) and len(changed.model.linear_blocks) > 1:
        return  # W-H shares the delay between its two linear blocks: no claim on quality
    mse = [r.estimation_metrics["mse"]["y"] for r in (default, changed)]
    assert mse[1] < mse[0], mse


def _check_center(case, default, changed, value):
    from blockid.fitting.simulation_error import offset_is_free

    means = _means(case)
    centered, plain = (changed, default) if value else (default, changed)
    refined = offset_is_free(centered.model) and case.method == "simulation-error"
    if refined:  # a Wiener model refines its output offset
        assert _offsets(centered.model)[0] == pytest.approx(means[0], rel=1e-12)
        data, model = case.data(), centered.model
        step = 0.01 * float(np.std(data.experiments[0].y))
        mse = [simulation_mse(model.replace(output_offset=model.output_offset + d), data)
               for d in (-step, 0.0, step)]  # fmt: skip
        assert mse[1] < min(mse[0], mse[2]), mse  # the least-squares constant
    else:
        np.testing.assert_allclose(_offsets(centered.model), means, rtol=1e-12)
    assert all(abs(m) > 1e-3 for m in means)
    if refined:  # not centred: no input offset, the output's the refined constant
        assert _offsets(plain.model)[0] == 0.0 and _offsets(plain.model)[1] != 0.0
    else:
        assert _offsets(plain.model) == (0.0, 0.0)
    _differs(default, changed)


def _check_refine(case, default, changed, value):
    if case.method == "simulation-error":  # already the refinement: nothing to add
        assert changed.method == default.method == "simulation-error"
        _same(default, changed)
        return
    assert changed.method == f"{default.method}+refine"
    assert changed.settings["started_from"] == default.method
    assert changed.metrics_mode == "simulation"
    start = simulation_mse(default.model, case.data())
    assert changed.settings["initial_simulation_mse"] == pytest.approx(start, rel=1e-9)
    assert changed.settings["final_simulation_mse"] <= start


def _check_allow_unstable(case, default, changed, value):
    _raised(default, "unstable")
    assert not _returned(changed).model.is_stable()


def _check_convergence_check(case, default, changed, value):
    _raised(default, "did not converge")
    model = _returned(changed).model
    best = _least_squares(case)
    assert _one_step_mse(case, model) > 2.0 * _one_step_mse(case, best)


def _check_max_mse_ratio(case, default, changed, value):
    _raised(default, "did not converge")
    model = _returned(changed).model
    best = _least_squares(case)
    assert 2.0 < _one_step_mse(case, model) / _one_step_mse(case, best) <= value


def _check_forgetting(case, default, changed, value):
    _differs(default, changed)
    if case.method == "rls":  # exactly the exponentially weighted least squares
        Phi, target, _ = _regression(case, changed.model)
        lam = float(value)
        weights = lam ** np.arange(target.size - 1, -1, -1.0)
        expected = reference.weighted_least_squares(Phi, target, weights)[:, 0]
        np.testing.assert_allclose(_theta(changed), expected, rtol=1e-6)
    elif case.method == "hierarchical-rls":  # H-RLS converges only with forgetting
        assert _one_step_mse(case, changed.model) < 0.5 * _one_step_mse(case, default.model)
    else:
        assert default.settings["forgetting"] == "0.98:200,1"
        assert changed.settings["forgetting"] == str(value)


def _arx_recursion(case, model, *, passes=None, mu=None, lam=1.0, eps=(1.0, 0.1)):
    """The recursive ARX estimate from the reference twins (tests/reference.py)."""
    Phi, target, scale = _regression(case, model)
    passes = case.options.get("passes", 1) if passes is None else passes
    rows = np.vstack([Phi / scale] * passes)
    y = np.concatenate([target] * passes)
    if case.method == "rls":
        mu = 1e8 if mu is None else mu
        lams = np.full(y.size, lam)
        theta, _ = reference.rls(rows, y, lams, mu, trace_max=mu * rows.shape[1])
    elif case.method == "aw-rls":
        theta, _, _ = reference.aw_rls(rows, y, *eps, 1e5 if mu is None else mu)
    else:
        groups = [list(g) for g in model.hierarchical_groups(0)]
        lams = np.full(y.size, lam)
        theta, _ = reference.hierarchical_rls(rows, y, groups, lams, 1e8 if mu is None else mu)
    return theta[:, 0] / scale


def _lam(case):
    return float(case.options.get("forgetting", 1.0))


def _check_initial_covariance(case, default, changed, value):
    _differs(default, changed)
    if case.structure == "arx":  # the same recursion from P(0) = value * I
        expected = _arx_recursion(case, changed.model, mu=value, lam=_lam(case))
        np.testing.assert_allclose(_theta(changed), expected, rtol=1e-6, atol=1e-9)
        # a smaller P(0) keeps the estimate nearer theta(0) = 0 (RLS, H-RLS)
        if case.method != "aw-rls":
            assert np.linalg.norm(_theta(changed)) < np.linalg.norm(_theta(default))
        return
    # paper recursions, one pass from theta(0) = the plant: a smaller P(0) stays nearer
    assert changed.settings["initial_covariance"] == value
    truth = case.plant().free_parameters()
    near, far = (np.abs(_theta(r) - truth).max() for r in (changed, default))
    assert near < 0.5 * far and near < 1e-2, (near, far)


def _check_passes(case, default, changed, value):
    _differs(default, changed)
    assert changed.settings["passes"] == value
    if case.structure == "arx":  # the recursion run over the record `value` times
        mu = 1e-2
        expected = _arx_recursion(case, changed.model, passes=value, mu=mu)
        np.testing.assert_allclose(_theta(changed), expected, rtol=1e-6, atol=1e-9)
    elif value == 1:
        assert default.settings["passes_run"] > 1 and default.settings["converged"] is True
        assert changed.settings["passes_run"] == 1 and changed.settings["converged"] is None
    else:
        assert default.settings["passes_run"] == 1
        assert changed.settings["passes_run"] > 1 and changed.settings["converged"] is True


def _check_standard_errors(case, default, changed, value):
    # the same estimate, now with standard errors shaped like the model's parameters
    _same(default, changed)
    assert "standard_errors" not in default.settings
    errors_ = changed.settings["standard_errors"]
    doc = changed.model.to_dict()  # a state-space file holds its matrices at the top
    params = doc["parameters"] if "parameters" in doc else changed.model.parameters
    assert set(errors_) == set(params)
    for name, value_ in params.items():
        assert np.shape(errors_[name]) == np.shape(value_)
    cov = np.asarray(changed.settings["covariance"]["matrix"], dtype=float)
    assert cov.shape[0] == cov.shape[1] > 0 and np.allclose(cov, cov.T)


def _check_tol(case, default, changed, value):
    assert changed.settings["tol"] == value
    assert changed.settings["converged"] is True and default.settings["converged"] is True
    assert 2 <= changed.settings["passes_run"] < default.settings["passes_run"]
    _differs(default, changed)


def _check_initial_parameters(case, default, changed, value):
    # theta(0) given in the data's units, and P(0) too small to leave it in one pass:
    # the estimate is the plant; from the default theta(0) = 0.01 it is no model at all
    assert changed.settings["initial_parameters"] == value
    np.testing.assert_allclose(_theta(changed), case.plant().free_parameters(), atol=1e-6)
    if not isinstance(default, EstimationError):  # no model, or far from the plant
        assert np.abs(_theta(default) - case.plant().free_parameters()).max() > 1e-2


def _check_normalize(case, default, changed, value):
    assert default.settings["normalize"] is True and changed.settings["normalize"] is False
    _differs(default, changed)


def _check_eps(name):
    def check(case, default, changed, value):
        _differs(default, changed)
        if case.structure == "arx":  # the same recursion with the other weight
            eps = {"eps1": 1.0, "eps2": 0.1, name: value}
            expected = _arx_recursion(case, changed.model, eps=(eps["eps1"], eps["eps2"]))
            np.testing.assert_allclose(_theta(changed), expected, rtol=1e-6, atol=1e-9)
        assert changed.settings[name] == value

    return check


def _check_record_history(case, default, changed, value):
    assert "theta" not in default.history
    history = changed.history
    assert history["theta"].shape[1] == len(history["names"]) >= 2
    assert history["theta"].shape[0] == history["update"].size > 100
    _same(default, changed)


def _check_r1(case, default, changed, value):
    assert len(default.model.input_block.f) == case.options["r1"] + 1
    assert len(changed.model.input_block.f) == value + 1 == len(changed.model.input_block.p)


def _degree(model: Any) -> int:
    """Degree of the model's polynomial block (the output block, or W-H's static one)."""
    (poly,) = [b for b in model.blocks if isinstance(b, Polynomial)]
    return poly.coefficients.size - int(poly.constant)


def _check_r2(case, default, changed, value):
    assert _degree(default.model) == case.options["r2"]
    assert _degree(changed.model) == value
    _differs(default, changed)


def _check_r(case, default, changed, value):
    assert default.settings["r"] == case.options["r"] and changed.settings["r"] == value
    assert changed.model.free_parameters().size == default.model.free_parameters().size + 1
    _differs(default, changed)


def _check_input_block(case, default, changed, value):
    if case.structure == "block-state-space":  # a block per channel
        assert default.model.input_blocks[0].kind == "polynomial"
        assert changed.model.input_blocks[0].kind == value
        assert changed.settings["input_blocks"] == [value]
        return
    assert default.model.input_block.kind == "two-segment-polynomial"
    assert changed.model.input_block.kind == value == changed.settings["input_block"]


def _check_output_block(case, default, changed, value):
    if case.structure == "block-state-space":  # a block per channel
        assert default.model.output_blocks == (None,)
        (block,) = changed.model.output_blocks
        assert block.kind == "polynomial" and len(block.coefficients) == 4  # no constant
        assert changed.settings["output_blocks"] == ["polynomial"]
        return
    assert len(default.model.parameters["q"]) == case.options["r2"]
    assert len(changed.model.parameters["q"]) == 4  # degree 4, no constant term
    assert changed.settings["output_block"] == "polynomial"


def _check_loop_block(case, default, changed, value):
    assert default.model.loop_blocks == () and default.settings["loop_blocks"] == []
    (block,) = changed.model.loop_blocks
    assert block.kind == value and changed.settings["loop_blocks"] == [value]
    assert changed.model.kind.endswith("+loop")


def _check_feedback_block(case, default, changed, value):
    assert default.model.feedback.kind == "polynomial" and default.settings["center"] is True
    assert changed.model.feedback.kind == "dead-zone"
    assert changed.settings["feedback_block"] == "dead-zone"
    assert changed.settings["center"] is False  # a dead zone sits at the signals' zero
    assert "N.lower" in changed.model.free_parameter_names()


def _integrating_record(case: Case) -> Any:
    """The case's plant with an integrator after its last linear block, without noise."""
    plant = case.plant()
    blocks = list(plant.blocks)
    blocks.insert(plant.last_linear_index + 1, Integrator(1))
    chain = ChainModel("u", "y", blocks)
    return record(chain, case.n, amplitude=case.amplitude, mean=case.mean, snr_db=None)


def _check_integrator(case, default, changed, value):
    # on the plant followed by an integrator, the fit with one follows the record; the
    # plain fit (its poles held inside the margin) cannot, or fails
    model = _returned(changed).model
    assert [b.kind for b in model.blocks].count("integrator") == 1
    assert changed.settings["integrator"] == value
    data = _integrating_record(case)
    mse = simulation_mse(model, data)
    assert mse < 1e-3 * float(np.var(data.experiments[0].y)), mse
    if not isinstance(default, BlockidError):
        assert simulation_mse(default.model, data) > 100 * mse


def _check_max_nfev(case, default, changed, value):
    assert changed.settings["max_nfev"] == value
    assert changed.settings["function_evaluations"] <= value + 1  # + the start
    assert changed.settings["function_evaluations"] < default.settings["function_evaluations"]
    assert changed.settings["stop_reason"] == "max_nfev reached"


def _check_tail_fraction(case, default, changed, value):
    assert default.settings["tail_mse"] is not None
    assert changed.settings["tail_fraction"] == 0.0
    assert changed.settings["tail_mse"] is None and changed.settings["initial_tail_mse"] is None
    assert changed.settings["early_stopping"] is False


def _check_patience(case, default, changed, value):
    assert changed.settings["patience"] == value
    assert changed.settings["early_stopping"] is True
    assert changed.settings["stop_reason"].startswith("early stopping: no better tail error in 1")
    assert changed.settings["function_evaluations"] < default.settings["function_evaluations"]


def _check_tolerance(name):
    def check(case, default, changed, value):
        reason = f"`{name}` termination condition is satisfied"
        assert reason in changed.settings["stop_reason"]
        fewer = changed.settings["function_evaluations"] < default.settings["function_evaluations"]
        assert fewer or reason not in default.settings["stop_reason"]

    return check


def _check_nx(case, default, changed, value):
    assert changed.model.nx == value == changed.settings["nx"]
    assert changed.settings["order_from"] == "given"
    if case.structure == "polynomial-state-space":  # chosen on held-back halves
        assert default.settings["order_from"].startswith("cross-validated")
        scored = [s["nx"] for s in default.settings["order_scores"]]
        assert default.model.nx == default.settings["nx"] in scored and len(scored) > 2
    else:
        assert default.settings["order_from"].startswith("canonical correlations")
        assert default.model.nx == 2


def _check_max_order(case, default, changed, value):
    assert changed.model.nx == value == 1 < default.model.nx


def _check_horizon(case, default, changed, value):
    assert changed.settings["horizon"] == value != default.settings["horizon"]
    _differs(default, changed)


def _check_weighting(case, default, changed, value):
    assert default.settings["weighting"] == "moesp" and changed.settings["weighting"] == value
    # canonical correlations lie between 0 and 1; MOESP's singular values need not
    assert 0 < max(changed.settings["singular_values"]) <= 1.0 + 1e-9
    _differs(default, changed)


def _check_feedthrough(case, default, changed, value):
    assert np.all(default.model.D == 0.0) and changed.settings["feedthrough"] is True
    assert np.any(changed.model.D != 0.0)


def _check_degree(case, default, changed, value):
    assert default.model.degree == case.options["degree"] and changed.model.degree == value
    assert changed.model.n_monomials > default.model.n_monomials


def _check_monomials(case, default, changed, value):
    nx = changed.model.nx
    assert np.any(default.model.exponents[:, nx:] > 0)  # full: the input's too
    assert np.all(changed.model.exponents[:, nx:] == 0) and changed.settings["monomials"] == value


def _check_margin(case, default, changed, value):
    width = [r.model.upper - r.model.lower for r in (default, changed)]
    np.testing.assert_allclose(width[1] / width[0], (1 + 2 * value) / (1 + 2 * 0.25), rtol=1e-9)
    assert changed.settings["margin"] == value


def _check_start_degree(case, default, changed, value):
    assert "rungs" not in default.settings and default.model.degree == 3
    assert [r["degree"] for r in changed.settings["rungs"]] == [value, 3]
    assert changed.model.degree == 3 and changed.settings["start_degree"] == value


def _check_rung_nfev(case, default, changed, value):
    assert default.settings["rungs"][1]["max_nfev"] == case.options["max_nfev"]
    assert changed.settings["rungs"][1]["max_nfev"] == value
    assert changed.settings["rungs"][0]["max_nfev"] == case.options["max_nfev"]


# ----------------------------------------------------------------------------- the table
@dataclass(frozen=True)
class Expect:
    """A non-default value of an option and how the fit must change with it.

    ``value`` may depend on the case (a function of it). ``extra`` options go to both
    fits (None removes a case option: the method's default applies); ``data`` replaces
    the case's record for both; ``n`` its length.
    """

    value: Any
    check: Callable[..., None]
    extra: dict[str, Any] | Callable[[Case], dict[str, Any]] = field(default_factory=dict)
    data: Callable[[Case], Any] | None = None
    n: Callable[[Case], int | None] | None = None

    def value_for(self, case: Case) -> Any:
        return self.value(case) if callable(self.value) else self.value

    def extra_for(self, case: Case) -> dict[str, Any]:
        return self.extra(case) if callable(self.extra) else self.extra


def _plus_one(name: str) -> Callable[[Case], int]:
    return lambda case: case.options[name] + 1


def _unstable_record(case: Case) -> Any:
    """A short record of an ARX plant with a pole at 1.05, which least squares finds."""
    plant = ARX(
        ["u"], ["y"], na=2, nb=2, nk=1, a={"y": {"y": [-1.55, 0.525]}}, b={"y": {"u": [1.0, 0.4]}}
    )
    return record(plant, 120, snr_db=40.0)


def _recursive_from_tiny_covariance(case: Case) -> dict[str, Any]:
    return {"initial_covariance": 1e-6}


def _one_pass(case: Case) -> dict[str, Any]:
    return {"passes": 1}


def _passes_extra(case: Case) -> dict[str, Any]:
    if case.structure == "arx":  # off the least-squares answer, so that passes tell
        return {"convergence_check": False, "initial_covariance": 1e-2, "forgetting": None}
    if case.structure == "backlash":
        return {"tol": 1e-4}
    return {"initial_parameters": recursion_vector(case.structure)}  # one pass suffices


def _SOLVER(case: Case) -> dict[str, Any]:  # noqa: N802 - a table entry
    takes_tail = "tail_fraction" in STRUCTURES[case.structure].accepted(case.method)
    return {"max_nfev": 20, **({"tail_fraction": 0.0} if takes_tail else {})}


#: option -> its non-default value and what it must change (see the checks above).
EXPECT: dict[str, Expect] = {
    "na": Expect(_plus_one("na"), _check_na),
    "nb": Expect(_plus_one("nb"), _check_nb),
    "nk": Expect(_plus_one("nk"), _check_nk, data=lambda case: case.data(delay=1)),
    "r1": Expect(_plus_one("r1"), _check_r1),
    "r2": Expect(_plus_one("r2"), _check_r2),
    "r": Expect(_plus_one("r"), _check_r),
    "input_block": Expect("dead-zone", _check_input_block),
    "output_block": Expect("polynomial:degree=4", _check_output_block),
    "feedback_block": Expect("dead-zone", _check_feedback_block),
    "loop_block": Expect("saturation", _check_loop_block),
    # not centred (the plants have no offsets): from centred data the Wiener-Hammerstein
    # split of the differenced record lands in another local minimum within max_nfev = 5
    "integrator": Expect(1, _check_integrator, {"center": False}, data=_integrating_record),
    "center": Expect(lambda case: not STRUCTURES[case.structure].center_default, _check_center),
    "refine": Expect(True, _check_refine),
    "allow_unstable": Expect(True, _check_allow_unstable, data=_unstable_record),
    "convergence_check": Expect(False, _check_convergence_check, _recursive_from_tiny_covariance),
    "max_mse_ratio": Expect(1e6, _check_max_mse_ratio, _recursive_from_tiny_covariance),
    "forgetting": Expect(
        lambda case: "0.99" if case.method == "key-term-rls" else "0.9",
        _check_forgetting,
        lambda case: (
            {"forgetting": None, "passes": None, "convergence_check": False}
            if case.method == "hierarchical-rls"
            else {}
        ),
        n=lambda case: 300 if case.method == "hierarchical-rls" else None,
    ),
    "initial_covariance": Expect(
        lambda case: 100.0 if case.structure == "arx" else 1e-4,
        _check_initial_covariance,
        lambda case: (
            {}
            if case.structure == "arx"
            else {"passes": 1, "initial_parameters": recursion_vector(case.structure)}
        ),
    ),
    "initial_parameters": Expect(
        lambda case: recursion_vector(case.structure),
        _check_initial_parameters,
        {"passes": 1, "initial_covariance": 1e-9},
    ),
    "passes": Expect(
        lambda case: {"arx": case.options.get("passes", 1) + 1, "backlash": 30}.get(
            case.structure, 1
        ),
        _check_passes,
        _passes_extra,
    ),
    "tol": Expect(1e-2, _check_tol, {"passes": 100}),
    "standard_errors": Expect(True, _check_standard_errors),
    "normalize": Expect(False, _check_normalize),
    "eps1": Expect(5.0, _check_eps("eps1")),
    "eps2": Expect(0.5, _check_eps("eps2")),
    "record_history": Expect(True, _check_record_history),
    "nx": Expect(3, _check_nx, {"nx": None}),
    "max_order": Expect(1, _check_max_order, {"nx": None}),
    "horizon": Expect(12, _check_horizon),
    "weighting": Expect("cva", _check_weighting),
    "feedthrough": Expect(True, _check_feedthrough),
    "degree": Expect(3, _check_degree),
    "monomials": Expect("states", _check_monomials),
    "margin": Expect(1.0, _check_margin),
    "start_degree": Expect(2, _check_start_degree, {"degree": 3}),
    "rung_nfev": Expect(1, _check_rung_nfev, {"degree": 3, "start_degree": 2}),
    "max_nfev": Expect(2, _check_max_nfev),
    "tail_fraction": Expect(0.0, _check_tail_fraction),
    "patience": Expect(1, _check_patience, {"max_nfev": 40}, n=lambda case: 150),
    "ftol": Expect(0.5, _check_tolerance("ftol"), _SOLVER),
    "xtol": Expect(0.5, _check_tolerance("xtol"), _SOLVER),
    "gtol": Expect(
        lambda case: 1e3 if case.structure == "wiener-hammerstein" else 0.5,
        _check_tolerance("gtol"),
        _SOLVER,
    ),
}


# ----------------------------------------------------------------------------- generated
def _triples() -> list[tuple[str, str, str]]:
    return [
        (structure.name, method, option)
        for structure in STRUCTURES.values()
        for method in structure.method_names
        for option in structure.accepted(method)
    ]


def _used_options() -> set[str]:
    return {option for _, _, option in _triples()}


def test_every_option_a_method_takes_has_an_expectation():
    missing = sorted(_used_options() - set(EXPECT))
    assert not missing, f"options without an entry in EXPECT (add one): {missing}"
    stale = sorted(set(EXPECT) - set(OPTIONS))
    assert not stale, f"EXPECT entries for options the registry no longer has: {stale}"


def test_every_structure_and_method_has_a_case():
    declared = {f"{s.name}/{m}" for s in STRUCTURES.values() for m in s.method_names}
    assert declared == set(CASES), declared ^ set(CASES)


_FITS: dict[tuple[Any, ...], Outcome] = {}


def _fit(case: Case, expect: Expect, options: dict[str, Any]) -> Outcome:
    """A fit of the case (errors returned), kept for the options' tests that share it."""
    key = (case.id, case.n, expect.data, tuple(sorted((k, repr(v)) for k, v in options.items())))
    if key not in _FITS:
        data = case.data() if expect.data is None else expect.data(case)
        try:
            _FITS[key] = fit_model(data, case.structure, method=case.method, **options)
        except BlockidError as exc:
            _FITS[key] = exc
    return _FITS[key]


#: Triples whose fit fails on a bug in src/ (strict xfail: fixing the bug fails them).
KNOWN_BUGS: dict[tuple[str, str, str], str] = {}


def _params() -> list[Any]:
    return [
        pytest.param(
            *triple,
            id="/".join(triple),
            marks=[pytest.mark.xfail(strict=True, reason=KNOWN_BUGS[triple])]
            if triple in KNOWN_BUGS
            else [],
        )
        for triple in _triples()
    ]


#: The regression methods of block-state-space: each option's change and its check
#: (their numbers against the truth: tests/fitting/test_block_arx.py).
REGRESSION = {"block-state-space/batch", "block-state-space/rls"}
_REGRESSION_CHANGES = {
    "input_block": "polynomial:degree=2",
    "na": 3,
    "nb": 3,
    "nk": 2,
    "forgetting": 0.99,
    "initial_covariance": 10.0,
    "passes": 3,
}


def _check_regression(case: Case, option: str) -> None:
    from blockid.errors import ParameterError

    data = case.data()
    default = fit_model(data, case.structure, method=case.method, **case.options)
    if option == "output_block":  # the regression holds input blocks only: refused
        with pytest.raises(ParameterError) as refused:
            fit_model(data, case.structure, method=case.method, **case.options,
                      output_block="polynomial")  # fmt: skip
        assert refused.value.parameter == "output_block"
        return
    value = _REGRESSION_CHANGES[option]
    changed = fit_model(data, case.structure, method=case.method, **{**case.options, option: value})
    _differs(default, changed)
    if option == "input_block":
        assert [b.coefficients.size for b in default.model.input_blocks] == [4]
        assert [b.coefficients.size for b in changed.model.input_blocks] == [3]
    elif option in ("na", "nb", "nk"):
        o = {**case.options, option: value}
        assert changed.settings[option] == value
        assert changed.model.nx == o["na"] + o["nk"] + o["nb"] - 1  # one input, one output
    else:  # the recursion's own settings
        assert changed.settings["regression"][option] == (
            str(value) if option == "forgetting" else value
        )


#: Key-term RLS of several inputs: each option's change (its numbers against the truth:
#: tests/fitting/test_key_term_channels.py). The case is a Hammerstein model (an input
#: block only), which the recursion converges on.
KEY_TERM_CHANNELS = "block-state-space/key-term-rls"
_KEY_TERM_CHANGES = {
    "input_block": "polynomial:degree=2",
    "output_block": "polynomial:degree=2",
    "na": 3,
    "nb": 3,
    "nk": 2,
    "forgetting": 0.99,
    "passes": 1,
    "tol": 1e-2,
    "initial_covariance": 10.0,
    "initial_parameters": 0.3,
    "normalize": False,
    "record_history": True,
    "center": True,
}


def _check_key_term_channels(case: Case, option: str) -> None:
    data = case.data()
    default = fit_model(data, case.structure, method=case.method, **case.options)
    value = _KEY_TERM_CHANGES[option]
    changed = fit_model(data, case.structure, method=case.method, **{**case.options, option: value})
    if option == "record_history":  # the same fit, its trajectory kept
        _same(default, changed)
        assert not default.history and changed.history["theta"].shape[1] == len(
            changed.history["names"]
        )
        # the last row is the estimate: the constant and the cubic's coefficients first
        np.testing.assert_allclose(
            changed.history["theta"][-1][:4], changed.model.input_blocks[0].coefficients
        )
        return
    _differs(default, changed)
    settings = changed.settings
    if option == "input_block":
        assert [b.coefficients.size for b in default.model.input_blocks] == [4]
        assert [b.coefficients.size for b in changed.model.input_blocks] == [3]
    elif option == "output_block":
        assert default.model.output_blocks == (None,)
        assert changed.model.output_blocks[0].degree == 2
        assert settings["blocks"]["output"] == "polynomial:degree=2"
    elif option in ("na", "nb"):
        assert settings[option] == value
        o = {**case.options, option: value}
        assert changed.model.nx == o["na"] + o["nk"] + o["nb"] - 1
    elif option == "nk":
        assert settings["nk"] == {"u": 2}
    elif option == "forgetting":
        assert settings["forgetting"] == str(value)
    elif option == "passes":
        assert settings["passes_run"] == 1 < default.settings["passes_run"]
    elif option == "tol":
        assert settings["passes_run"] < default.settings["passes_run"]
    elif option == "normalize":
        assert settings["normalize"] is False and default.settings["normalize"] is True
    elif option == "center":  # a Hammerstein model's default is not to centre
        assert settings["center"] is True and default.settings["center"] is False
        np.testing.assert_allclose(changed.model.input_offset, _means(case)[0])
    else:  # initial_covariance, initial_parameters: the start of the recursion
        assert settings[option] == value


@pytest.mark.parametrize(("structure", "method", "option"), _params())
def test_option_off_its_default_changes_the_fit(structure, method, option):
    if f"{structure}/{method}" in REGRESSION:
        _check_regression(CASES[f"{structure}/{method}"], option)
        return
    if f"{structure}/{method}" == KEY_TERM_CHANNELS:
        _check_key_term_channels(CASES[KEY_TERM_CHANNELS], option)
        return
    case = CASES[f"{structure}/{method}"]
    expect = EXPECT.get(option)
    if expect is None:
        pytest.fail(f"no expectation for option {option!r}; add it to EXPECT")
    n = None if expect.n is None else expect.n(case)
    if n is not None:
        case = replace(case, n=n)
    value = expect.value_for(case)
    options = {**case.options, **expect.extra_for(case)}
    default = _fit(case, expect, options)
    changed = _fit(case, expect, {**options, option: value})
    if isinstance(changed, BlockidError) and not isinstance(default, BlockidError):
        raise changed
    expect.check(case, default, changed, value)
