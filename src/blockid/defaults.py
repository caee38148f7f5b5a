"""The default values of the options that several modules share, written once.

Every signature, help text and check that states one of these defaults reads it from
here (``tests/test_defaults.py`` compares each signature with this table), so that
``--eps1`` cannot mean 1 in one place and 10 in another without the table saying so and
why. Plain Python, no NumPy: the command line shows these values before it imports
anything numerical.

The recursive estimators' defaults differ by estimator on purpose; each entry says why.
"""

from __future__ import annotations

__all__ = [
    "DEGREE",
    "FORGETTING",
    "MAX_NFEV",
    "MAX_ORDER",
    "PATIENCE",
    "PNLSS_NFEV",
    "RECURSIVE",
    "STATE_SPACE_NFEV",
    "STATE_SPACE_TAIL",
    "TAIL_FRACTION",
    "TIE",
    "TOLERANCE",
    "WEIGHTING",
    "recursive_default",
]

#: Degree of a polynomial block when none is given: r1 (input block) and r2 (output
#: block), paper B's r1 = r2 = 3.
DEGREE = 3

#: The simulation-error refinements' stopping tolerances ``ftol``, ``xtol`` and ``gtol``
#: (as ``scipy.optimize.least_squares`` reads them; MINPACK's test for ``ftol``): tight,
#: so that a fit ends at convergence or at its ``max_nfev``, which says so.
TOLERANCE = 1e-10

#: The simulation-error refinement of a chain of blocks (and of the feedback and
#: Wiener-Hammerstein models): at most ``MAX_NFEV`` simulations; early stopping on the
#: last ``TAIL_FRACTION`` of the record after ``PATIENCE`` evaluations without a gain.
MAX_NFEV = 200
TAIL_FRACTION = 0.2
PATIENCE = 5
#: ... of a linear or block state space (``STATE_SPACE_NFEV``) and of a polynomial state
#: space, whose nonlinear refinement crawls for a few hundred evaluations before it
#: converges (the Silverbox: 342) (``PNLSS_NFEV``).
STATE_SPACE_NFEV = 100
PNLSS_NFEV = 500
#: Early stopping of the state-space refinements (linear, block and polynomial): the
#: last ``STATE_SPACE_TAIL`` of each experiment held back; a linear or block model's
#: refinement stops after ``PATIENCE`` iterates without a better tail, a polynomial
#: model's never (its refinement crawls through plateaus), and one whose tails never
#: stopped improving is finished on all the data (``docs/models.md``).
STATE_SPACE_TAIL = 0.2

#: Forgetting factor of recursive least squares (1: none; a schedule may be given).
FORGETTING = 1.0

#: The largest state dimension a state-space fit reads its default order among, and the
#: subspace method's weighting (PO-MOESP; ``cva`` the alternative).
MAX_ORDER = 10
WEIGHTING = "moesp"

#: Two cross-validated errors within this fraction of each other are a tie, the simpler
#: candidate taken: ``identify``'s ``tie`` and the polynomial state space's default order
#: (``blockid.fitting.state_space.ORDER_TIE``).
TIE = 0.02

#: Defaults of the recursive estimators, by estimator (``fit --method``):
#:
#: - ``rls``, ``hierarchical-rls``: P(0) = 1e8 I, inside SPEC's mu in [1e4, 1e10] and
#:   large, so that the first samples decide; no forgetting.
#: - ``aw-rls`` (paper A's adaptive weight, on an ARX): P(0) = 1e5 I, paper A's value
#:   (SPEC, A8); eps1 = 1, eps2 = 0.1 (paper A gives no numbers).
#: - ``backlash-aw-rls`` (paper A's S2 with internal variables): eps1 = 10. With
#:   eps1 = 1 the first samples, processed while the internal signals are still wrong,
#:   threw one of 30 noise-free records 32 % off; eps1 = 10 brought all 30 within 2e-6,
#:   eps1 = 100 slowed convergence (~1 %) (``fit_backlash_aw_rls``). One pass, as the
#:   paper runs it online.
#: - ``key-term-rls`` (paper B): P(0) = 1e6 I and forgetting 0.98 for 200 samples then
#:   1, paper B's settings (SPEC); 20 passes at most, stopping when the estimate settles.
RECURSIVE: dict[str, dict[str, object]] = {
    "rls": {"forgetting": FORGETTING, "initial_covariance": 1e8},
    "hierarchical-rls": {"forgetting": FORGETTING, "initial_covariance": 1e8},
    "aw-rls": {"eps1": 1.0, "eps2": 0.1, "initial_covariance": 1e5},
    "backlash-aw-rls": {
        "eps1": 10.0,
        "eps2": 0.1,
        "initial_covariance": 1e5,
        "passes": 1,
        "tol": 1e-6,
    },
    "key-term-rls": {
        "forgetting": "0.98:200,1",
        "initial_covariance": 1e6,
        "passes": 20,
        "tol": 1e-6,
    },
}


def recursive_default(estimator: str, option: str) -> object:
    """``RECURSIVE[estimator][option]``, named in the error when it is not there."""
    try:
        return RECURSIVE[estimator][option]
    except KeyError:
        raise KeyError(f"no default of {option!r} for the {estimator!r} estimator") from None
