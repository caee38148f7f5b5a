"""Tests of blockid.plotting.notebook through the models' and fits' hooks: the HTML a
notebook shows (parsed, not matched as text) and the figures ``.plot()`` returns."""

import base64
import subprocess
import sys
from html.parser import HTMLParser

import numpy as np
import pytest
from matplotlib.figure import Figure

from blockid.errors import ParameterError
from blockid.fitting import fit_model


class Page(HTMLParser):
    """Text, tables (rows of cell texts) and image sources of an HTML fragment."""

    def __init__(self, html: str) -> None:
        super().__init__()
        self.text: list[str] = []
        self.tables: list[list[list[str]]] = []
        self.images: list[str] = []
        self._cell: list[str] | None = None
        self.feed(html)
        self.close()

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables.append([])
        elif tag == "tr":
            self.tables[-1].append([])
        elif tag in ("td", "th"):
            self._cell = []
        elif tag == "img":
            self.images.append(dict(attrs)["src"])

    def handle_endtag(self, tag):
        if tag in ("td", "th"):
            self.tables[-1][-1].append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data):
        self.text.append(data)
        if self._cell is not None:
            self._cell.append(data)

    @property
    def all_text(self) -> str:
        return " ".join(" ".join(self.text).split())


def _png(src: str) -> bytes:
    head = "data:image/png;base64,"
    assert src.startswith(head)
    raw = base64.b64decode(src[len(head) :], validate=True)
    assert raw[:8] == b"\x89PNG\r\n\x1a\n" and raw[-8:-4] == b"IEND"
    return raw


def test_a_fit_shows_its_structure_parameters_errors_scores_and_curves(hammerstein_fit):
    fit, _, _ = hammerstein_fit
    page = Page(fit._repr_html_())
    text = page.all_text
    assert "hammerstein model" in text and "u → y; sampling time 0.1 s" in text
    assert "two-segment polynomial → linear (na=2, nb=2, nk=1)" in text
    mode = fit.estimation_metrics["fit_percent"]["y"]
    assert f"Fitted by {fit.method} on {fit.n_samples} samples" in text
    assert f"fit {mode:.1f} %" in text
    (params,) = page.tables
    assert params[0] == ["parameter", "value", "standard error", "relative SE [%]"]
    names = [row[0] for row in params[1:]]
    assert names == fit.model.free_parameter_names()
    values = np.array([float(row[1]) for row in params[1:]])
    np.testing.assert_allclose(values, fit.model.free_parameters(), rtol=1e-5, atol=1e-12)
    errors = np.array([float(row[2]) for row in params[1:]])
    cov = np.array(fit.settings["covariance"]["matrix"], float)
    np.testing.assert_allclose(errors, np.sqrt(np.diag(cov)), rtol=1e-5)
    assert "linear block: static gain" in text
    gain = fit.model.linear.static_gain()
    assert f"static gain {gain:.4g}" in text
    (thumb,) = page.images
    assert len(_png(thumb)) > 3000
    assert "…" not in text and "TwoSegmentPolynomial" not in text


def test_a_model_shows_itself_without_errors(hammerstein_fit):
    model = hammerstein_fit[0].model
    page = Page(model._repr_html_())
    assert "No standard errors" in page.all_text
    assert [row[2] for row in page.tables[0][1:]] == ["n/a"] * model.free_parameters().size


def test_plot_returns_the_report_figures(hammerstein_fit):
    fit, _, val = hammerstein_fit
    figures = fit.plot(val)
    assert list(figures) == ["output", "blocks", "linear"]
    assert all(isinstance(f, Figure) for f in figures.values())
    assert "95 % band" in [t.get_text() for t in figures["output"].legends[0].get_texts()]
    assert list(fit.model.plot()) == ["blocks", "linear"]  # no data: no output figure
    linear = fit.plot(which="linear")
    assert isinstance(linear, Figure) and len(linear.axes) == 4
    with pytest.raises(ParameterError, match="no 'output' figure: no data were given"):
        fit.plot(which="output")
    with pytest.raises(ParameterError, match="choose one of output, blocks"):
        fit.plot(which="bode")


def test_an_arx_fit_has_no_blocks_but_its_dynamics(hammerstein_fit):
    _, est, val = hammerstein_fit
    fit = fit_model(est, "arx", na=2, nb=2, nk=1)
    assert list(fit.plot(val)) == ["output", "linear"]
    page = Page(fit._repr_html_())
    assert page.images == []
    assert "y / u: static gain" in page.all_text


def test_a_block_model_of_several_channels_shows_each_block_its_deviation_and_band():
    """A block state space's blocks as a chain's: the curve and its deviation from the
    best straight line, each with its 95 % band (the fit carries a covariance), and
    curves in the notebook summary (they once had neither, and no summary curves)."""
    from reference import mimo_hw_record

    data, _ = mimo_hw_record(n=600)
    fit = fit_model(data, "block-state-space", nx=3, input_block="polynomial",
                    output_block={"y2": "polynomial"}, standard_errors=True)  # fmt: skip
    figures = fit.plot(data)
    assert list(figures) == ["output", "blocks", "linear"]
    axes = figures["blocks"].axes
    titles = [ax.get_title() for ax in axes]
    assert titles[0::2] == ["input block on u1 (polynomial)", "input block on u2 (polynomial)",
                            "output block on y2 (polynomial)"]  # fmt: skip
    assert all(t.startswith("deviation from the best straight line") for t in titles[1::2])
    curves = fit.model.static_curves(np.vstack([x.u for x in data.experiments]))
    for curve_ax, deviation_ax, c in zip(axes[0::2], axes[1::2], curves, strict=True):
        np.testing.assert_allclose(curve_ax.lines[0].get_ydata(), c["y"])
        line = np.polyval(np.polyfit(c["grid"], c["y"], 1), c["grid"])
        np.testing.assert_allclose(deviation_ax.lines[0].get_ydata(), c["y"] - line, atol=1e-9)
        assert len(curve_ax.collections) == len(deviation_ax.collections) == 1  # the bands
    legend = [t.get_text() for t in figures["blocks"].legends[0].get_texts()]
    assert "95 % band" in legend
    # without data: over the ranges recorded in estimation, in the summary too
    assert list(fit.model.plot()) == ["blocks", "linear"]
    (thumb,) = Page(fit._repr_html_()).images
    assert len(_png(thumb)) > 3000


def test_importing_the_displays_does_not_import_matplotlib():
    code = (
        "import sys, blockid.plotting.notebook, blockid.reporting.notebook\n"
        "assert 'matplotlib' not in sys.modules, 'matplotlib imported eagerly'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_a_state_space_summary_lists_basis_free_quantities_and_folds_its_matrices(
    hammerstein_fit,
):
    """The entries of A, B and C depend on the state basis: the summary lists the static
    gain, poles, Hankel singular values and Markov parameters, the matrices folded."""
    import re

    _, est, _ = hammerstein_fit
    fit = fit_model(est, "state-space", nx=2, standard_errors=True)
    html = fit._repr_html_()
    outside = Page(re.sub(r"<details>.*?</details>", "", html, flags=re.S))
    names = [row[0] for t in outside.tables for row in t[1:]]
    assert "static gain y / u" in names and "Hankel singular value 2" in names
    assert not any(re.match(r"[ABC]\[", n) for n in names), names
    gain = next(row for t in outside.tables for row in t[1:] if row[0] == "static gain y / u")
    assert float(gain[2]) > 0  # a standard error, by the delta method
    folded = Page(re.search(r"<details>.*?</details>", html, re.S).group(0))
    assert [row[0] for row in folded.tables[0][1:]] == ["A[0,:]", "A[1,:]", "B[0,:]",
                                                         "B[1,:]", "C[0,:]"]  # fmt: skip
