"""Paper B's key-term RLS (B4, B5): when it converges, and that it says so when it does not."""

import re

import numpy as np
import pytest

from blockid._kernels.rls import OK, rls_run
from blockid.blocks import Polynomial, TwoSegmentPolynomial
from blockid.data import Dataset
from blockid.data.dataset import Experiment
from blockid.errors import DataError, EstimationError, OrderError, ParameterError
from blockid.estimators.forgetting import ForgettingSchedule
from blockid.fitting.key_term import fit_key_term_rls
from blockid.models import ARX, Hammerstein, HammersteinWiener, Wiener

from reference import _arx_data, _dataset

# paper B's orders: na = 3, nb = 3 (b_0..b_2), nk = 8; two-segment cubic input block
A_FAST = np.real(np.poly([0.7, 0.5, -0.3]))[1:]
A_SLOW = np.real(np.poly([0.9, 0.8, 0.5]))[1:]
B = [1.0, 0.5, 0.2]
N1 = TwoSegmentPolynomial.from_segments(
    positive=[0, 0.3, 0.1, -0.05], negative=[0, 0.15, -0.05, 0.03]
)
N2 = Polynomial([1.0, 0.2, 0.05], constant=False)
ORDERS = dict(na=3, nb=3, nk=8)


def _hw(a=A_FAST, n1=N1, n2=N2):
    return HammersteinWiener("u", "y", input_block=n1, output_block=n2, a=a, b=B, **ORDERS)


def _hammerstein(a=A_FAST):
    return Hammerstein("u", "y", input_block=N1, a=a, b=B, **ORDERS)


def _wiener(a=A_FAST):
    return Wiener("u", "y", output_block=N2, a=a, b=B, **ORDERS)


def _white(n=4000, seed=1):
    return np.random.default_rng(seed).uniform(-1.0, 1.0, n)


def _multisine(n=4000, seed=1):
    """Paper B's input: 0.05, 0.1, 0.2, 0.4, 0.5 Hz at 20 Hz sampling, peak 1."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 20.0
    u = sum(
        np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi)) for f in (0.05, 0.1, 0.2, 0.4, 0.5)
    )
    return u / np.max(np.abs(u))


def _data(plant, u, snr_db=None, seed=2):
    y = plant.simulate(u)[:, 0]
    if snr_db is not None:
        y = y + np.random.default_rng(seed).standard_normal(y.size) * np.std(y) * 10 ** (
            -snr_db / 20
        )
    return Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"], sampling_time=0.05)


def _error(model, plant):
    return float(np.max(np.abs(model.free_parameters() - plant.free_parameters())))


# ---------------------------------------------------------------------- ARX = plain RLS
def test_arx_structure_is_plain_rls_pass_after_pass():
    arx = ARX(
        ["u"], ["y"], na=2, nb=2, nk=1, a={"y": {"y": [-1.2, 0.5]}}, b={"y": {"u": [1.0, 0.4]}}
    )
    u = _white(1500)
    data = _data(arx, u, snr_db=40)
    kw = dict(na=2, nb=2, nk=1, initial_covariance=1e4, normalize=False)
    result = fit_key_term_rls(data, "arx", **kw)
    assert isinstance(result.model, ARX)
    n_passes = result.settings["passes_run"]
    assert result.settings["converged"] is True and n_passes >= 2
    # the same recursion on the ARX regressor [u(t-1), u(t-2), -y(t-1), -y(t-2)]
    y = data.experiments[0].y[:, 0]
    Phi = np.column_stack([u[1:-1], u[:-2], -y[1:-1], -y[:-2]])
    theta, P = np.full(4, 0.01), 1e4 * np.eye(4)
    lam = ForgettingSchedule.parse("0.98:200,1").factors(0, len(Phi))
    for _ in range(n_passes):  # the schedule restarts with every pass
        assert rls_run(theta, P, Phi, y[2:], lam, 4e4, np.empty(len(Phi))) == OK
    np.testing.assert_array_equal(result.model.b["y"]["u"], theta[:2])
    np.testing.assert_array_equal(result.model.a["y"]["y"], theta[2:])
    np.testing.assert_allclose(theta, [1.0, 0.4, -1.2, 0.5], atol=0.02)


def test_arx_normalisation_changes_only_the_start():
    arx = ARX(
        ["u"], ["y"], na=2, nb=2, nk=1, a={"y": {"y": [-1.2, 0.5]}}, b={"y": {"u": [1.0, 0.4]}}
    )
    data = _data(arx, 10.0 * _white(1500), snr_db=40)
    raw = fit_key_term_rls(data, "arx", na=2, nb=2, nk=1, normalize=False).model
    scaled = fit_key_term_rls(data, "arx", na=2, nb=2, nk=1).model
    np.testing.assert_allclose(scaled.parameter_vector(0), raw.parameter_vector(0), rtol=1e-6)


# ---------------------------------------------------------------------- convergence
@pytest.mark.parametrize(
    ("plant", "structure", "passes_max"),
    [
        (_hammerstein(), "hammerstein", 6),
        (_wiener(), "wiener", 8),
        (_hw(), "hammerstein-wiener", 16),
    ],
    ids=["hammerstein", "wiener", "hammerstein-wiener"],
)
def test_white_noise_input_converges_to_the_truth(plant, structure, passes_max):
    result = fit_key_term_rls(_data(plant, _white()), structure, **ORDERS)
    assert type(result.model) is type(plant)
    assert _error(result.model, plant) < 1e-6  # measured 6e-10 (H), 7e-9 (W), 8e-9 (H-W)
    assert result.settings["converged"] is True
    assert result.settings["passes_run"] <= passes_max  # measured 5, 6, 13


@pytest.mark.parametrize(
    ("plant", "structure", "bound"),
    [(_hammerstein(), "hammerstein", 0.1), (_hw(), "hammerstein-wiener", 0.03)],
    ids=["hammerstein", "hammerstein-wiener"],
)
def test_white_noise_input_at_40_db(plant, structure, bound):
    # Hammerstein: x = y is measured, so noisy past outputs enter the regressor and the
    # a's and b_1 carry the equation-error bias, 0.05-0.08 at 40 dB (seeds 2-4); H-W uses
    # the estimated x instead: <= 0.02
    data = _data(plant, _white(), snr_db=40)
    result = fit_key_term_rls(data, structure, **ORDERS)
    assert _error(result.model, plant) < bound
    e = data.experiments[0]
    y_sim = result.model.simulate(e.u)[:, 0]
    y_true = plant.simulate(e.u)[:, 0]
    # free run against the noise-free output: within 1 % (the noise alone is 1 %)
    assert np.linalg.norm(y_true - y_sim) / np.linalg.norm(y_true - y_true.mean()) < 0.01


def test_paper_default_settings_on_two_experiments():
    # internal signals restart at rest with every experiment (theta, P carry over)
    plant = _hw()
    exps = [
        Experiment(n, u, plant.simulate(u))
        for n, u in (("a", _white(2000, 3)), ("b", _white(2000, 4)))
    ]
    result = fit_key_term_rls(Dataset(("u",), ("y",), 0.05, exps), "hammerstein-wiener")
    assert _error(result.model, plant) < 1e-6
    assert result.model.sampling_time == 0.05


def test_history_records_the_trajectory_in_data_units():
    # u spans +-3: the recursion runs on u / std(u); the history is mapped back
    plant = _hammerstein()
    data = _data(plant, 3.0 * _white(2000))
    result = fit_key_term_rls(data, "hammerstein", record_history=True, **ORDERS)
    hist = result.history
    assert hist["names"][:2] == ["f_0", "f_1"] and hist["names"][-3:] == ["a_1", "a_2", "a_3"]
    # 20 passes x 1990 updates would be 39 800 rows: every 2nd is kept (<= 20 000)
    n_rows = result.settings["passes_run"] * (1990 // 2)
    assert hist["theta"].shape == (n_rows, 13)
    np.testing.assert_array_equal(hist["update"], 2 * np.arange(1, n_rows + 1))
    np.testing.assert_allclose(hist["theta"][-1, :8], N1.to_vector(), atol=1e-6)
    assert abs(hist["theta"][0, 1] - N1.f[1]) > 0.05  # it starts far away


def test_a_failed_fit_carries_the_history_it_recorded():
    # Paper B's multisine to the H-W plant: 3 passes do not settle. The error carries
    # the trajectory in data units; its first pass is exactly the 1-pass fit's history.
    data = _data(_hw(), _multisine(1500))
    with pytest.raises(EstimationError, match="did not converge in 3 passes") as info:
        fit_key_term_rls(data, "hammerstein-wiener", passes=3, record_history=True)
    failed = info.value.history
    n = 1500 - 10  # updates per pass (max lag 10)
    assert failed["theta"].shape == (3 * n, 15) and np.all(np.isfinite(failed["theta"]))
    np.testing.assert_array_equal(failed["update"], np.arange(1, 3 * n + 1))
    one = fit_key_term_rls(data, "hammerstein-wiener", passes=1, record_history=True).history
    assert failed["names"] == one["names"]
    np.testing.assert_allclose(failed["theta"][:n], one["theta"], rtol=1e-12, atol=1e-12)
    with pytest.raises(EstimationError) as plain:
        fit_key_term_rls(data, "hammerstein-wiener", passes=3)
    assert plain.value.history is None  # nothing recorded unless asked


def test_a_diverged_fit_keeps_the_rows_before_the_failing_sample():
    plant = _hw(n1=TwoSegmentPolynomial(N1.f / 100.0 ** np.arange(4), N1.p / 100.0 ** np.arange(4)))
    data = _data(plant, 100.0 * _white())
    with pytest.raises(EstimationError, match=r"at sample (\d+)") as info:
        fit_key_term_rls(data, "hammerstein-wiener", normalize=False, record_history=True, passes=1)
    sample = int(re.search(r"at sample (\d+)", str(info.value)).group(1))
    history = info.value.history
    assert history["theta"].shape[0] == sample - 10  # one row per update before it
    assert np.all(np.isfinite(history["theta"]))


# ---------------------------------------------------------------------- failures
@pytest.mark.parametrize(
    ("structure", "refusal"),
    [
        ("hammerstein-wiener", "did not converge in 20 passes"),
        ("wiener", r"diverged: after pass \d+ the linear block is unstable"),
    ],
)
def test_paper_multisine_input_does_not_converge_and_no_model_is_returned(structure, refusal):
    # every refusal ends with "See docs/convergence.md": match the check that refused
    plant = _hw() if structure == "hammerstein-wiener" else _wiener()
    with pytest.raises(EstimationError, match=refusal):
        fit_key_term_rls(_data(plant, _multisine()), structure)


def test_hw_multisine_reports_the_remaining_change():
    with pytest.raises(
        EstimationError, match=r"did not converge in 20 passes: .* changed by up to"
    ):
        fit_key_term_rls(_data(_hw(), _multisine()), "hammerstein-wiener")


def test_hw_slow_plant_does_not_converge_even_from_near_the_truth():
    plant = _hw(a=A_SLOW)
    data = _data(plant, _white())
    with pytest.raises(EstimationError, match="did not converge"):
        fit_key_term_rls(data, "hammerstein-wiener")
    # nor when started 5 % from the true parameters (B4 order: f, p, b_1.., a, q_2..)
    v = plant.free_parameters()  # f, p, a, b_1, b_2, q_2, q_3
    truth = np.concatenate([v[:8], v[11:13], v[8:11], v[13:]])
    with pytest.raises(EstimationError, match="did not converge"):
        fit_key_term_rls(data, "hammerstein-wiener", initial_parameters=truth * 1.05)


def test_hammerstein_on_the_slow_plant_converges():
    # the same slow linear block is no problem when x is measured (no output block)
    plant = _hammerstein(a=A_SLOW)
    result = fit_key_term_rls(_data(plant, _white()), "hammerstein")
    assert _error(result.model, plant) < 1e-6


def test_wiener_multisine_drives_the_linear_block_unstable_and_says_after_which_pass():
    with pytest.raises(EstimationError, match=r"after pass \d+ the linear block is unstable"):
        fit_key_term_rls(_data(_wiener(), _multisine()), "wiener")


def test_large_signals_on_raw_units_break_the_covariance_and_the_sample_is_named():
    # the same H-W plant with the input in units 100 times smaller (u up to 100):
    # on raw signals x^3 is huge and P(0) = 1e6 I loses definiteness at once
    plant = _hw(n1=TwoSegmentPolynomial(N1.f / 100.0 ** np.arange(4), N1.p / 100.0 ** np.arange(4)))
    data = _data(plant, 100.0 * _white())
    with pytest.raises(
        EstimationError,
        match=r"diverged in pass 1, experiment 'experiment 1', at sample \d+: the RLS update",
    ):
        fit_key_term_rls(data, "hammerstein-wiener", normalize=False)
    # normalised, the same data converge
    result = fit_key_term_rls(data, "hammerstein-wiener")
    assert _error(result.model, plant) < 1e-6


def test_single_pass_is_not_checked_for_convergence_but_for_the_model():
    result = fit_key_term_rls(_data(_hammerstein(), _white()), "hammerstein", passes=1)
    assert result.settings["passes_run"] == 1 and result.settings["converged"] is None


# ---------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("structure", "kwargs", "error", "match"),
    [
        ("narx", {}, ParameterError, "unknown structure 'narx'"),
        ("wiener", dict(r2=1), ParameterError, "r2=1 must be a whole number >= 2"),
        ("hammerstein", dict(r1=0), ParameterError, "r1 must be a whole number >= 1"),
        ("arx", dict(passes=0), ParameterError, "passes must be a whole number >= 1"),
        ("arx", dict(tol=-1.0), ParameterError, "tol must be > 0"),
        ("arx", dict(forgetting="0.98:x"), ParameterError, "cannot read forgetting"),
        ("arx", dict(initial_parameters=[1.0]), ParameterError, "finite values"),
        ("hammerstein-wiener", dict(nk=200), OrderError, "looks back"),
    ],
)
def test_bad_settings_name_the_parameter(structure, kwargs, error, match):
    with pytest.raises(error, match=match):
        fit_key_term_rls(_data(_hammerstein(), _white(150)), structure, **kwargs)


def test_needs_one_input_and_one_output():
    # several inputs and one output go channel by channel (test_key_term_channels.py)
    data = Dataset.from_arrays(np.zeros(50), np.zeros((50, 2)))
    with pytest.raises(DataError, match="one input and one output"):
        fit_key_term_rls(data, "arx")


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def test_key_term_rls_names_a_bad_nb():
    from blockid.fitting.key_term import fit_key_term_rls

    with pytest.raises(ParameterError, match=r"^nb=0 must be a whole number >= 1"):
        fit_key_term_rls(_dataset(), structure="hammerstein", na=1, nb=0, nk=1)


def test_key_term_rls_settings_record_r1():
    from blockid.fitting.key_term import fit_key_term_rls

    u, y = _arx_data()
    data = Dataset.from_arrays(u, y + 0.2 * y**2, ["u"], ["y"])
    fit = fit_key_term_rls(data, "hammerstein", na=1, nb=1, nk=1, r1=2)
    assert fit.settings["r1"] == 2 and "r2" not in fit.settings
