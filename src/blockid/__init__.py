"""blockid: identification of block-oriented nonlinear models.

Data flows one way::

    data -> blocks -> models -> estimators -> evaluation -> fitting -> plotting -> cli
                          \\-> _kernels (numba, NumPy only) <-/

The top level re-exports a small, deliberate API; everything else lives in its
subpackage (``blockid.blocks``, ``blockid.models``, ``blockid.estimators``, ...). The
names are imported on first use (PEP 562), so ``import blockid`` and the command line
start without loading pandas, SciPy or numba until a command needs them.
"""

from __future__ import annotations

from blockid._lazy import lazy_names

__version__ = "0.1.0"

#: Public name -> module that defines it.
_WHERE = {
    # data
    "Dataset": "blockid.data",
    "Experiment": "blockid.data",
    "read_data": "blockid.data",
    # experiment design
    "multisine": "blockid.design",
    "prbs": "blockid.design",
    "random_binary": "blockid.design",
    # blocks
    "Backlash": "blockid.blocks",
    "DeadZone": "blockid.blocks",
    "LinearBlock": "blockid.blocks",
    "PiecewiseLinear": "blockid.blocks",
    "Polynomial": "blockid.blocks",
    "Saturation": "blockid.blocks",
    "StaticBlock": "blockid.blocks",
    "TwoSegmentPolynomial": "blockid.blocks",
    # models
    "ARX": "blockid.models",
    "BlockStateSpace": "blockid.models",
    "ChainModel": "blockid.models",
    "LinearFeedback": "blockid.models",
    "PolynomialStateSpace": "blockid.models",
    "StateSpace": "blockid.models",
    "load_model": "blockid.models",
    "save_model": "blockid.models",
    # estimators (regressor level)
    "AdaptiveWeightedRLS": "blockid.estimators",
    "BatchLeastSquares": "blockid.estimators",
    "ForgettingSchedule": "blockid.estimators",
    "HierarchicalRLS": "blockid.estimators",
    "RecursiveLeastSquares": "blockid.estimators",
    # identification (model level) and validation
    "ARXEstimator": "blockid.fitting.estimator",
    "BacklashEstimator": "blockid.fitting.estimator",
    "HammersteinEstimator": "blockid.fitting.estimator",
    "HammersteinWienerEstimator": "blockid.fitting.estimator",
    "WienerEstimator": "blockid.fitting.estimator",
    "best_linear_approximation": "blockid.evaluation",
    "evaluate": "blockid.evaluation",
    "identify": "blockid.workflows.identify",
    "false_nearest_neighbours": "blockid.fitting.orders",
    "fit_arx": "blockid.fitting",
    "fit_model": "blockid.fitting",
    "metrics_by_output": "blockid.evaluation",
    "predict": "blockid.evaluation",
    # memory and work-partition sizes of the fits
    "config_context": "blockid.config",
    "get_config": "blockid.config",
    "set_config": "blockid.config",
    # errors
    "BlockidError": "blockid.errors",
    "DataError": "blockid.errors",
    "EstimationError": "blockid.errors",
    "ModelFileError": "blockid.errors",
    "OrderError": "blockid.errors",
    "ParameterError": "blockid.errors",
}

__all__, __getattr__, __dir__ = lazy_names(__name__, _WHERE)
