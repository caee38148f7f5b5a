"""Identification: from data and a model structure to a checked, fitted model."""

from blockid.fitting.arx import ARX_METHODS, fit_arx, make_estimator
from blockid.fitting.backlash import fit_backlash_aw_rls
from blockid.fitting.checks import check_model, linear_baseline, simulation_mse
from blockid.fitting.dispatch import DEFAULT_METHOD, METHODS, STRUCTURES, fit_model
from blockid.fitting.initial import initial_estimate
from blockid.fitting.key_term import KEY_TERM_STRUCTURES, fit_key_term_rls
from blockid.fitting.network import SubsystemSpec, fit_network, parse_subsystem, subset
from blockid.fitting.result import FitResult
from blockid.fitting.simulation_error import fit_simulation_error, refine

__all__ = [
    "KEY_TERM_STRUCTURES",
    "fit_backlash_aw_rls",
    "fit_key_term_rls",
    "fit_simulation_error",
    "initial_estimate",
    "refine",
    "DEFAULT_METHOD",
    "METHODS",
    "STRUCTURES",
    "SubsystemSpec",
    "fit_model",
    "fit_network",
    "parse_subsystem",
    "subset",
    "ARX_METHODS",
    "FitResult",
    "check_model",
    "fit_arx",
    "linear_baseline",
    "make_estimator",
    "simulation_mse",
]
