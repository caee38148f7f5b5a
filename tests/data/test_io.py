"""Tests of blockid.data.io.read_data: formats, round trips and malformed files."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import scipy.io

from blockid.data import read_data, write_table
from blockid.errors import DataError

from reference import write


@pytest.fixture
def table(rng):
    n = 50
    return pd.DataFrame(
        {
            "time": 0.05 * np.arange(n),
            "u1": rng.standard_normal(n),
            "u2": rng.uniform(-1e6, 1e6, n),
            "y1": rng.standard_normal(n) * 1e-9,
        }
    )


def assert_same(data, table, rows=slice(None)):
    exp = data.experiments[0]
    np.testing.assert_array_equal(exp.u, table[["u1", "u2"]].to_numpy()[rows])
    np.testing.assert_array_equal(exp.y, table[["y1"]].to_numpy()[rows])


# ------------------------------------------------------------------ round trips
@pytest.mark.parametrize("suffix", [".csv", ".tsv", ".parquet"])
def test_table_round_trip_is_exact(tmp_path, table, suffix):
    path = write_table(table, tmp_path / f"run1{suffix}")
    data = read_data(path, ["u1", "u2"], ["y1"], time_column="time")
    assert data.inputs == ("u1", "u2") and data.outputs == ("y1",)
    assert data.sampling_time == pytest.approx(0.05, rel=1e-12)
    assert [e.name for e in data.experiments] == ["run1"]
    assert data.source == str(path)
    assert_same(data, table)


def test_mat_round_trip_vectors(tmp_path, table):
    path = tmp_path / "plant.mat"
    # a row vector, a column vector and a 1-D vector all mean one experiment
    scipy.io.savemat(
        path,
        {
            "u1": table["u1"].to_numpy()[None, :],
            "u2": table["u2"].to_numpy()[:, None],
            "y1": table["y1"].to_numpy(),
            "time": table["time"].to_numpy(),
        },
        oned_as="row",
    )
    data = read_data(path, ["u1", "u2"], ["y1"], time_column="time")
    assert [e.name for e in data.experiments] == ["plant"]
    assert data.sampling_time == pytest.approx(0.05, rel=1e-12)
    assert_same(data, table)


def test_mat_matrix_gives_one_experiment_per_column(tmp_path, rng):
    u, y = rng.standard_normal((40, 3)), rng.standard_normal((40, 3))
    path = tmp_path / "runs.mat"
    scipy.io.savemat(path, {"u": u, "y": y, "t": 0.1 * np.arange(40)})
    data = read_data(path, ["u"], ["y"], time_column="t")
    assert [e.name for e in data.experiments] == ["runs column 1", "runs column 2", "runs column 3"]
    assert data.sampling_time == pytest.approx(0.1)
    for j, exp in enumerate(data.experiments):
        np.testing.assert_array_equal(exp.u[:, 0], u[:, j])
        np.testing.assert_array_equal(exp.y[:, 0], y[:, j])


def test_integer_and_logical_mat_variables_are_read(tmp_path):
    path = tmp_path / "ints.mat"
    scipy.io.savemat(path, {"u": np.arange(5, dtype=np.int16), "y": np.array([1, 0, 1, 1, 0]) > 0})
    data = read_data(path, ["u"], ["y"])
    np.testing.assert_array_equal(data.experiments[0].y[:, 0], [1.0, 0.0, 1.0, 1.0, 0.0])


def test_experiment_column_in_csv(tmp_path):
    path = write(tmp_path / "log.csv", "batch,u,y\nA,1,10\nA,2,20\nB,3,30\nB,4,40\nB,5,50\n")
    data = read_data(path, ["u"], ["y"], experiment_column="batch")
    assert [e.name for e in data.experiments] == ["A", "B"]
    np.testing.assert_array_equal(data.signal("y")[1], [30.0, 40.0, 50.0])


def test_several_files_become_experiments_named_by_stem(tmp_path, table):
    first = write_table(table.iloc[:30], tmp_path / "day1.csv")
    second = write_table(table.iloc[30:], tmp_path / "day2.parquet")
    data = read_data([first, second], ["u1", "u2"], ["y1"], sampling_time=0.05)
    assert [e.name for e in data.experiments] == ["day1", "day2"]
    assert [e.n_samples for e in data.experiments] == [30, 20]
    assert data.source == f"{first}, {second}"
    np.testing.assert_array_equal(data.signal("u1")[1], table["u1"].to_numpy()[30:])


def test_several_files_with_experiment_column_prefix_the_stem(tmp_path):
    a = write(tmp_path / "a.csv", "k,u,y\n1,1,1\n1,2,2\n2,3,3\n2,4,4\n")
    b = write(tmp_path / "b.csv", "k,u,y\n1,1,1\n1,2,2\n")
    data = read_data([a, b], ["u"], ["y"], experiment_column="k")
    assert [e.name for e in data.experiments] == ["a/1", "a/2", "b/1"]


def test_same_stem_in_two_folders_uses_the_paths(tmp_path, table):
    (tmp_path / "x").mkdir()
    (tmp_path / "z").mkdir()
    one = write_table(table, tmp_path / "x" / "run.csv")
    two = write_table(table, tmp_path / "z" / "run.csv")
    data = read_data([one, two], ["u1", "u2"], ["y1"])
    assert [e.name for e in data.experiments] == [str(one), str(two)]


def test_files_with_different_sampling_times_rejected(tmp_path):
    a = write(tmp_path / "a.csv", "t,u,y\n0,1,1\n1,2,2\n2,3,3\n")
    b = write(tmp_path / "b.csv", "t,u,y\n0,1,1\n2,2,2\n4,3,3\n")
    with pytest.raises(DataError) as info:
        read_data([a, b], ["u"], ["y"], time_column="t")
    message = str(info.value)
    assert f"{a} has sampling time 1 but {b} has 2" in message


def test_same_file_twice_rejected(tmp_path, table):
    path = write_table(table, tmp_path / "run.csv")
    with pytest.raises(DataError, match="is listed twice"):
        read_data([path, str(path)], ["u1"], ["y1"])


# ------------------------------------------------------------------ delimiters
def test_semicolon_delimiter_is_sniffed(tmp_path):
    path = write(tmp_path / "eu.csv", "u;y\n1.5;2\n2.5;3\n")
    np.testing.assert_array_equal(read_data(path, ["u"], ["y"]).signal("u")[0], [1.5, 2.5])


def test_delimiter_of_wide_rows_when_the_sniffed_bytes_end_inside_a_row(tmp_path):
    """Rows so wide that the sniffed first 64 KiB end one field into a row: the cut line
    holds no delimiter and must not outvote the whole ones (it did: a tab-separated
    ``.csv`` was read as one comma-separated column)."""
    from blockid.data.io import _SNIFF_BYTES

    values = "\t".join(["0.25"] * 300)
    row = "1.5\t" + values + "\n"  # first field '1.5', then the tab
    for pad in range(len(row)):
        header = "u\ty\t" + "\t".join(f"c{k}" for k in range(299)) + "x" * pad + "\n"
        if 1 <= (_SNIFF_BYTES - len(header)) % len(row) <= 3:  # the cut falls in '1.5'
            break
    path = write(tmp_path / "wide.csv", header + row * (2 * _SNIFF_BYTES // len(row)))
    data = read_data(path, ["u"], ["y"])
    np.testing.assert_array_equal(data.signal("y")[0][:3], [0.25, 0.25, 0.25])


def test_decimal_comma_gets_a_hint(tmp_path):
    path = write(tmp_path / "eu.csv", "u;y\n1,5;2\n2,5;3\n")
    with pytest.raises(DataError) as info:
        read_data(path, ["u"], ["y"])
    message = str(info.value)
    assert "column 'u', data row 1 (line 2): '1,5' is not a number" in message
    assert "decimal comma" in message


def test_whitespace_separated_txt(tmp_path):
    path = write(tmp_path / "plain.txt", "t   u    y\n0.0  1.0  -1\n0.5  2.0  -2\n1.0  3.0  -3\n")
    data = read_data(path, ["u"], ["y"], time_column="t")
    assert data.sampling_time == 0.5
    np.testing.assert_array_equal(data.signal("y")[0], [-1.0, -2.0, -3.0])


def test_tab_separated_tsv_with_padded_header(tmp_path):
    path = write(tmp_path / "data.tsv", " u \t y\n1\t2\n3\t4\n")
    np.testing.assert_array_equal(read_data(path, ["u"], ["y"]).signal("y")[0], [2.0, 4.0])


def test_quoted_header_and_trailing_delimiter(tmp_path):
    path = write(tmp_path / "bench.csv", '"V1","V2",\n0.5,1.5,\n0.25,2.5,\n')
    data = read_data(path, ["V1"], ["V2"])
    np.testing.assert_array_equal(data.signal("V1")[0], [0.5, 0.25])


def test_unused_columns_may_hold_anything(tmp_path):
    path = write(tmp_path / "mixed.csv", "note,u,y\nhello,1,2\n,3,4\n")
    np.testing.assert_array_equal(read_data(path, ["u"], ["y"]).signal("u")[0], [1.0, 3.0])


def test_blank_lines_only_file_is_empty(tmp_path):
    path = write(tmp_path / "blank.csv", "\n\n  \n")
    with pytest.raises(DataError, match=rf"{path} is empty"):
        read_data(path, ["u"], ["y"])


def test_header_but_no_rows(tmp_path):
    path = write(tmp_path / "head.csv", "u,y\n")
    with pytest.raises(DataError, match=rf"^{path} has a header but no data rows$"):
        read_data(path, ["u"], ["y"])


def test_parquet_without_rows(tmp_path):
    path = write_table(pd.DataFrame({"u": [], "y": []}), tmp_path / "none.parquet")
    with pytest.raises(DataError, match=rf"^{path} has columns but no data rows$"):
        read_data(path, ["u"], ["y"])


def test_missing_column_in_csv_lists_columns(tmp_path):
    path = write(tmp_path / "p.csv", "time,valve_cmd,pressure\n0,1,2\n")
    with pytest.raises(DataError) as info:
        read_data(path, ["valve_command"], ["pressure"])
    message = str(info.value)
    assert message.startswith(f"{path}: no column 'valve_command' (did you mean 'valve_cmd'?)")
    assert "available columns: 'time', 'valve_cmd', 'pressure'" in message


def test_headerless_file_gets_a_hint(tmp_path):
    path = write(tmp_path / "raw.csv", "0.1,0.2\n0.3,0.4\n")
    with pytest.raises(DataError, match="the first line is read as the header"):
        read_data(path, ["u"], ["y"])


def test_non_numeric_cell_names_file_column_row_line_and_value(tmp_path):
    # a blank line before the bad row: the file line differs from the data row
    path = write(tmp_path / "bad.csv", "u,y\n1,2\n\n3,4\n5,oops\n")
    with pytest.raises(DataError) as info:
        read_data(path, ["u"], ["y"])
    message = str(info.value)
    assert message.startswith(f"{path}: column 'y', data row 3 (line 5): 'oops' is not a number")


def test_empty_cell_names_file_column_row_and_line(tmp_path):
    path = write(tmp_path / "gap.csv", "u,y\n1,2\n3,\n5,6\n")
    with pytest.raises(DataError) as info:
        read_data(path, ["u"], ["y"])
    message = str(info.value)
    assert message.startswith(f"{path}: column 'y', data row 2 (line 3) is empty")
    assert "remove that row or fill the gap" in message


def test_nan_literal_cell_shows_the_text(tmp_path):
    path = write(tmp_path / "na.csv", "u,y\n1,2\nNA,4\n")
    with pytest.raises(
        DataError, match=r"column 'u', data row 2 \(line 3\) has a missing value \('NA'\)"
    ):
        read_data(path, ["u"], ["y"])


def test_infinite_cell_in_csv(tmp_path):
    path = write(tmp_path / "inf.csv", "u,y\n1,2\n3,-inf\n")
    with pytest.raises(
        DataError, match=r"column 'y', data row 2 \(line 3\) is infinite \('-inf'\)"
    ):
        read_data(path, ["u"], ["y"])


def test_non_uniform_time_in_csv_names_lines(tmp_path):
    path = write(tmp_path / "t.csv", "t,u,y\n0,1,1\n1,1,1\n2,1,1\n3.5,1,1\n4.5,1,1\n")
    with pytest.raises(DataError) as info:
        read_data(path, ["u"], ["y"], time_column="t")
    message = str(info.value)
    assert "time column 't' is not uniformly sampled" in message
    assert "data rows 3 and 4 (lines 4 and 5) is 1.5 but the median step is 1" in message


def test_ragged_csv_is_reported_with_file(tmp_path):
    path = write(tmp_path / "ragged.csv", "u,y\n1,2\n3,4,5,6\n")
    with pytest.raises(DataError, match=rf"^{path} could not be parsed.*line 3, saw 4"):
        read_data(path, ["u"], ["y"])


def test_short_row_is_an_empty_cell(tmp_path):
    path = write(tmp_path / "short.csv", "u,y\n1,2\n3\n")
    with pytest.raises(DataError, match=r"column 'y', data row 2 \(line 3\) is empty"):
        read_data(path, ["u"], ["y"])


def test_every_row_one_field_longer_than_header_is_not_shifted(tmp_path):
    # pandas would otherwise make the first column the index and shift u and y
    path = write(tmp_path / "wide.csv", "u,y\n1,2,3\n4,5,6\n")
    with pytest.raises(
        DataError, match=rf"^{path}: line 2 has 3 fields but the header names only 2"
    ):
        read_data(path, ["u"], ["y"])


def test_trailing_delimiter_on_data_rows_only(tmp_path):
    path = write(tmp_path / "trail.csv", "u,y\n1,2,\n4,5,\n")
    np.testing.assert_array_equal(read_data(path, ["u"], ["y"]).signal("y")[0], [2.0, 5.0])


def test_corrupt_parquet(tmp_path):
    path = tmp_path / "broken.parquet"
    path.write_bytes(b"definitely not parquet")
    with pytest.raises(DataError, match=rf"^{path} is not a readable Parquet file"):
        read_data(path, ["u"], ["y"])


def test_missing_parquet_column(tmp_path, table):
    path = write_table(table, tmp_path / "t.parquet")
    with pytest.raises(DataError, match=rf"^{path}: no column 'U1' \(did you mean 'u1'"):
        read_data(path, ["U1"], ["y1"])


def test_non_numeric_parquet_cell(tmp_path):
    path = write_table(pd.DataFrame({"u": ["1", "x"], "y": [1.0, 2.0]}), tmp_path / "s.parquet")
    with pytest.raises(DataError, match=rf"^{path}: column 'u', data row 2: 'x' is not a number"):
        read_data(path, ["u"], ["y"])


# .mat ---------------------------------------------------------------------------------
def test_mat_v73_explains_how_to_resave(tmp_path):
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5"
    path = tmp_path / "new.mat"
    path.write_bytes(header.ljust(116) + bytes(8) + b"\x00\x02IM" + bytes(384))
    with pytest.raises(DataError) as info:
        read_data(path, ["u"], ["y"])
    message = str(info.value)
    assert message.startswith(f"{path} is a MATLAB v7.3 (HDF5) file")
    assert "save(filename, ..., '-v7')" in message and "CSV" in message


def test_mat_different_lengths(tmp_path):
    path = tmp_path / "lens.mat"
    scipy.io.savemat(path, {"u": np.zeros((100, 1)), "y": np.zeros((99, 1))})
    with pytest.raises(DataError) as info:
        read_data(path, ["u"], ["y"])
    message = str(info.value)
    assert message.startswith(f"{path}: variables have different shapes")
    assert "'u' is 100 x 1, 'y' is 99 x 1" in message


def test_mat_missing_variable_lists_variables(tmp_path):
    path = tmp_path / "vars.mat"
    scipy.io.savemat(path, {"force": np.zeros(5), "disp": np.zeros(5)})
    with pytest.raises(DataError) as info:
        read_data(path, ["forces"], ["disp"])
    message = str(info.value)
    assert message.startswith(f"{path}: no variable 'forces' (did you mean 'force'?)")
    assert "available variables:" in message and "'disp'" in message


def test_mat_nan_names_variable_and_sample(tmp_path):
    y = np.ones((6, 2))
    y[4, 1] = np.nan
    path = tmp_path / "gaps.mat"
    scipy.io.savemat(path, {"u": np.zeros((6, 2)), "y": y})
    with pytest.raises(
        DataError, match=r"gaps.mat \(column 2\): variable 'y', sample 5 has a missing"
    ):
        read_data(path, ["u"], ["y"])


def test_mat_text_variable_rejected(tmp_path):
    path = tmp_path / "text.mat"
    scipy.io.savemat(path, {"u": "hello", "y": np.zeros(5)})
    with pytest.raises(DataError, match=r"variable 'u' is a char array, not a real numeric"):
        read_data(path, ["u"], ["y"])


def test_mat_complex_variable_rejected(tmp_path):
    path = tmp_path / "cplx.mat"
    scipy.io.savemat(path, {"u": np.ones(5) * 1j, "y": np.zeros(5)})
    with pytest.raises(DataError, match=r"variable 'u' is a complex array"):
        read_data(path, ["u"], ["y"])


def test_not_a_mat_file(tmp_path):
    path = tmp_path / "fake.mat"
    path.write_bytes(b"\x00\x01" * 200)
    with pytest.raises(DataError, match=rf"^{path}"):
        read_data(path, ["u"], ["y"])


def test_a_huge_value_in_a_file_names_the_row_and_a_folder_is_not_a_type(tmp_path):
    import pytest

    from blockid.data import read_data
    from blockid.errors import DataError

    path = tmp_path / "d.csv"
    path.write_text("u,y\n1,2\n3,1e300\n")
    with pytest.raises(DataError, match=r"'y', data row 2 \(line 3\): 1e\+300 is too large"):
        read_data(path, ["u"], ["y"])
    with pytest.raises(DataError, match="is a folder, not a data file; name the files in it"):
        read_data(tmp_path, ["u"], ["y"])


def test_a_latin1_header_is_read_as_the_user_typed_it(tmp_path):
    """Issue 21: a Latin-1 header gave ``did you mean 'courant_\\ufffd'``."""
    from blockid.data import read_data

    path = tmp_path / "latin.csv"
    path.write_bytes("courant_é,vitesse\n1,2\n2,3\n3,5\n".encode("latin-1"))
    data = read_data(path, ["courant_é"], ["vitesse"])
    assert data.inputs == ("courant_é",) and data.n_samples == 3
