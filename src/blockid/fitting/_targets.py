"""What the registry names: each structure's model class.

Each function here is named after the class it returns and imports it only when called,
so that :mod:`blockid.fitting.registry` refers to real classes (seen by the import graph,
by refactoring tools and by "find references") while importing it, and starting the
command line, still loads none of NumPy, SciPy, numba or the models.
:class:`~blockid.fitting.registry.Structure` holds one of these loaders.

The estimators are not here: every fitting module imports the registry (``checked``,
``get_structure``), so a loader of one, even importing it inside a function, would close
an import circle (``tests/test_architecture.py::test_no_import_circle``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
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
