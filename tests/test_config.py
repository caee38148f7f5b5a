"""blockid.config: the fits' memory and work-partition sizes, read when a fit runs."""

from __future__ import annotations

import numpy as np
import pytest

import blockid
from blockid.config import SETTINGS, config_context, get_config, set_config
from blockid.data import Dataset


def test_the_defaults_are_the_documented_sizes():
    """The table in docs/performance.md states every size with its default and unit."""
    from pathlib import Path

    doc = (Path(blockid.__file__).parents[2] / "docs" / "performance.md").read_text()
    section = doc[doc.index("## Memory and work-partition sizes") :]
    section = section[: section.index("\n## ", 3)]
    assert get_config() == {name: s.default for name, s in SETTINGS.items()}
    for name, s in SETTINGS.items():
        assert f"| `{name}` | {s.default:,} | {s.unit} |" in section, name


def test_a_context_sets_and_restores_every_size_even_on_an_error():
    before = get_config()
    with pytest.raises(RuntimeError, match="inside"):
        with config_context(regressor_rows=5, tile_columns=3):
            assert get_config() == {**before, "regressor_rows": 5, "tile_columns": 3}
            with config_context(regressor_rows=9):
                assert get_config()["regressor_rows"] == 9
            assert get_config()["regressor_rows"] == 5
            raise RuntimeError("inside")
    assert get_config() == before


def test_set_config_holds_for_later_calls():
    with config_context():  # restores what set_config changes inside it
        set_config(history_rows=np.int64(7))
        assert get_config()["history_rows"] == 7
        assert type(get_config()["history_rows"]) is int
        assert blockid.get_config() == get_config()  # exported lazily from the package
    assert get_config()["history_rows"] == SETTINGS["history_rows"].default


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({"tile_columns": 0}, r"tile_columns=0 must be a whole number >= 1 \(columns\)"),
        ({"regressor_rows": 2.0}, r"regressor_rows=2.0 must be a whole number >= 1 \(rows\)"),
        ({"history_rows": True}, r"history_rows=True must be a whole number >= 1"),
        ({"jacobian_bytes": -1}, r"jacobian_bytes=-1 must be a whole number >= 0 \(bytes\)"),
        ({"chunk": 10}, r"'chunk' is not a blockid setting; choose one of regressor_rows, "),
    ],
)
def test_a_bad_size_is_refused_naming_it_and_changes_nothing(values, message):
    before = get_config()
    with pytest.raises(ValueError, match=message):
        set_config(**{"sensitivity_rows": 3, **values})  # the good value not set either
    with pytest.raises(ValueError, match=message):
        with config_context(**values):
            pass  # pragma: no cover - never entered
    assert get_config() == before


def test_the_sizes_go_with_each_task_to_the_workers():
    """identify's worker processes fit under the sizes set where the search runs (they
    fix the sums, so one worker or two give the same model only if both see them)."""
    from blockid.workflows.parallel import TaskRunner

    def _sizes_seen(data: Dataset, item: int) -> tuple[int, dict[str, int]]:
        from blockid.config import get_config  # (sent by value: runs in the worker)

        return item, get_config()

    data = Dataset.from_arrays(np.zeros(20), np.zeros(20))
    with config_context(tile_columns=16, regressor_rows=100), TaskRunner(data, 2) as pool:
        seen = pool.map(_sizes_seen, [0, 1, 2])
    expected = {**get_config(), "tile_columns": 16, "regressor_rows": 100}
    assert seen == [(i, expected) for i in range(3)]
    with TaskRunner(data, 2) as pool:  # and without a setting, the defaults again
        assert pool.map(_sizes_seen, [0]) == [(0, get_config())]
