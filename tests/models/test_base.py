"""model_from_dict (blockid.models.base): an unknown structure and a damaged description
are named in the error."""

import pytest

from blockid.blocks import Polynomial
from blockid.errors import ModelFileError
from blockid.models import Hammerstein
from blockid.models.base import model_from_dict


def test_damaged_model_description_names_the_missing_entry():
    data = Hammerstein(
        "u", "y", input_block=Polynomial([0.0, 1.0]), na=1, nb=1, nk=1, a=[-0.5]
    ).to_dict()
    del data["parameters"], data["chain"]
    with pytest.raises(
        ModelFileError, match=r"hammerstein model description is damaged or incomplete \(KeyError: "
    ):
        model_from_dict(data)


def test_unknown_model_structure_lists_the_known_ones():
    from blockid.models.base import MODEL_TYPES

    with pytest.raises(ModelFileError) as info:
        model_from_dict({"structure": "nope"})
    known = str(info.value).split("; known: ")[1].split(", ")
    assert str(info.value).startswith("unknown model structure 'nope'; known: ")
    assert known == sorted(MODEL_TYPES)
    assert {"arx", "hammerstein", "wiener", "network", "feedback"} <= set(known)


def test_signals_of_the_wrong_width_name_the_model_signals_and_the_shape():
    import numpy as np

    from blockid.errors import DataError
    from blockid.models import StateSpace

    model = StateSpace(["a", "b"], ["y"], A=[[0.5]], B=[[1.0, 0.5]], C=[[1.0]], D=[[0.0, 0.0]])
    with pytest.raises(DataError) as info:
        model.simulate(np.zeros(5))
    assert str(info.value) == (
        "the model has 2 input(s) ['a', 'b'] but got an input array of shape (5, 1)"
    )
    with pytest.raises(DataError) as info:
        model.simulate(np.zeros((5, 2)), np.zeros((3, 2)))
    assert str(info.value) == (
        "the model has 1 output(s) ['y'] but got an output array of shape (3, 2)"
    )
