"""Checks on file paths before any numerical library (data/files.py): data files that
are missing, folders, of an unknown type, empty or listed twice, and tables to write."""

from __future__ import annotations

import pytest

from blockid.data import read_data
from blockid.data.files import check_data_paths, check_table_target
from blockid.errors import DataError

from reference import write


# ------------------------------------------------------------------ malformed input
def test_missing_file_is_a_data_error_with_suggestion(tmp_path):
    write(tmp_path / "plant.csv", "u,y\n1,2\n")
    with pytest.raises(DataError) as info:
        read_data(tmp_path / "plnt.csv", ["u"], ["y"])
    message = str(info.value)
    assert f"{tmp_path / 'plnt.csv'} does not exist" in message
    assert "did you mean 'plant.csv'?" in message


def test_missing_folder(tmp_path):
    with pytest.raises(DataError, match="does not exist .no folder"):
        read_data(tmp_path / "nowhere" / "a.csv", ["u"], ["y"])


def test_folder_instead_of_file(tmp_path):
    (tmp_path / "d.csv").mkdir()
    with pytest.raises(DataError, match=r"d.csv is a folder, not a data file"):
        read_data(tmp_path / "d.csv", ["u"], ["y"])


def test_unknown_suffix_lists_supported(tmp_path):
    path = write(tmp_path / "data.xlsx", "x")
    with pytest.raises(DataError) as info:
        read_data(path, ["u"], ["y"])
    message = str(info.value)
    assert str(path) in message and "'.xlsx'" in message
    assert "supported: .csv, .tsv, .txt, .parquet, .mat" in message


def test_no_paths():
    with pytest.raises(DataError, match="no data file given"):
        read_data([], ["u"], ["y"])


@pytest.mark.parametrize("suffix", [".csv", ".parquet", ".mat"])
def test_zero_byte_file_is_empty(tmp_path, suffix):
    path = tmp_path / f"blank{suffix}"
    path.write_bytes(b"")
    with pytest.raises(DataError, match=rf"^{path} is empty$"):
        read_data(path, ["u"], ["y"])


def test_a_file_listed_twice_through_a_link_is_named_as_given(tmp_path):
    data = write(tmp_path / "a.csv", "u,y\n1,2\n")
    (tmp_path / "b.csv").symlink_to(data)
    assert check_data_paths(data) == [str(data)]
    with pytest.raises(DataError, match=rf"^{tmp_path / 'b.csv'} is listed twice; give each"):
        check_data_paths([data, tmp_path / "b.csv"])


def test_a_table_to_write_needs_a_known_suffix():
    assert check_table_target("out.PARQUET") == ".parquet"
    with pytest.raises(
        DataError,
        match=r"^cannot write out: unknown table type '\(no suffix\)'; use one of .csv, .tsv, .parquet$",
    ):
        check_table_target("out")
