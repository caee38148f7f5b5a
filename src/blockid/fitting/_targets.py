"""What the registry names: each structure's model class and each method's fitter.

Each function here is named after the class it returns and imports it only when called,
so that :mod:`blockid.fitting.registry` refers to real classes (seen by the import graph,
by refactoring tools and by "find references") while importing it, and starting the
command line, still loads none of NumPy, SciPy, numba or the models.
:class:`~blockid.fitting.registry.Structure` holds one of these loaders.

The fitters check their options in :mod:`blockid.fitting.options`, below the registry,
and never import the registry itself: a loader here imports a fitting module inside a
function, and that module importing the registry back would close an import circle
(``tests/test_architecture.py::test_no_import_circle``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from collections.abc import Callable

    from blockid.models.base import Model

__all__ = [
    "ARX",
    "Hammerstein",
    "Wiener",
    "HammersteinWiener",
    "BacklashModel",
    "OutputError",
    "WienerHammerstein",
    "StateSpace",
    "PolynomialStateSpace",
    "BlockStateSpace",
    "LinearFeedback",
    "fit_arx",
    "fit_backlash_aw_rls",
    "fit_block_arx",
    "fit_block_state_space",
    "fit_feedback",
    "fit_key_term_rls",
    "fit_key_term_block",
    "fit_simulation_error",
    "fit_polynomial_state_space",
    "fit_state_space",
    "fit_subspace",
    "fit_wiener_hammerstein",
]


# ----------------------------------------------------------------------------- model classes
def ARX() -> type[Model]:
    from blockid.models.arx import ARX

    return ARX


def Hammerstein() -> type[Model]:
    from blockid.models.block import Hammerstein

    return Hammerstein


def Wiener() -> type[Model]:
    from blockid.models.block import Wiener

    return Wiener


def HammersteinWiener() -> type[Model]:
    from blockid.models.block import HammersteinWiener

    return HammersteinWiener


def BacklashModel() -> type[Model]:
    from blockid.models.block import BacklashModel

    return BacklashModel


def OutputError() -> type[Model]:
    from blockid.models.block import OutputError

    return OutputError


def WienerHammerstein() -> type[Model]:
    from blockid.models.block import WienerHammerstein

    return WienerHammerstein


def StateSpace() -> type[Model]:
    from blockid.models.state_space import StateSpace

    return StateSpace


def PolynomialStateSpace() -> type[Model]:
    from blockid.models.state_space import PolynomialStateSpace

    return PolynomialStateSpace


def BlockStateSpace() -> type[Model]:
    from blockid.models.block_state_space import BlockStateSpace

    return BlockStateSpace


def LinearFeedback() -> type[Model]:
    from blockid.models.feedback import LinearFeedback

    return LinearFeedback


# ----------------------------------------------------------------------------- fitters
def fit_arx() -> Callable[..., Any]:
    from blockid.fitting.arx import fit_arx

    return fit_arx


def fit_backlash_aw_rls() -> Callable[..., Any]:
    from blockid.fitting.backlash import fit_backlash_aw_rls

    return fit_backlash_aw_rls


def fit_block_arx() -> Callable[..., Any]:
    from blockid.fitting.block_arx import fit_block_arx

    return fit_block_arx


def fit_block_state_space() -> Callable[..., Any]:
    from blockid.fitting.block_state_space import fit_block_state_space

    return fit_block_state_space


def fit_feedback() -> Callable[..., Any]:
    from blockid.fitting.feedback import fit_feedback

    return fit_feedback


def fit_key_term_rls() -> Callable[..., Any]:
    from blockid.fitting.key_term import fit_key_term_rls

    return fit_key_term_rls


def fit_key_term_block() -> Callable[..., Any]:
    from blockid.fitting.key_term_channels import fit_key_term_block

    return fit_key_term_block


def fit_simulation_error() -> Callable[..., Any]:
    from blockid.fitting.simulation_error import fit_simulation_error

    return fit_simulation_error


def fit_polynomial_state_space() -> Callable[..., Any]:
    from blockid.fitting.state_space import fit_polynomial_state_space

    return fit_polynomial_state_space


def fit_state_space() -> Callable[..., Any]:
    from blockid.fitting.state_space import fit_state_space

    return fit_state_space


def fit_subspace() -> Callable[..., Any]:
    from blockid.fitting.state_space import fit_subspace

    return fit_subspace


def fit_wiener_hammerstein() -> Callable[..., Any]:
    from blockid.fitting.wiener_hammerstein import fit_wiener_hammerstein

    return fit_wiener_hammerstein
