"""The floors of blockid: each package's floor, the one statement of them.

A module may import from its own floor and the floors below, never from one above
(the one exception: a ``.plot()`` or ``_repr_html_()`` method hands off to
:mod:`blockid.plotting` through an import inside the method).
``tests/test_architecture.py`` checks every import against this table and that the
table in ``docs/architecture.md`` states the same floors. Plain Python, no imports.
"""

from __future__ import annotations

__all__ = ["FLOORS"]

#: Package (the first name below ``blockid``) -> floor.
FLOORS: dict[str, int] = {
    "errors": 0,
    "defaults": 0,
    "floors": 0,
    "config": 0,  # memory and work-partition sizes, read by the fits at call time
    "_lazy": 0,  # the packages' lazy exports: the standard library only
    "_kernels": 0,
    "data": 1,
    "design": 1,  # excitation signals: NumPy only, beside the data they become
    "blocks": 2,
    "plants": 3,
    "models": 3,
    "estimators": 4,
    "evaluation": 5,  # scores and standard errors read models, never fitters
    "fitting": 6,
    "plotting": 7,
    "workflows": 8,
    "reporting": 8,
    "cli": 9,
}
