"""Defaults of the false-nearest-neighbours order test (:mod:`blockid.fitting.orders`),
apart from it so that the command line can show them without importing NumPy."""

__all__ = ["DEFAULTS"]

#: Keyword defaults of :func:`blockid.fitting.orders.false_nearest_neighbours`.
DEFAULTS = {
    "max_na": 4,
    "max_nb": 4,
    "max_nk": 3,
    "r_tol": 2.0,
    "a_tol": 2.0,
    "noise": "auto",
    "threshold": 1.0,
    "max_points": 2000,
    "exclude": 0,
    "seed": 0,
}
