"""Names imported on first use (blockid/_lazy.py), on a throwaway package."""

import sys
import types

import pytest

from blockid._lazy import lazy_names


@pytest.fixture
def package(monkeypatch):
    """``lazy_pkg`` with a submodule ``lazy_pkg.sub`` holding ``answer``; the lazy
    table names it relatively, and ``FLOORS`` by its full module path."""
    pkg, sub = types.ModuleType("lazy_pkg"), types.ModuleType("lazy_pkg.sub")
    sub.answer = 42
    monkeypatch.setitem(sys.modules, "lazy_pkg", pkg)
    monkeypatch.setitem(sys.modules, "lazy_pkg.sub", sub)
    pkg.__all__, pkg.__getattr__, pkg.__dir__ = lazy_names(
        "lazy_pkg", {"answer": "sub", "FLOORS": "blockid.floors"}
    )
    return pkg


def test_a_name_is_imported_from_its_module_on_first_use_and_kept(package):
    from blockid.floors import FLOORS

    assert "answer" not in vars(package)
    assert package.answer == 42
    assert vars(package)["answer"] == 42  # later look-ups skip __getattr__
    assert package.FLOORS is FLOORS


def test_an_unknown_name_is_an_attribute_error_naming_the_package(package):
    with pytest.raises(AttributeError, match=r"^module 'lazy_pkg' has no attribute 'nope'$"):
        package.nope  # noqa: B018


def test_dir_lists_the_lazy_names_before_they_are_imported(package):
    listed = dir(package)
    assert {"answer", "FLOORS", "__name__"} <= set(listed)
    assert listed == sorted(listed)


def test_all_is_the_lazy_names_sorted(package):
    assert package.__all__ == ["FLOORS", "answer"]
