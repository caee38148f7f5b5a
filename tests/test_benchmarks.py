"""The benchmark scripts still run against the code they measure.

They live outside the package and nothing else imports them, so a renamed module or
function breaks them silently until the next benchmark run (``bench_state_space.py``'s
profile read the state-space refinement from its old module for a session). These tests
import every script and run the cheapest path through the ones that reach into
internals; the measurements themselves stay in ``benchmarks/``.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"
SCRIPTS = sorted(BENCHMARKS.glob("*.py")) + sorted((BENCHMARKS / "real").glob("*.py"))


def _load(path: Path):
    for folder in (path.parent, BENCHMARKS):
        if str(folder) not in sys.path:
            sys.path.insert(0, str(folder))
    name = f"_bench_{path.parent.name}_{path.stem}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look their module up while it loads
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("path", SCRIPTS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_every_benchmark_script_imports(path):
    module = _load(path)
    if not path.name.startswith("_") and path.parent == BENCHMARKS:
        assert callable(getattr(module, "main", None)), f"{path.name} has no main()"


def test_state_space_profile_runs_on_a_short_record():
    bench = _load(BENCHMARKS / "bench_state_space.py")
    n = 2 * bench.CHUNK + 100
    rng = np.random.default_rng(1)
    u = rng.uniform(-1, 1, n)
    y = bench.plant().simulate(u)[:, 0]
    out = bench.profile(u[:, None], y[:, None])
    assert out["parameters"] == 845
    for threads in (1, 2):
        assert all(seconds > 0 for seconds in out[threads].values())
    assert out["whole 1"] > 0 and out["whole 2"] > 0


def test_tanks_study_records_are_the_documented_plant():
    """The study's records (``docs/identify.md``): the same per seed, two different
    multisine realisations, levels in the tanks' range, and the upper tank overflowing
    in some samples (the nonlinearity the study is about)."""
    study = _load(BENCHMARKS / "tanks_study.py")
    ue, ye, ut, yt = study.records(1)
    again = study.records(1)
    assert all(np.array_equal(a, b) for a, b in zip((ue, ye, ut, yt), again, strict=True))
    assert ue.shape == ye.shape == ut.shape == yt.shape == (study.N,)
    assert not np.allclose(ue, ut)
    assert 0.0 <= ue.min() and ue.max() <= 10.0
    assert 0.5 < ye.min() and ye.max() < 10.5  # the lower level, measured with noise
    upper = study.upper_levels(ue)
    full = upper >= 9.95  # at the brim (process noise moves it by about 0.01)
    assert 0.0 < np.mean(full) < 0.2  # it overflows, now and then
