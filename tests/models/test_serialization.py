import json

import numpy as np
import pytest

from blockid import errors
from blockid.errors import ModelFileError
from blockid.models import ARX, load_model, save_model


def test_save_load_identical_predictions(tmp_path, rng):
    model = ARX(
        ["u"],
        ["y"],
        na=2,
        nb=3,
        nk=2,
        sampling_time=0.05,
        a={"y": {"y": rng.standard_normal(2) * 0.3}},
        b={"y": {"u": rng.standard_normal(3)}},
    )
    path = save_model(model, tmp_path / "m.json", estimation={"method": "batch"})
    again = load_model(path)
    u = rng.standard_normal(500)
    y = model.simulate(u)
    assert np.array_equal(again.simulate(u), model.simulate(u))
    assert np.array_equal(again.predict(u, y), model.predict(u, y))
    assert again.sampling_time == 0.05
    doc = json.loads(path.read_text())
    assert (doc["format"], doc["version"]) == ("blockid-model", 1)
    assert doc["estimation"] == {"method": "batch"}
    assert doc["model"] == model.to_dict()
    with pytest.raises(errors.BlockidError, match="exists"):
        save_model(model, path)
    assert json.loads(path.read_text()) == doc  # the refused save left the file alone


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("not json", "not valid JSON"),
        ('{"format": "other"}', "not a blockid model file"),
        ('{"format": "blockid-model", "version": 2, "model": {}}', "version 2"),
        ('{"format": "blockid-model", "version": 1}', 'no \\"model\\" entry'),
        (
            '{"format": "blockid-model", "version": 1, "model": {"structure": "nope"}}',
            "unknown model structure 'nope'",
        ),
        (
            '{"format": "blockid-model", "version": 1, "model": {"structure": "arx", "inputs": ["u"]}}',
            "damaged or incomplete",
        ),
    ],
)
def test_damaged_files(tmp_path, text, match):
    path = tmp_path / "m.json"
    path.write_text(text)
    with pytest.raises(errors.ModelFileError, match=match) as info:
        load_model(path)
    # the message names the file it refused, first, so a user knows which one to fix
    assert str(info.value).startswith(str(path))
    assert path.read_text() == text  # loading never rewrites a file


def test_missing_file_is_named(tmp_path):
    path = tmp_path / "nowhere.json"
    with pytest.raises(errors.ModelFileError) as info:
        load_model(path)
    assert str(info.value) == f"model file {path} does not exist"


def test_a_chain_file_edited_to_two_inputs_is_refused(tmp_path):
    """Issue 21: a model file whose inputs were edited to two names for a one-input
    chain simulated silently with the first."""
    import json

    import pytest

    from blockid.blocks import LinearBlock
    from blockid.errors import ModelFileError
    from blockid.models import ChainModel, load_model, save_model

    path = tmp_path / "m.json"
    save_model(ChainModel("u", "y", [LinearBlock(1, 1, 1, a=[-0.5], b=[1.0])]), path)
    doc = json.loads(path.read_text())
    doc["model"]["inputs"] = ["u", "v"]
    path.write_text(json.dumps(doc))
    with pytest.raises(ModelFileError, match=r"names 2 inputs \(\['u', 'v'\]\)"):
        load_model(path)


def test_a_model_refuses_non_finite_inputs_naming_the_sample():
    """Issue 21: ``estimator.simulate(np.full(100, np.nan))`` returned NaNs silently."""
    import numpy as np
    import pytest

    from blockid.blocks import LinearBlock
    from blockid.errors import DataError
    from blockid.models import ChainModel

    model = ChainModel("u", "y", [LinearBlock(1, 1, 1, a=[-0.5], b=[1.0])])
    u = np.ones(20)
    u[4] = np.nan
    with pytest.raises(DataError, match=r"input 'u' is nan at sample 4"):
        model.simulate(u)


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def test_model_document_without_format_is_named_by_default():
    from blockid.models.serialization import model_from_document

    with pytest.raises(ModelFileError) as info:
        model_from_document({})
    assert str(info.value) == (
        'the model document is not a blockid model file (no "format": "blockid-model")'
    )


def test_model_files_are_indented_by_two_and_name_the_non_finite_entry(tmp_path):
    import json
    import math

    from blockid.errors import ModelFileError
    from blockid.models import ARX, save_model
    from blockid.models.serialization import check_finite

    model = ARX("u", "y", 1, 1, 1, a={"y": {"y": [-0.5]}}, b={"y": {"u": [1.0]}})
    path = tmp_path / "m.json"
    save_model(model, path)
    text = path.read_text()
    assert text.startswith('{\n  "') and text == json.dumps(json.loads(text), indent=2) + "\n"
    document = {"parameters": {"y": {"a": [0.1, math.nan]}}}
    with pytest.raises(ModelFileError) as info:
        check_finite(document)
    assert "parameters.y.a[1] is nan" in str(info.value)


def test_a_model_with_a_nan_parameter_is_not_written(tmp_path):
    """json's allow_nan=False is the guard: a NaN would make a file no reader accepts."""
    import math

    from blockid.models import ARX, save_model

    model = ARX("u", "y", 1, 1, 1, a={"y": {"y": [math.nan]}}, b={"y": {"u": [1.0]}})
    path = tmp_path / "m.json"
    with pytest.raises(ValueError, match="Out of range float values"):
        save_model(model, path)
    assert not path.exists()


@pytest.mark.parametrize(
    ("key", "bad", "match"),
    [
        ("offsets", "abc", "offsets of its inputs \\('abc'\\) must give each of \\['u'\\]"),
        ("offsets", {"inputs": {"v": 1.0}, "outputs": {"y": 0.0}}, "of its inputs .* \\['u'\\]"),
        ("offsets", {"inputs": {"u": 0.0}, "outputs": []}, "of its outputs"),
        ("estimation_ranges", "zz", "estimation_ranges \\(zz\\) are not pairs"),
        ("estimation_ranges", {"input": [1.0]}, "are not pairs"),
    ],
)
def test_a_damaged_offset_or_range_of_a_block_model_is_named(tmp_path, key, bad, match):
    """A chain's (or feedback loop's) offsets and ranges: a damaged entry is refused by
    name; it raised AttributeError with a traceback, or (an offset under another signal's
    name) was read as 0 without a word."""
    from blockid.blocks import Polynomial
    from blockid.models import Hammerstein

    model = Hammerstein("u", "y", input_block=Polynomial([0.0, 1.0, 0.2]), na=1, nb=1, nk=1,
                        a=[-0.5], b=[1.0], input_offset=0.3, output_offset=-0.1)  # fmt: skip
    path = tmp_path / "m.json"
    save_model(model, path)
    document = json.loads(path.read_text())
    document["model"][key] = bad
    path.write_text(json.dumps(document))
    with pytest.raises(ModelFileError, match=match):
        load_model(path)


@pytest.mark.parametrize(
    ("structure", "key", "bad", "match"),
    [
        ("arx", "offsets", "abc", "offsets of its inputs \\('abc'\\)"),
        ("arx", "offsets", {"zz": 1.0}, "must give each of \\['u'\\] a number"),
        ("arx", "offsets", {"inputs": {"u": 0.0}, "outputs": {"q": 1.0}}, "of its outputs"),
        ("state-space", "normalisation", "abc", "normalisation \\(abc\\) must give"),
        ("state-space", "normalisation", {"zz": 1}, "input_offset, input_scale"),
    ],
)
def test_a_damaged_offset_or_normalisation_of_a_linear_model_is_named(
    tmp_path, structure, key, bad, match
):
    """An ARX model's offsets and a state space's normalisation: a table under other names
    was read as no offset (0) and no scaling (1) without a word; a string raised
    AttributeError. Both are refused by name."""
    from blockid.data import Dataset
    from blockid.fitting import fit_model

    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, 300)
    data = Dataset.from_arrays(u, np.convolve(u, [0.0, 1.0, 0.5])[:300] + 2.0, ["u"], ["y"])
    orders = {"na": 1, "nb": 2, "nk": 1} if structure == "arx" else {"nx": 2}
    path = tmp_path / "m.json"
    save_model(fit_model(data, structure, **orders).model, path)
    document = json.loads(path.read_text())
    document["model"][key] = bad
    path.write_text(json.dumps(document))
    with pytest.raises(ModelFileError, match=match):
        load_model(path)
