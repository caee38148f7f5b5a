"""The commands' data files and argument checks (cli/_data.py): the label of what was
read, the rate a model's data are read at, ranges, and the files read."""

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from blockid.cli._data import check_arguments, data_label, load_data, model_rate, select_range
from blockid.cli._flags import Reading
from blockid.data import Dataset
from blockid.errors import DataError, ParameterError


def test_the_data_label_names_the_files_and_the_range():
    assert data_label([Path("a.csv"), Path("b.csv")], "0:500") == "a.csv, b.csv [0:500]"
    assert data_label([Path("a.csv")], None) == "a.csv"


def test_data_are_read_at_the_model_s_rate_and_another_ts_is_refused():
    model = SimpleNamespace(sampling_time=0.1)
    assert model_rate(model, None, Path("m.json")) == 0.1
    assert model_rate(model, 0.1 + 1e-12, Path("m.json")) == pytest.approx(0.1)
    assert model_rate(SimpleNamespace(sampling_time=None), 0.5, Path("m.json")) == 0.5
    with pytest.raises(
        ParameterError,
        match=r"^--ts 0\.2 differs from the sampling time of m\.json, 0\.1 s: the model runs",
    ):
        model_rate(model, 0.2, Path("m.json"))


def test_a_range_selects_its_samples_and_none_keeps_them_all():
    data = Dataset.from_arrays(np.arange(10.0), np.arange(10.0), ["u"], ["y"])
    assert select_range(data, None, "--range") is data
    np.testing.assert_array_equal(
        select_range(data, "2:5", "--range").experiments[0].u[:, 0], [2, 3, 4]
    )
    with pytest.raises(ParameterError, match=r"^--range expects START:STOP .* '5:2' is empty"):
        select_range(data, "5:2", "--range")


def test_files_are_read_and_cut_to_the_range_after_the_checks(tmp_path):
    path = tmp_path / "d.csv"
    path.write_text("t,u,y\n" + "".join(f"{0.5 * k},{k},{2 * k}\n" for k in range(8)))
    data = load_data([path], ["u"], ["y"], Reading(time_column="t"), "1:4", "--estimation")
    assert data.sampling_time == 0.5
    np.testing.assert_array_equal(data.experiments[0].y[:, 0], [2, 4, 6])
    with pytest.raises(ParameterError, match=r"^--estimation expects START:STOP .* 'x' in '4:x'"):
        load_data([path], ["u"], ["y"], Reading(time_column="t"), "4:x", "--estimation")
    with pytest.raises(DataError, match="none.csv"):
        check_arguments([tmp_path / "none.csv"])
