"""Estimators on the regressor level, following the scikit-learn conventions."""

from blockid.estimators.adaptive import AdaptiveWeightedRLS
from blockid.estimators.batch import BatchLeastSquares
from blockid.estimators.forgetting import ForgettingSchedule
from blockid.estimators.hierarchical import HierarchicalRLS
from blockid.estimators.rls import RecursiveEstimator, RecursiveLeastSquares

__all__ = [
    "AdaptiveWeightedRLS",
    "BatchLeastSquares",
    "ForgettingSchedule",
    "HierarchicalRLS",
    "RecursiveEstimator",
    "RecursiveLeastSquares",
]
