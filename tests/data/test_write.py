"""Tests of the atomic writers write_table and write_text_atomic."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pyarrow as pa
import pytest

from blockid.data import write_table, write_text_atomic
from blockid.errors import DataError


@pytest.fixture
def frame():
    return pd.DataFrame({"u": [0.1, 0.2, 1 / 3], "y": [1e-300, -2.5, np.pi]})


def leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


@pytest.mark.parametrize("suffix", [".csv", ".tsv", ".parquet"])
def test_write_table_writes_every_format_exactly(tmp_path, frame, suffix):
    path = write_table(frame, tmp_path / f"out{suffix}")
    assert path == tmp_path / f"out{suffix}"
    if suffix == ".parquet":
        back = pd.read_parquet(path)
    else:
        back = pd.read_csv(path, sep="\t" if suffix == ".tsv" else ",")
    assert list(back.columns) == ["u", "y"]  # no index column
    np.testing.assert_array_equal(back.to_numpy(), frame.to_numpy())
    assert leftovers(tmp_path) == []


def test_write_table_refuses_to_overwrite(tmp_path, frame):
    path = tmp_path / "out.csv"
    path.write_text("precious\n")
    with pytest.raises(DataError) as info:
        write_table(frame, path)
    message = str(info.value)
    assert f"{path} already exists" in message and "overwrite=True" in message
    assert "overwrite=True" in message
    assert path.read_text() == "precious\n"
    assert leftovers(tmp_path) == []


def test_write_table_overwrites_when_asked(tmp_path, frame):
    path = tmp_path / "out.csv"
    path.write_text("old\n")
    write_table(frame, path, overwrite=True)
    np.testing.assert_array_equal(pd.read_csv(path).to_numpy(), frame.to_numpy())


def test_failed_write_leaves_old_file_and_no_temporary(tmp_path, frame, monkeypatch):
    path = tmp_path / "out.csv"
    path.write_text("old\n")

    def half_then_fail(self, handle, **kwargs):
        handle.write(b"u,y\n0.1,")  # a partial table reaches the temporary file
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(pd.DataFrame, "to_csv", half_then_fail)
    with pytest.raises(DataError, match=rf"could not write {path}: No space left on device"):
        write_table(frame, path, overwrite=True)
    assert path.read_text() == "old\n"
    assert leftovers(tmp_path) == []


def test_failed_write_of_new_file_leaves_nothing(tmp_path, frame, monkeypatch):
    def fail(self, handle, **kwargs):
        handle.write(b"partial")
        raise RuntimeError("writer crashed")

    monkeypatch.setattr(pd.DataFrame, "to_parquet", fail)
    with pytest.raises(RuntimeError, match="writer crashed"):
        write_table(frame, tmp_path / "new.parquet")
    assert list(tmp_path.iterdir()) == []


def test_unwritable_table_leaves_existing_file(tmp_path):
    path = tmp_path / "out.parquet"
    path.write_bytes(b"old")
    mixed = pd.DataFrame({"a": [1, "text", 2.5]})  # pyarrow cannot store mixed objects
    with pytest.raises(pa.ArrowException):
        write_table(mixed, path, overwrite=True)
    assert path.read_bytes() == b"old"
    assert leftovers(tmp_path) == []


def test_write_table_unknown_suffix(tmp_path, frame):
    with pytest.raises(DataError, match=r"unknown table type '.xlsx'; use one of .csv, .tsv"):
        write_table(frame, tmp_path / "out.xlsx")


def test_write_table_missing_folder(tmp_path, frame):
    with pytest.raises(DataError, match=r"folder .*nowhere does not exist"):
        write_table(frame, tmp_path / "nowhere" / "out.csv")


def test_write_table_onto_folder(tmp_path, frame):
    (tmp_path / "out.csv").mkdir()
    with pytest.raises(DataError, match="it is a folder"):
        write_table(frame, tmp_path / "out.csv", overwrite=True)


def test_write_text_atomic_round_trip_and_refusal(tmp_path):
    path = tmp_path / "model.json"
    text = json.dumps({"a": [0.5, -0.25], "name": "Ωmega"})
    assert write_text_atomic(text, path) == path
    assert json.loads(path.read_text(encoding="utf-8")) == {"a": [0.5, -0.25], "name": "Ωmega"}
    with pytest.raises(DataError, match="already exists; pass overwrite=True"):
        write_text_atomic("{}", path)
    assert json.loads(path.read_text(encoding="utf-8"))["a"] == [0.5, -0.25]
    write_text_atomic("{}", path, overwrite=True)
    assert path.read_text(encoding="utf-8") == "{}"
    assert leftovers(tmp_path) == []


def test_written_file_has_the_permissions_of_a_plain_open(tmp_path, frame):
    path = write_table(frame, tmp_path / "out.csv")
    plain = tmp_path / "plain.csv"
    plain.write_text("x")
    assert path.stat().st_mode == plain.stat().st_mode  # not the 0600 of a mkstemp file


def test_a_symbolic_link_is_kept_and_its_target_written(tmp_path):
    """Issue 21: ``-o link.py --force`` replaced the link with a file."""
    target = tmp_path / "real.json"
    target.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    write_text_atomic("new", link, overwrite=True)
    assert link.is_symlink() and target.read_text() == "new"


def test_devices_and_pipes_are_written_through_not_replaced(tmp_path):
    """Issue 21: ``-o /dev/full --force`` replaced the device with a regular file, and
    ``-o /dev/stdout`` was refused as existing."""
    import os
    import stat
    import threading

    from blockid.data.io import is_stream

    assert is_stream("/dev/null") and not is_stream(tmp_path) and not is_stream(tmp_path / "no")
    write_text_atomic("ignored", "/dev/null")  # no --force needed: nothing is replaced
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)
    if os.path.exists("/dev/full"):
        with pytest.raises(DataError, match="could not write /dev/full: No space left"):
            write_text_atomic("x" * 10_000, "/dev/full", overwrite=True)
        assert stat.S_ISCHR(os.stat("/dev/full").st_mode)
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(open(fifo).read()))  # noqa: SIM115
    reader.start()
    write_text_atomic("through the pipe", fifo)
    reader.join(timeout=10)
    assert got == ["through the pipe"] and stat.S_ISFIFO(os.stat(fifo).st_mode)
