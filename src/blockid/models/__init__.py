"""Model structures: linear ARX and the block-oriented models."""

from blockid.models.arx import ARX
from blockid.models.base import MODEL_TYPES, Model, model_from_dict
from blockid.models.block import (
    BLOCK_STRUCTURES,
    BacklashModel,
    BlockModel,
    ChainModel,
    Hammerstein,
    HammersteinWiener,
    OutputError,
    Wiener,
    WienerHammerstein,
)
from blockid.models.block_state_space import BlockStateSpace
from blockid.models.feedback import LinearFeedback
from blockid.models.network import Network
from blockid.models.serialization import (
    load_model,
    model_document,
    model_from_document,
    save_model,
)
from blockid.models.state_space import PolynomialStateSpace, StateSpace

__all__ = [
    "BlockStateSpace",
    "LinearFeedback",
    "PolynomialStateSpace",
    "StateSpace",
    "Network",
    "BLOCK_STRUCTURES",
    "BacklashModel",
    "BlockModel",
    "ChainModel",
    "Hammerstein",
    "HammersteinWiener",
    "OutputError",
    "Wiener",
    "WienerHammerstein",
    "ARX",
    "MODEL_TYPES",
    "Model",
    "load_model",
    "model_document",
    "model_from_dict",
    "model_from_document",
    "save_model",
]
