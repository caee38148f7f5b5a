"""blockid: identification of block-oriented nonlinear models.

Data flows one way::

    data -> blocks -> models -> estimators -> fitting -> evaluation -> plotting -> cli
                          \\-> _kernels (numba, NumPy only) <-/

The top level re-exports a small, deliberate API; everything else lives in its
subpackage (``blockid.blocks``, ``blockid.models``, ``blockid.estimators``, ...).
"""

from blockid.blocks import (
    Backlash,
    DeadZone,
    PiecewiseLinear,
    Polynomial,
    Saturation,
    TwoSegmentPolynomial,
)
from blockid.data import Dataset, Experiment, read_data
from blockid.errors import (
    BlockidError,
    DataError,
    EstimationError,
    ModelFileError,
    OrderError,
    ParameterError,
)
from blockid.estimators import (
    AdaptiveWeightedRLS,
    BatchLeastSquares,
    ForgettingSchedule,
    HierarchicalRLS,
    RecursiveLeastSquares,
)
from blockid.evaluation import evaluate, metrics_by_output
from blockid.fitting import fit_arx
from blockid.models import ARX, load_model, save_model

__version__ = "0.1.0"

__all__ = [
    # data
    "Dataset",
    "Experiment",
    "read_data",
    # blocks
    "Backlash",
    "DeadZone",
    "PiecewiseLinear",
    "Polynomial",
    "Saturation",
    "TwoSegmentPolynomial",
    # models
    "ARX",
    "load_model",
    "save_model",
    # estimators
    "AdaptiveWeightedRLS",
    "BatchLeastSquares",
    "ForgettingSchedule",
    "HierarchicalRLS",
    "RecursiveLeastSquares",
    # identification and validation
    "evaluate",
    "fit_arx",
    "metrics_by_output",
    # errors
    "BlockidError",
    "DataError",
    "EstimationError",
    "ModelFileError",
    "OrderError",
    "ParameterError",
]
