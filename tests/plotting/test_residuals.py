"""The figure of a residual analysis (plotting/residuals.py): a row per output, the
autocorrelation and each input's cross-correlation with their bounds and p-values, and
the file it writes."""

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.errors import DataError
from blockid.evaluation.residuals import residual_analysis
from blockid.models import ARX
from blockid.plotting.residuals import plot_residuals, residual_figure


@pytest.fixture(scope="module")
def analysis():
    rng = np.random.default_rng(1)
    u = rng.standard_normal((400, 2))
    model = ARX(["a", "b"], ["y"], na=1, nb=1, nk=1, a={"y": {"y": [-0.5]}},
                b={"y": {"a": [1.0], "b": [0.5]}})  # fmt: skip
    y = model.simulate(u) + 0.1 * rng.standard_normal((400, 1))
    data = Dataset.from_arrays(u, y, ["a", "b"], ["y"])
    return residual_analysis(model, data, "simulation", max_lag=8, confidence=0.95)


def test_one_row_per_output_the_autocorrelation_then_each_input(analysis):
    import matplotlib.pyplot as plt

    fig = plot_residuals(analysis, data_label="d.csv")
    try:
        auto, cross_a, cross_b = fig.axes
        assert auto.get_title() == (
            "autocorrelation of the residual of y\n"
            f"Ljung-Box p = {analysis.whiteness['y']['p_value']:.3g}"
        )
        assert cross_b.get_title().startswith("cross-correlation b (t) with residual y (t+τ)\n")
        markers = auto.containers[0].markerline
        np.testing.assert_array_equal(markers.get_xdata(), analysis.lags)
        np.testing.assert_allclose(markers.get_ydata(), analysis.autocorrelation["y"])
        band = cross_a.patches[0].get_extents()  # the shaded bounds
        assert band.height > 0 and auto.get_legend().get_texts()[0].get_text() == "95%"
        assert fig._suptitle.get_text() == (
            f"residual of the free-run simulation on d.csv ({analysis.n_samples} samples)"
        )
    finally:
        plt.close(fig)


def test_the_figure_is_written_once_and_replaced_only_when_asked(analysis, tmp_path):
    path = residual_figure(analysis, tmp_path / "figs")
    assert path == tmp_path / "figs" / "residuals.png" and path.read_bytes()[:4] == b"\x89PNG"
    path.write_bytes(b"mine")
    with pytest.raises(DataError, match=r"residuals\.png exists; pass --force to replace it$"):
        residual_figure(analysis, tmp_path / "figs")
    assert path.read_bytes() == b"mine"
    residual_figure(analysis, tmp_path / "figs", overwrite=True)
    assert path.read_bytes()[:4] == b"\x89PNG"
