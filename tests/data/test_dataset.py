"""Tests of blockid.data.dataset: records, frame validation, select, orders, tables."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest

from blockid.data import Dataset, Experiment
from blockid.errors import BlockidError, DataError, OrderError, ParameterError


def frame(n=6, **extra):
    columns = {
        "t": 0.5 * np.arange(n),
        "u1": np.arange(n, dtype=float),
        "y1": -np.arange(n, dtype=float),
    }
    columns.update(extra)
    return pd.DataFrame(columns)


# ------------------------------------------------------------------ Experiment
def test_experiment_is_immutable_and_copies_writable_input():
    u = np.arange(4.0)
    exp = Experiment("run", u, 2 * u)
    assert exp.u.shape == (4, 1) and exp.y.shape == (4, 1)
    assert exp.u.dtype == np.float64 and exp.n_samples == 4
    u[0] = 99.0  # the caller's array is not the record
    assert exp.u[0, 0] == 0.0
    with pytest.raises(ValueError):
        exp.y[0, 0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        exp.name = "other"


def test_experiment_length_mismatch():
    with pytest.raises(DataError, match=r"u has 3 samples but y has 4"):
        Experiment("run", np.zeros(3), np.zeros(4))


def test_errors_are_blockid_errors():
    assert issubclass(DataError, BlockidError)


# ------------------------------------------------------------------ from_arrays
def test_from_arrays_defaults_and_shapes():
    u = np.column_stack([np.arange(5.0), np.ones(5)])
    data = Dataset.from_arrays(u, np.arange(5), sampling_time=0.1)
    assert data.inputs == ("u1", "u2") and data.outputs == ("y1",)
    assert data.sampling_time == 0.1
    assert data.n_samples == len(data) == 5 and data.n_experiments == 1
    assert data.experiments[0].name == "experiment 1"
    np.testing.assert_array_equal(data.experiments[0].u, u)
    np.testing.assert_array_equal(data.signal("y1")[0], np.arange(5.0))


def test_from_arrays_length_mismatch_names_both_lengths():
    with pytest.raises(DataError, match=r"u has 10 samples but y has 9"):
        Dataset.from_arrays(np.zeros(10), np.zeros(9))


def test_from_arrays_ragged_rows_say_what_to_give():
    with pytest.raises(DataError, match=r"u is not a rectangular array.*one Experiment each"):
        Dataset.from_arrays([np.zeros(10), np.zeros(9)], np.zeros(2))


def test_from_arrays_name_count_mismatch():
    with pytest.raises(DataError, match=r"u has 2 columns but 1 names were given \('a'\)"):
        Dataset.from_arrays(np.zeros((4, 2)), np.zeros(4), inputs=["a"])


def test_from_arrays_non_finite_names_signal_and_sample():
    y = np.arange(6.0)
    y[3] = np.nan
    with pytest.raises(DataError, match=r"signal 'out' is nan at sample 3"):
        Dataset.from_arrays(np.zeros(6), y, outputs=["out"])


def test_signal_both_input_and_output_is_an_error():
    with pytest.raises(DataError, match=r"'x' is listed both as an input and as an output"):
        Dataset.from_arrays(np.zeros(3), np.zeros(3), inputs=["x"], outputs=["x"])


def test_duplicate_signal_name_is_an_error():
    with pytest.raises(DataError, match=r"input signal 'a' is listed twice"):
        Dataset.from_frame(frame(a=np.ones(6)), ["a", "a"], ["y1"])


@pytest.mark.parametrize("bad", [0.0, -1.0, np.inf, "fast"])
def test_bad_sampling_time(bad):
    with pytest.raises(ParameterError, match="sampling_time must be a positive number"):
        Dataset.from_arrays(np.zeros(3), np.zeros(3), sampling_time=bad)


def test_duplicate_experiment_names_rejected():
    exp = Experiment("run", np.zeros(3), np.zeros(3))
    with pytest.raises(DataError, match="experiment name 'run' appears twice"):
        Dataset(("u1",), ("y1",), None, [exp, exp])


def test_experiment_width_must_match_names():
    exp = Experiment("run", np.zeros((3, 2)), np.zeros(3))
    with pytest.raises(DataError, match=r"'run' has 2 input and 1 output columns, but 1 inputs"):
        Dataset(("u1",), ("y1",), None, [exp])


# ------------------------------------------------------------------ from_frame checks
def test_from_frame_reads_columns_in_given_order():
    df = frame(u2=np.full(6, 7.0))
    data = Dataset.from_frame(df, ["u2", "u1"], ["y1"], source="mem")
    np.testing.assert_array_equal(data.experiments[0].u[:, 0], np.full(6, 7.0))
    np.testing.assert_array_equal(data.experiments[0].u[:, 1], np.arange(6.0))
    assert data.source == "mem" and data.sampling_time is None


def test_from_frame_missing_column_lists_available_and_suggests():
    with pytest.raises(DataError) as info:
        Dataset.from_frame(frame(), ["u_1"], ["y1"], source="plant.csv")
    message = str(info.value)
    assert message.startswith("plant.csv: no column 'u_1'")
    assert "did you mean 'u1'?" in message
    assert "available columns: 't', 'u1', 'y1'" in message


def test_from_frame_missing_column_case_only_difference_is_suggested():
    with pytest.raises(DataError, match=r"no column 'Y1' \(did you mean 'y1'\?\)"):
        Dataset.from_frame(frame(), ["u1"], ["Y1"])


def test_from_frame_non_numeric_cell():
    df = frame()
    df["y1"] = df["y1"].astype(object)
    df.loc[4, "y1"] = "broken"
    with pytest.raises(DataError) as info:
        Dataset.from_frame(df, ["u1"], ["y1"], source="rec.parquet")
    message = str(info.value)
    assert message.startswith("rec.parquet: column 'y1', data row 5: 'broken' is not a number")


def test_from_frame_nan_cell():
    df = frame()
    df.loc[2, "u1"] = np.nan
    with pytest.raises(DataError) as info:
        Dataset.from_frame(df, ["u1"], ["y1"], source="mem")
    message = str(info.value)
    assert "mem: column 'u1', data row 3 has a missing value" in message
    assert "remove that row or fill the gap" in message


def test_from_frame_infinite_cell():
    df = frame()
    df.loc[5, "y1"] = -np.inf
    with pytest.raises(DataError, match=r"column 'y1', data row 6 is infinite \(-inf\)"):
        Dataset.from_frame(df, ["u1"], ["y1"])


def test_from_frame_empty_frame():
    with pytest.raises(DataError, match="no data rows"):
        Dataset.from_frame(frame(0), ["u1"], ["y1"])


def test_from_frame_duplicate_column_in_frame():
    df = pd.DataFrame(np.zeros((3, 3)), columns=["u1", "y1", "y1"])
    with pytest.raises(DataError, match="column 'y1' appears more than once"):
        Dataset.from_frame(df, ["u1"], ["y1"])


def test_from_frame_bool_and_int_columns_become_float():
    df = pd.DataFrame({"u": [True, False, True], "y": pd.array([1, 2, 3], dtype="Int64")})
    data = Dataset.from_frame(df, ["u"], ["y"])
    np.testing.assert_array_equal(data.experiments[0].u[:, 0], [1.0, 0.0, 1.0])
    assert data.experiments[0].y.dtype == np.float64


def test_from_frame_numeric_strings_are_converted():
    df = pd.DataFrame({"u": ["1.5", " 2", "3e1"], "y": [1, 2, 3]})
    np.testing.assert_array_equal(
        Dataset.from_frame(df, ["u"], ["y"]).experiments[0].u[:, 0], [1.5, 2.0, 30.0]
    )


# ------------------------------------------------------------------ time column
def test_time_column_infers_sampling_time():
    data = Dataset.from_frame(frame(), ["u1"], ["y1"], time_column="t")
    assert data.sampling_time == 0.5


def test_time_column_small_jitter_is_accepted_and_median_step_used():
    t = np.array([0.0, 0.1, 0.2005, 0.3, 0.4, 0.5])  # steps 0.1 +- 0.5 %
    data = Dataset.from_frame(frame(t=t), ["u1"], ["y1"], time_column="t")
    assert data.sampling_time == pytest.approx(np.median(np.diff(t)))


def test_time_column_not_increasing_names_row():
    t = 0.5 * np.arange(6)
    t[4] = t[3]
    with pytest.raises(DataError) as info:
        Dataset.from_frame(frame(t=t), ["u1"], ["y1"], time_column="t", source="s.csv")
    message = str(info.value)
    assert "s.csv: time column 't' does not increase at data rows 4 and 5" in message
    assert "1.5 follows 1.5" in message


def test_time_column_non_uniform_names_row_and_steps():
    t = np.array([0.0, 0.5, 1.0, 1.5, 2.1, 2.6])
    with pytest.raises(DataError) as info:
        Dataset.from_frame(frame(t=t), ["u1"], ["y1"], time_column="t")
    message = str(info.value)
    assert "not uniformly sampled" in message
    assert "data rows 4 and 5" in message and "median step is 0.5" in message


def test_time_column_and_sampling_time_must_agree():
    with pytest.raises(DataError, match=r"sampling_time 0.1 disagrees with time column 't'"):
        Dataset.from_frame(frame(), ["u1"], ["y1"], sampling_time=0.1, time_column="t")
    data = Dataset.from_frame(frame(), ["u1"], ["y1"], sampling_time=0.502, time_column="t")
    assert data.sampling_time == 0.502  # agrees within 1 %: the given value is kept


def test_time_column_iso_datetimes_give_seconds():
    stamps = pd.date_range("2024-05-01 12:00:00", periods=6, freq="50ms")
    df = frame(t=stamps.strftime("%Y-%m-%dT%H:%M:%S.%f"))
    data = Dataset.from_frame(df, ["u1"], ["y1"], time_column="t")
    assert data.sampling_time == pytest.approx(0.05)


def test_time_column_datetime_gap_is_reported():
    stamps = list(pd.date_range("2024-05-01", periods=6, freq="1s").strftime("%Y-%m-%d %H:%M:%S"))
    stamps[2] = None
    with pytest.raises(DataError, match=r"column 't', data row 3 has a missing value"):
        Dataset.from_frame(frame(t=stamps), ["u1"], ["y1"], time_column="t")


def test_time_column_non_numeric_text_is_reported():
    df = frame(t=["0", "1", "two", "3", "4", "5"])
    with pytest.raises(DataError, match=r"column 't', data row 3: 'two' is not a number"):
        Dataset.from_frame(df, ["u1"], ["y1"], time_column="t")


def test_time_column_cannot_be_a_signal():
    with pytest.raises(DataError, match="time_column 'u1' is also listed as an input"):
        Dataset.from_frame(frame(), ["u1"], ["y1"], time_column="u1")


def test_time_column_single_sample_cannot_give_sampling_time():
    with pytest.raises(DataError, match="cannot infer the sampling time"):
        Dataset.from_frame(frame(1), ["u1"], ["y1"], time_column="t")


# ------------------------------------------------------------------ experiment column
def test_experiment_column_splits_in_order_of_first_appearance():
    df = frame(8, run=[3, 3, 3, 1, 1, 2, 2, 2])
    df["t"] = [0.0, 0.5, 1.0, 0.0, 0.5, 10.0, 10.5, 11.0]  # time restarts per experiment
    data = Dataset.from_frame(df, ["u1"], ["y1"], time_column="t", experiment_column="run")
    assert [e.name for e in data.experiments] == ["3", "1", "2"]
    assert [e.n_samples for e in data.experiments] == [3, 2, 3]
    np.testing.assert_array_equal(data.experiments[1].u[:, 0], [3.0, 4.0])
    np.testing.assert_array_equal(data.experiments[2].y[:, 0], [-5.0, -6.0, -7.0])
    assert data.sampling_time == 0.5 and data.n_samples == 8


def test_experiment_column_rows_must_be_contiguous():
    df = frame(5, run=["a", "a", "b", "a", "b"])
    with pytest.raises(DataError) as info:
        Dataset.from_frame(df, ["u1"], ["y1"], experiment_column="run")
    message = str(info.value)
    assert "experiment 'a'" in message and "starts again at data row 4" in message
    assert "first appears at data row 1" in message


def test_experiment_column_empty_label():
    df = frame(4, run=["a", "a", None, "b"])
    with pytest.raises(DataError, match=r"experiment column 'run', data row 3 is empty"):
        Dataset.from_frame(df, ["u1"], ["y1"], experiment_column="run")


def test_experiments_with_different_sampling_times_rejected():
    df = frame(6, run=["a", "a", "a", "b", "b", "b"])
    df["t"] = [0.0, 1.0, 2.0, 0.0, 2.0, 4.0]
    with pytest.raises(
        DataError, match=r"experiment 'a' has sampling time 1 but experiment 'b' has 2"
    ):
        Dataset.from_frame(df, ["u1"], ["y1"], time_column="t", experiment_column="run")


# ------------------------------------------------------------------ select
def two_experiments():
    a = Experiment("a", np.arange(10.0), 10 + np.arange(10.0))
    b = Experiment("b", np.arange(6.0), 20 + np.arange(6.0))
    return Dataset(("u",), ("y",), 1.0, [a, b], "two.csv")


def test_select_applies_half_open_range_to_each_experiment():
    part = two_experiments().select(2, 5)
    np.testing.assert_array_equal(part.signal("u")[0], [2.0, 3.0, 4.0])
    np.testing.assert_array_equal(part.signal("y")[1], [22.0, 23.0, 24.0])
    assert part.n_samples == 6 and part.sampling_time == 1.0 and part.source == "two.csv"


def test_select_open_ends():
    data = two_experiments()
    assert [e.n_samples for e in data.select(None, 4).experiments] == [4, 4]
    assert [e.n_samples for e in data.select(3, None).experiments] == [7, 3]
    assert data.select().n_samples == data.n_samples


def test_select_out_of_range_names_option_range_and_length():
    with pytest.raises(DataError) as info:
        two_experiments().select(0, 8, what="--validation")
    message = str(info.value)
    assert "--validation 0:8 does not fit experiment 'b', which has 6 samples" in message
    assert message.startswith("two.csv: ")


def test_select_start_beyond_end():
    with pytest.raises(DataError, match=r"range 6: does not fit experiment 'b'"):
        two_experiments().select(6, None)


def test_select_negative_index_rejected():
    with pytest.raises(DataError, match="negative sample indices are not allowed"):
        two_experiments().select(-3, None)


def test_select_empty_range_rejected():
    with pytest.raises(DataError, match=r"range 4:4 is empty"):
        two_experiments().select(4, 4)


# ------------------------------------------------------------------ check_orders
def test_check_orders_accepts_exactly_enough_rows():
    data = two_experiments()  # 10 + 6 samples
    data.check_orders(max_lag=3, n_parameters=10, what="ARX na=2 nb=2 nk=2")  # (10-3)+(6-3)


def test_check_orders_too_few_rows():
    with pytest.raises(OrderError) as info:
        two_experiments().check_orders(max_lag=3, n_parameters=11, what="ARX na=2 nb=2 nk=2")
    message = str(info.value)
    assert "ARX na=2 nb=2 nk=2 has 11 parameters" in message
    assert "give only 10" in message and "lower the orders or use a longer range" in message


def test_check_orders_experiment_shorter_than_lag():
    with pytest.raises(OrderError) as info:
        two_experiments().check_orders(max_lag=6, n_parameters=1, what="model")
    message = str(info.value)
    assert "more than 6 samples" in message and "experiment 'b' has only 6" in message


# ------------------------------------------------------------------ access and tables
def test_signal_unknown_name_suggests():
    with pytest.raises(DataError, match=r"no signal 'yy' \(did you mean 'y'\?\)"):
        two_experiments().signal("yy")


def test_to_frame_columns_and_round_trip():
    data = two_experiments()
    table = data.to_frame()
    assert list(table.columns) == ["experiment", "time", "u", "y"]
    np.testing.assert_array_equal(table["time"].to_numpy()[8:12], [8.0, 9.0, 0.0, 1.0])
    again = Dataset.from_frame(
        table, ["u"], ["y"], time_column="time", experiment_column="experiment"
    )
    assert again.sampling_time == 1.0
    assert [e.name for e in again.experiments] == ["a", "b"]
    for left, right in zip(again.experiments, data.experiments, strict=True):
        np.testing.assert_array_equal(left.u, right.u)
        np.testing.assert_array_equal(left.y, right.y)


def test_to_frame_single_experiment_without_time():
    table = Dataset.from_arrays(np.zeros(3), np.ones(3)).to_frame()
    assert list(table.columns) == ["u1", "y1"]


def test_repr_is_short():
    text = repr(two_experiments())
    assert "experiments=2" in text and "n_samples=16" in text and "array" not in text


def test_values_too_large_to_fit_are_refused_naming_the_signal_and_sample():
    """Issue 21: values of 1e300 ended in a LinAlgError (Hammerstein) or a model with an
    infinite MSE written with exit 0 (ARX)."""
    import numpy as np
    import pytest

    from blockid.data import Dataset
    from blockid.errors import DataError

    u = np.ones(50)
    u[7] = 1e300
    with pytest.raises(DataError, match=r"signal 'u' is 1e\+300 at sample 7.*rescale"):
        Dataset.from_arrays(u, np.ones(50), ["u"], ["y"])
