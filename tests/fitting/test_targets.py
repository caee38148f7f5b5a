"""The registry's loaders (fitting/_targets.py): each returns the class or fitter it is
named after, and imports it only when called."""

import subprocess
import sys

import pytest

from blockid.fitting import _targets


@pytest.mark.parametrize("name", _targets.__all__)
def test_each_loader_returns_what_it_is_named_after(name):
    target = getattr(_targets, name)()
    assert target.__name__ == name
    package = "blockid.models." if name[0].isupper() else "blockid.fitting."
    assert target.__module__.startswith(package)


def test_the_loaders_import_nothing_until_called():
    code = (
        "import sys\n"
        "from blockid.fitting import _targets\n"
        "assert not [m for m in sys.modules if m.startswith('blockid.models')]\n"
        "assert 'numpy' not in sys.modules\n"
        "_targets.fit_arx()\n"
        "assert 'blockid.fitting.arx' in sys.modules and 'numpy' in sys.modules\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
