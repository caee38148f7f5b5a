"""A nonlinear state-space model linearised at an operating point: the small-signal
model a control engineer designs with.

For a constant physical input ``u_0`` the model rests at the equilibrium ``x^*`` of its
one-step map (normalised signals, :mod:`blockid.models.state_space`)

.. math::

    x^* = f(x^*, u_{n,0}), \\qquad y^* = g(x^*, u_{n,0}), \\qquad
    u_{n,0} = (u_0 - \\text{input\\_offset}) / \\text{input\\_scale}

and small deviations from it follow

.. math::

    \\delta x(k+1) = A\\, \\delta x(k) + B\\, (u(k) - u_0), \\qquad
    y(k) - y^* = C\\, \\delta x(k) + D\\, (u(k) - u_0)

with ``A = ∂f/∂x``, ``B = ∂f/∂u_n S_u^{-1}``, ``C = S_y ∂g/∂x``,
``D = S_y ∂g/∂u_n S_u^{-1}`` at ``(x^*, u_{n,0})`` (``S``: the diagonal scales; the state
is the model's own, normalised, so ``δx = x - x^*``). The derivatives are the model's
own (``step_jacobians``: analytic, the blocks' ``derivative`` for a block state space);
the map is its ``step``, the simulation's arithmetic.

**Finding the equilibrium.** The model is first run from rest (``x = 0``) at the
constant input, as a plant settles, for up to :data:`SETTLE_SAMPLES` samples; Newton's
method on ``x - f(x, u_{n,0}) = 0`` with the analytic ``∂f/∂x`` then polishes the
state (or, where the run diverged, searches from rest). An equilibrium whose ``A`` has
an eigenvalue on or outside the unit circle is refused: a small-signal model of a point
the plant cannot rest at would mislead a controller design. So is one at which a
polynomial state space clips a monomial's argument (the monomials hold their boundary
values beyond the range the fit let them span, so the slopes there are those of the
clipping, not of the plant).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from blockid.errors import EstimationError, ParameterError

__all__ = ["SETTLE_SAMPLES", "linearise"]

#: Samples the model is run from rest at ``u_0`` before Newton's method polishes the state.
SETTLE_SAMPLES = 2000
#: Newton iterations on ``x - f(x, u_0) = 0``.
NEWTON_ITERATIONS = 50
#: The equilibrium's accuracy: ``|x - f(x, u_0)|`` relative to ``1 + |x|`` (max-norm).
TOLERANCE = 1e-12


def _operating_input(model: Any, u0: Any) -> np.ndarray:
    """``u_0`` as one physical value per input (default the input offset)."""
    nu = len(model.inputs)
    if u0 is None:
        return np.asarray(model.input_offset, dtype=float).reshape(nu).copy()
    value = np.asarray(u0, dtype=float).reshape(-1)
    if value.size == 1 and nu > 1:
        value = np.full(nu, float(value[0]))
    if value.size != nu or not np.all(np.isfinite(value)):
        raise ParameterError(
            f"the operating point needs one finite input value, or one per input "
            f"({nu}: {', '.join(model.inputs)}), got {np.asarray(u0).tolist()}",
            parameter="operating_point",
        )
    return value


def _residual(model: Any, x: np.ndarray, un: np.ndarray) -> np.ndarray:
    return x - model.step(x, un)[0]


def _settle(model: Any, un: np.ndarray) -> np.ndarray:
    """The state after running from rest at ``un`` until it stops moving (at most
    :data:`SETTLE_SAMPLES` samples); rest (0) if the run diverges."""
    x = np.zeros(model.nx)
    for _ in range(SETTLE_SAMPLES):
        x_next = model.step(x, un)[0]
        if not np.all(np.isfinite(x_next)) or np.abs(x_next).max() > 1e12:
            return np.zeros(model.nx)
        moved = np.abs(x_next - x).max()
        x = x_next
        if moved <= TOLERANCE * (1.0 + np.abs(x).max()):
            break
    return x


def _newton(model: Any, x: np.ndarray, un: np.ndarray) -> np.ndarray | None:
    """Newton's method on ``r(x) = x - f(x, un)`` from ``x``, the step halved until
    ``|r|`` falls; None if it does not converge."""
    eye = np.eye(model.nx)
    r = _residual(model, x, un)
    for _ in range(NEWTON_ITERATIONS):
        if np.abs(r).max() <= TOLERANCE * (1.0 + np.abs(x).max()):
            return x
        jacobian = eye - model.step_jacobians(x, un)[0]
        try:
            step = np.linalg.solve(jacobian, -r)
        except np.linalg.LinAlgError:
            step = np.linalg.lstsq(jacobian, -r, rcond=None)[0]
        for _halving in range(30):
            trial = x + step
            r_trial = _residual(model, trial, un)
            if np.all(np.isfinite(r_trial)) and np.abs(r_trial).max() < np.abs(r).max():
                break
            step = step / 2
        else:
            return None  # no step lowers the residual: no equilibrium nearby
        x, r = trial, r_trial
    return x if np.abs(r).max() <= TOLERANCE * (1.0 + np.abs(x).max()) else None


def _clipped(model: Any, z: np.ndarray) -> list[str]:
    """The coordinates of ``z = [x; u_n]`` a polynomial state space clips (those its
    monomials take, outside or on the bounds of ``[lower, upper]``)."""
    expo = getattr(model, "exponents", None)
    if expo is None or not expo.size:
        return []
    names = [f"x{i + 1}" for i in range(model.nx)] + [f"input {u}" for u in model.inputs]
    used = expo.any(axis=0)
    inside = (model.lower < z) & (z < model.upper)
    return [
        f"{names[i]} = {z[i]:.6g} (range {model.lower[i]:.6g} .. {model.upper[i]:.6g})"
        for i in np.flatnonzero(used & ~inside)
    ]


def linearise(model: Any, u0: Any = None) -> dict[str, Any]:
    """The model linearised at its equilibrium for the constant input ``u0`` (module
    docstring), in physical units.

    Parameters
    ----------
    model : PolynomialStateSpace, StateSpace or BlockStateSpace
        Any model with ``step(x, u_n)`` and ``step_jacobians(x, u_n)``.
    u0 : float or array_like, optional
        The operating input in the data's units, one value or one per input; default the
        input offset (the middle of the estimation data).

    Returns
    -------
    dict
        ``"A"``, ``"B"``, ``"C"``, ``"D"`` (from ``u - u0`` to ``y - y*``, the state the
        deviation ``x - x*``), ``"states"`` (names), ``"input_offset"`` (``u0``),
        ``"output_offset"`` (``y*``), ``"equilibrium_state"`` (``x*``, the model's
        normalised state) and ``"spectral_radius"`` (of ``A``): the keys of
        :func:`~blockid.models.export.state_space_matrices`, which returns this for a
        nonlinear model.

    Raises
    ------
    EstimationError
        No equilibrium found, an unstable one, or one where the monomials' arguments are
        clipped (the message says which and what to try).
    ParameterError
        ``u0`` of the wrong size, or a model without a one-step map.

    Examples
    --------
    >>> from blockid.models import PolynomialStateSpace
    >>> m = PolynomialStateSpace(["u"], ["y"], A=[[0.5]], B=[[1.0]], C=[[1.0]], D=[[0.0]],
    ...                          E=[[0.1, 0.2]], F=[[0.0, 0.0]], exponents=[[0, 0], [2, 0]])
    >>> op = linearise(m, u0=0.0)
    >>> round(float(op["equilibrium_state"][0]), 6), round(float(op["A"][0, 0]), 6)
    (0.219224, 0.587689)
    """
    if not hasattr(model, "step_jacobians"):
        raise ParameterError(
            f"a {type(model).__name__} has no one-step state map to linearise; linearise "
            "a state-space model (linear, polynomial or block)"
        )
    u0 = _operating_input(model, u0)
    su, sy = np.asarray(model.input_scale, dtype=float), np.asarray(model.output_scale, dtype=float)
    un = (u0 - np.asarray(model.input_offset, dtype=float)) / su
    at = f"u0 = {', '.join(f'{v:.6g}' for v in u0)}"
    with np.errstate(all="ignore"):
        x = _newton(model, _settle(model, un), un)
    if x is None or not np.all(np.isfinite(x)):
        raise EstimationError(
            f"the model has no equilibrium at {at}: neither running it from rest nor "
            f"Newton's method finds a state with x = f(x, u0); choose another operating "
            "point (operating_point=) inside the estimation data's input range"
        )
    clipped = _clipped(model, np.r_[x, un])
    if clipped:
        raise EstimationError(
            f"the equilibrium at {at} lies where the monomials' arguments are clipped "
            f"({'; '.join(clipped)}): beyond the range the fit let them span the model's "
            "slopes are the clipping's, not the plant's; choose an operating point inside "
            "the estimation data's range"
        )
    A, B, C, D = (np.asarray(m, dtype=float) for m in model.step_jacobians(x, un))
    radius = float(np.abs(np.linalg.eigvals(A)).max())
    if not radius < 1.0:
        raise EstimationError(
            f"the equilibrium at {at} is unstable (the linearisation's largest pole has "
            f"magnitude {radius:.6g} >= 1), so the model cannot rest there and no stable "
            "equilibrium was found; choose another operating point, or export the tangent "
            "at x = 0 with to_control(model.linear_part())"
        )
    yn = model.step(x, un)[1]
    return {
        "A": A, "B": B / su[None, :], "C": sy[:, None] * C,
        "D": sy[:, None] * D / su[None, :], "states": [f"x{i + 1}" for i in range(model.nx)],
        "input_offset": u0, "output_offset": np.asarray(model.output_offset) + sy * yn,
        "equilibrium_state": x, "spectral_radius": radius,
    }  # fmt: skip
