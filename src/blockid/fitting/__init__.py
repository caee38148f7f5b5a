"""Identification: from data and a model structure to a checked, fitted model."""

from blockid.fitting.arx import ARX_METHODS, FitResult, fit_arx, make_estimator

__all__ = ["ARX_METHODS", "FitResult", "fit_arx", "make_estimator"]
