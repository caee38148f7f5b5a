import pytest

from cli import bad_input


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """The working folder of a bad-input case (:func:`cli.bad_input.workdir`)."""
    monkeypatch.chdir(tmp_path)
    return bad_input.workdir(tmp_path)
