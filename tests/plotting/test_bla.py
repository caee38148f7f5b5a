"""The figure of a measured BLA: what it draws, on what data it says it is made."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from blockid.data import Dataset, Experiment
from blockid.design import multisine
from blockid.errors import DataError
from blockid.evaluation import best_linear_approximation
from blockid.plotting.bla import BLA_FIGURE, bla_figure, plot_bla


def _data(odd: bool, periodic: bool = True) -> Dataset:
    rng = np.random.default_rng(1)
    x = multisine(256, sampling_time=0.01, f_max=30, odd=odd, periods=3, realisations=3, seed=2)
    exps = []
    for m, u in enumerate(x.signals):
        u = u if periodic else rng.standard_normal(u.size)
        v = signal.lfilter(*signal.butter(2, 0.4), u)
        exps.append(Experiment(f"r{m}", u, v + 0.2 * v**3 + 0.01 * rng.standard_normal(u.size)))
    return Dataset(("u",), ("y",), 0.01, exps, source="rig.csv")


def _labels(fig) -> list[str]:
    return [t.get_text() for t in fig.axes[0].get_legend().get_texts()]


def test_the_robust_figure_draws_the_bla_its_levels_and_the_empty_lines():
    bla = best_linear_approximation(_data(odd=True), transient_periods=1)
    fig = plot_bla(bla)
    labels = _labels(fig)
    for label in ("BLA |G|", "std of G (noise + distortion)", "std of G from noise",
                  "distortion (total - noise)", "even lines (even distortion + noise)",
                  "odd non-excited lines (odd distortion + noise)"):  # fmt: skip
        assert label in labels, labels
    title = fig.axes[0].get_title().replace("\n", " ")
    assert "on rig.csv" in title and "3 realisation(s) x 2 period(s)" in title
    assert "dominates the noise" in title
    line = fig.axes[0].get_lines()[0]  # |G| in dB at the excited lines
    np.testing.assert_allclose(line.get_ydata(), 20 * np.log10(np.abs(bla.g)))


def test_the_welch_figure_adds_the_coherence():
    bla = best_linear_approximation(_data(odd=False, periodic=False))
    fig = bla.plot()
    assert len(fig.axes) == 2 and fig.axes[1].get_ylabel() == "coherence γ²"
    assert "std of G (1 - coherence)" in _labels(fig) and "Welch" in fig.axes[0].get_title()


def test_the_figure_is_written_once_unless_replaced(tmp_path):
    bla = best_linear_approximation(_data(odd=False), transient_periods=1)
    path = bla_figure(bla, tmp_path / "figs")
    assert path == tmp_path / "figs" / BLA_FIGURE and path.stat().st_size > 10_000
    with pytest.raises(DataError, match="exists; pass --force"):
        bla_figure(bla, tmp_path / "figs")
    assert bla_figure(bla, tmp_path / "figs", overwrite=True) == path
