"""The order test's defaults (fitting/order_defaults.py): the keywords of
false_nearest_neighbours, readable without NumPy by the command line."""

import inspect
import subprocess
import sys

from blockid.fitting.order_defaults import DEFAULTS
from blockid.fitting.orders import false_nearest_neighbours


def test_every_default_is_a_keyword_of_the_order_test_with_that_value():
    params = inspect.signature(false_nearest_neighbours).parameters
    assert {name: params[name].default for name in DEFAULTS} == DEFAULTS
    # the keywords it leaves out are the ones with no default worth showing
    assert {n for n, p in params.items() if p.kind is p.KEYWORD_ONLY} - set(DEFAULTS) == {
        "output",
        "min_nk",
    }


def test_reading_the_defaults_imports_no_numpy():
    code = (
        "import sys\n"
        "from blockid.fitting.order_defaults import DEFAULTS\n"
        "assert DEFAULTS['max_na'] == 4\n"
        "assert 'numpy' not in sys.modules, 'numpy imported'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
