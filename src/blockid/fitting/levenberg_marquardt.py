"""Levenberg-Marquardt on the normal equations ``J^T J`` and ``J^T r``.

For least-squares problems whose Jacobian is too large to hold (a long record: the
simulation-error refinement of :mod:`blockid.fitting.simulation_error` above
``jacobian_bytes`` of :mod:`blockid.config`) or that are summed piece by piece anyway
(the state-space fits of :mod:`blockid.fitting.state_space`, whose Jacobian is walked
forward in time). The
problem gives ``residuals(theta)`` (a rejected candidate returns a large constant
vector), ``normal_equations(theta)`` at accepted iterates, and counts residual
evaluations in ``tracker.nfev``; an early-stopping monitor in ``normal_equations`` may
raise to end the solver (the caller catches it). The damping ``mu I`` of the
column-scaled normal equations also keeps a problem whose parameters are not unique
(a state-space model's basis) solvable.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

__all__ = ["EarlyStop", "Problem", "levenberg_marquardt", "note_tail"]


class EarlyStop(Exception):
    """Raised by a problem's early-stopping monitor (:func:`note_tail`) to end the
    solver; the caller catches it and takes the tracker's ``best_theta``."""


def note_tail(tracker: Any, tail: float, theta: np.ndarray) -> None:
    """Early stopping's book-keeping at an accepted iterate ``theta`` whose held-back
    tail error is ``tail``: the tracker's ``tail`` list, ``best_tail``/``best_theta``
    and ``since_best``; raises :class:`EarlyStop` (``triggered`` set) after
    ``tracker.patience`` iterates without a better tail."""
    tracker.tail.append(tail)
    if tail < tracker.best_tail:
        tracker.best_tail, tracker.best_theta = tail, theta.copy()
        tracker.since_best = 0
        return
    tracker.since_best += 1
    if tracker.since_best >= tracker.patience:
        tracker.triggered = True
        raise EarlyStop


class Problem(Protocol):
    """What :func:`levenberg_marquardt` asks of a problem."""

    tracker: Any

    def residuals(self, theta: np.ndarray) -> np.ndarray: ...

    def normal_equations(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...


def levenberg_marquardt(
    problem: Problem,
    theta0: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray],
    max_nfev: int,
    ftol: float,
    xtol: float,
    gtol: float,
    null_space: float | None = None,
) -> tuple[np.ndarray, str]:
    """Levenberg-Marquardt on the normal equations (module docstring).

    Columns scaled to unit norm (as ``x_scale="jac"``), damping by Nielsen's rule from
    the gain ratio, steps clipped to the bounds; a rejected residual (unstable, invalid
    or exploding candidate: the problem's residuals say so) raises the damping. Stops like
    MINPACK's ``lmder``: the actual and the predicted relative cost reduction of a step
    both below ``ftol`` (a step that gains little where the model predicts more is a
    crawl, not convergence: stopping there left PNLSS fits at twice their error), step below
    ``xtol`` relative to the parameters, every scaled gradient entry below ``gtol``
    times the residual norm (the cosine between the residual and each column), or
    ``max_nfev`` residual evaluations. Returns the final iterate and why it stopped.

    ``null_space``: the steps are solved in the eigenvectors of the scaled ``J^T J`` whose
    eigenvalues exceed ``null_space`` times the largest, the rest left alone. For a
    problem whose parameters are unique only up to a transformation (a state-space
    model's basis), rounding puts a little of the gradient in those directions, and the
    damping divides it by ``mu``: steps along them, harmless to first order, spoil the
    model of the cost and the convergence (PNLSS fits stalled at a gain ratio of 0.6
    without it). None: the damped system is solved as it is.
    """
    lower, upper = bounds
    theta = theta0.copy()
    r = problem.residuals(theta)
    cost = 0.5 * float(r @ r)
    H, g = problem.normal_equations(theta)
    mu, nu = 1e-3, 2.0
    basis = None  # eigen-decomposition of the scaled J^T J at the current iterate
    while problem.tracker.nfev < max_nfev:
        d = np.sqrt(np.diag(H))
        d[d == 0] = 1.0
        Hs, gs = H / np.outer(d, d), g / d
        if np.max(np.abs(gs), initial=0.0) <= gtol * np.sqrt(2.0 * cost):
            return theta, "`gtol` termination condition is satisfied."
        try:
            if null_space is None:
                p = -np.linalg.solve(Hs + mu * np.eye(theta.size), gs)
            else:
                if basis is None:
                    lam, V = np.linalg.eigh(Hs)
                    keep = lam > null_space * max(float(lam.max()), 1e-300)
                    basis = (lam[keep], V[:, keep])
                lam, V = basis
                p = -V @ ((V.T @ gs) / (lam + mu))
        except np.linalg.LinAlgError:
            mu, nu = mu * nu, 2.0 * nu
            continue
        new = np.clip(theta + p / d, lower, upper)
        r_new = problem.residuals(new)
        cost_new = 0.5 * float(r_new @ r_new)
        predicted = 0.5 * float(p @ (mu * p - gs))
        rho = (cost - cost_new) / predicted if predicted > 0 else -1.0
        if rho > 0 and cost_new < cost:
            reduction = cost - cost_new
            small = np.linalg.norm(new - theta) <= xtol * (xtol + np.linalg.norm(theta))
            theta, cost = new, cost_new
            if max(reduction, predicted) <= ftol * (cost + reduction):
                return theta, "`ftol` termination condition is satisfied."
            if small:
                return theta, "`xtol` termination condition is satisfied."
            H, g = problem.normal_equations(theta)
            basis = None
            mu *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
            nu = 2.0
        else:
            mu, nu = mu * nu, 2.0 * nu
            if mu > 1e16:
                return theta, "no step reduces the error"
    return theta, "max_nfev reached"
