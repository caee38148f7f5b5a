"""The design's checks: each bad input is one error that names the parameter and the
fix, before any signal is made; the tables of parameters and defaults are the design
functions' own."""

import inspect

import pytest

from blockid.design import multisine, prbs, random_binary
from blockid.design.checks import DEFAULTS, PARAMETERS, band_lines, check_design
from blockid.errors import ParameterError

FUNCTIONS = {"multisine": multisine, "odd-multisine": multisine, "prbs": prbs,
             "random-binary": random_binary}  # fmt: skip


@pytest.mark.parametrize("kind", PARAMETERS)
def test_the_parameter_table_is_the_functions_signature(kind):
    params = inspect.signature(FUNCTIONS[kind]).parameters
    required, optional = PARAMETERS[kind]
    declared = {*required, *optional, "sampling_time", "periods"}
    if kind.endswith("multisine"):
        declared |= {"odd", "group"}
    assert declared == set(params)
    assert all(params[p].default is inspect.Parameter.empty for p in required)
    for name in set(params) & set(DEFAULTS):
        assert params[name].default == DEFAULTS[name], (kind, name)


def _refused(kind, parameter, *fragments, **given):
    with pytest.raises(ParameterError) as caught:
        check_design(kind, given)
    message = str(caught.value)
    assert caught.value.parameter == parameter, message
    assert all(f in message for f in fragments), message
    return message


def test_a_band_above_nyquist_is_refused():
    _refused(
        "multisine", "f_max", "f_max = 600 Hz", "Nyquist frequency 500 Hz", "lower f_max",
        samples=1000, sampling_time=1e-3, f_max=600,
    )  # fmt: skip


def test_f_min_above_f_max_is_refused():
    _refused("multisine", "f_min", "f_min = 50 Hz is above f_max = 20 Hz", "f_min <= f_max",
             samples=1000, sampling_time=1e-3, f_min=50, f_max=20)  # fmt: skip


def test_a_band_between_the_lines_is_refused():
    _refused("odd-multisine", "f_max", "no line", "1 Hz apart", "widen the band",
             samples=1000, sampling_time=1e-3, f_min=10.2, f_max=10.8)  # fmt: skip
    _refused("odd-multisine", "f_max", "no odd line", "its only line, 10, is even",
             samples=1000, sampling_time=1e-3, f_min=10, f_max=10.5)  # fmt: skip


@pytest.mark.parametrize("rms", [0, -1.0, float("nan")])
def test_a_non_positive_rms_value_is_refused(rms):
    _refused("multisine", "rms", "rms must be a finite number > 0", samples=64, rms=rms)


@pytest.mark.parametrize("order", [1, 25])
def test_a_prbs_order_out_of_range_is_refused(order):
    _refused("prbs", "order", "order must be 2..24", f"got {order}", order=order)


def test_a_parameter_of_another_kind_or_a_missing_one_is_refused():
    _refused("prbs", "realisations", "prbs takes no realisations", order=5, realisations=2)
    _refused("multisine", "levels", "multisine takes no levels", samples=64, levels=(0, 1))
    _refused("random-binary", "samples", "random-binary needs samples", clock=2)
    _refused("random-binary", "samples", "whole number of bits", samples=10, clock=3)
    _refused("prbs", "levels", "LOW < HIGH", order=5, levels="1,-1")
    _refused("sine", "kind", "choose one of multisine, odd-multisine, prbs, random-binary")


def test_the_library_runs_the_same_checks():
    with pytest.raises(ParameterError, match="Nyquist"):
        multisine(64, f_max=0.7)
    with pytest.raises(ParameterError, match="order must be"):
        prbs(30)
    with pytest.raises(ParameterError, match="rms must be"):
        multisine(64, rms=0)


def test_band_edges_on_the_grid_count_as_inside():
    # 0.1 Hz lines: 0.3 / 0.1 is 2.9999999999999996 in floating point
    assert band_lines(100, 0.1, 0.3, 0.7) == range(3, 8)
    assert band_lines(9, 1.0, None, 0.5) == range(1, 5)  # odd N: line 4 is below Nyquist
