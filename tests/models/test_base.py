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
