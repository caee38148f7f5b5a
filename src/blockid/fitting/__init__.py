"""Identification: from data and a model structure to a checked, fitted model.

Names are imported on first use (PEP 562): the registry of structures and options
(:mod:`blockid.fitting.registry`) can be read, e.g. by the command line, without
loading SciPy and numba.
"""

from __future__ import annotations

from blockid._lazy import lazy_names

_WHERE = {
    "ARX_METHODS": "arx",
    "fit_arx": "arx",
    "make_estimator": "arx",
    "fit_backlash_aw_rls": "backlash",
    "check_model": "checks",
    "linear_baseline": "checks",
    "simulation_mse": "checks",
    "DEFAULT_METHOD": "dispatch",
    "METHODS": "dispatch",
    "STRUCTURES": "dispatch",
    "fit_model": "dispatch",
    "ESTIMATORS": "estimator",
    "ModelEstimator": "estimator",
    "initial_estimate": "initial",
    "OrderEvidence": "orders",
    "false_nearest_neighbours": "orders",
    "fit_feedback": "feedback",
    "FrequencyFit": "frequency",
    "fit_bla": "frequency",
    "fit_frequency_response": "frequency",
    "fit_wiener_hammerstein": "wiener_hammerstein",
    "KEY_TERM_STRUCTURES": "key_term",
    "fit_key_term_rls": "key_term",
    "SubsystemSpec": "network",
    "fit_network": "network",
    "network_signals": "network",
    "parse_subsystem": "network",
    "subset": "network",
    "FitResult": "result",
    "fit_simulation_error": "simulation_error",
    "refine": "simulation_error",
}

__all__, __getattr__, __dir__ = lazy_names(__name__, _WHERE)
