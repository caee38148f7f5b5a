"""Paper A's AW-RLS for the backlash model with internal-variable estimation (A6–A8).

The backlash (A3) followed by a linear block with ``b_0 = 1`` (A5, MATLAB orders),

.. math::

    v(t) = \\sum_{i=0}^{n_b-1} b_i x(t-n_k-i) - \\sum_{j=1}^{n_a} a_j v(t-j),
    \\qquad b_0 = 1,

becomes linear in :math:`\\theta = [m_L, m_L c_L, m_R, m_R c_R, b_1..b_{nb-1},
a_1..a_{na}]` once the key term ``x(t - nk)`` is replaced by the switching form of the
backlash (A4, A6). The unmeasured ``x`` and switching values ``f1, f2`` are estimated
with the newest parameters (A7) and ``theta`` is updated by adaptive-weighted RLS (A8):
see :mod:`blockid._kernels.backlash_awrls`. Paper A's S2 is ``na = 2, nb = 1, nk = 1``
(its ``mf = 1, nf = 2``).

The backlash is read back as ``m_L = theta_1, c_L = theta_2/theta_1, m_R = theta_3,
c_R = theta_4/theta_3``; slopes that are not positive or dead-band widths that are
negative make that read-back meaningless and are reported as
:class:`~blockid.errors.EstimationError`, as are divergence (non-finite step, exploding
internal signal, unstable linear block after a pass) and a model that fails
:func:`~blockid.fitting.check_model`.

Several experiments are processed one after another, each starting with the internal
signals at rest; ``theta`` and ``P`` are carried over, also from pass to pass. The
passes, checks and read-back are run by :func:`blockid.fitting.recursive.fit_recursive`,
to which this module describes the algorithm (:class:`BacklashAWRLS`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from blockid._kernels import backlash_awrls as _k
from blockid.blocks import Backlash
from blockid.data.dataset import Dataset
from blockid.defaults import RECURSIVE
from blockid.errors import EstimationError, ParameterError
from blockid.fitting.options import checked
from blockid.fitting.recursive import (
    RecursiveAlgorithm,
    Signals,
    check_siso,
    fit_recursive,
    given_scale_signals,
    largest_lag,
    normalised_signals,
    orders_at_least,
)
from blockid.fitting.result import FitResult
from blockid.models.block import BacklashModel

_AW = RECURSIVE["backlash-aw-rls"]

__all__ = ["BACKLASH_AT_LEAST", "BacklashAWRLS", "fit_backlash_aw_rls"]

#: The smallest orders the AW-RLS backlash fit (paper A's A6-A8) takes, declared once for
#: the batch fit and its online form: the backlash's output enters one sample late at
#: the earliest (nk >= 1), with one input coefficient at least.
BACKLASH_AT_LEAST = {"na": 0, "nb": 1, "nk": 1}


def _names(na: int, nb: int) -> list[str]:
    """Names of the entries of theta (A6)."""
    return (
        ["m_left", "m_left*c_left", "m_right", "m_right*c_right"]
        + [f"b_{i}" for i in range(1, nb)]
        + [f"a_{j}" for j in range(1, na + 1)]
    )


def _read_backlash(theta: np.ndarray) -> Backlash:
    """``Backlash.from_theta`` with the failure explained in terms of the estimate."""
    m_left, m_right = float(theta[0]), float(theta[2])
    if not (m_left > 0.0 and m_right > 0.0):
        raise EstimationError(
            f"AW-RLS ended with backlash slopes m_left = theta_1 = {m_left:.4g} and "
            f"m_right = theta_3 = {m_right:.4g}; both must be > 0 for the dead-band widths "
            "c = theta_2/theta_1, theta_4/theta_3 to mean anything, so no model is returned. "
            "The input probably does not reverse often enough, or far enough beyond the "
            "dead band, to excite the backlash. See docs/convergence.md"
        )
    c_left, c_right = float(theta[1]) / m_left, float(theta[3]) / m_right
    if c_left < 0.0 or c_right < 0.0:
        raise EstimationError(
            f"AW-RLS ended with a negative dead-band half-width: c_left = {c_left:.4g}, "
            f"c_right = {c_right:.4g} (theta_2/theta_1, theta_4/theta_3); a backlash needs "
            "both >= 0, so no model is returned. See docs/convergence.md"
        )
    return Backlash.from_theta(theta[:4])


def _to_data_units(theta: np.ndarray, u_map: tuple, v_map: tuple, nb: int) -> np.ndarray:
    """Theta (rows) on ``(u - u0)/su, (v - v0)/sv`` back to the data's units.

    The backlash and linear block are equivariant under these maps. The linear
    block's steady state links the offsets, ``x0 = v0 A(1) / B(1)``; then
    ``m = m~ sv/su``, ``m_L c_L = sv (m_L c_L)~ - m_L u0 + x0`` and
    ``m_R c_R = sv (m_R c_R)~ + m_R u0 - x0``; ``a, b`` are unchanged.
    """
    (u0, su), (v0, sv) = u_map, v_map
    t = np.array(theta, dtype=float)
    ia = 4 + nb - 1
    with np.errstate(divide="ignore", invalid="ignore"):
        x0 = v0 * (1.0 + t[..., ia:].sum(axis=-1)) / (1.0 + t[..., 4:ia].sum(axis=-1))
    x0 = np.where(v0 == 0.0, 0.0, x0)
    out = t.copy()
    out[..., 0] = t[..., 0] * sv / su
    out[..., 2] = t[..., 2] * sv / su
    out[..., 1] = sv * t[..., 1] - out[..., 0] * u0 + x0
    out[..., 3] = sv * t[..., 3] + out[..., 2] * u0 - x0
    return out


def _from_data_units(theta: np.ndarray, u_map: tuple, v_map: tuple, nb: int) -> np.ndarray:
    """Inverse of :func:`_to_data_units` for one vector."""
    (u0, su), (v0, sv) = u_map, v_map
    ia = 4 + nb - 1
    x0 = v0 * (1.0 + theta[ia:].sum()) / (1.0 + theta[4:ia].sum()) if v0 else 0.0
    out = theta.copy()
    out[0] = theta[0] * su / sv
    out[2] = theta[2] * su / sv
    out[1] = (theta[1] + theta[0] * u0 - x0) / sv
    out[3] = (theta[3] - theta[2] * u0 + x0) / sv
    return out


def _check_branches_excited(switching: list[tuple[np.ndarray, ...]]) -> None:
    """Raise unless the estimated backlash drove along both branches at two inputs each.

    ``m_L, c_L`` enter (A6) only through samples with ``f1 = 1`` (``m_R, c_R`` through
    ``f2 = 1``); with fewer than two distinct inputs on a branch they are not
    determined by the data and keep whatever value they started from.
    """
    for branch, label in ((1, "left (f1)"), (2, "right (f2)")):
        driven = np.concatenate([u[f[branch - 1] > 0.5] for u, *f in switching])
        if np.unique(driven).size < 2:
            raise EstimationError(
                f"AW-RLS: the estimated backlash drove along its {label} branch at "
                f"{np.unique(driven).size} distinct input value(s) in the last pass, so that "
                "branch's slope and dead band are not determined by these data and no model "
                "is returned. Use an input that reverses well beyond the dead band, in both "
                "directions. See docs/convergence.md"
            )


class BacklashAWRLS(RecursiveAlgorithm):
    """AW-RLS (A8) with internal-variable estimation (A7) on the centred, normalised
    signals; ``theta`` is ordered as in (A6)."""

    method = "AW-RLS"
    label = "aw-rls"
    reasons = {
        _k.REASON_STEP: "the AW-RLS update became non-finite or lost positive definiteness",
        _k.REASON_EXPLODED: "the estimated backlash output x exceeded 1e6 (1 + max|v|)",
        _k.REASON_ZERO_SLOPE: "a slope estimate (theta_1 or theta_3) reached exactly 0, "
        "where the dead-band edges of (A7) are undefined",
    }

    def __init__(
        self, orders: tuple[int, int, int], eps: tuple[float, float], signals: Signals
    ) -> None:
        na, nb, nk = orders
        self.orders = orders  # na, nb, nk
        self.eps = eps  # eps1, eps2 of the adaptive weight (A8)
        self.names = _names(na, nb)
        self.n0 = largest_lag(na, nb, nk)
        self.a = slice(4 + nb - 1, 4 + nb - 1 + na)
        self.u_map, self.v_map = signals.u_map, signals.y_map
        # eps1, eps2 and the |x_hat| beyond which the recursion has diverged
        self.params = np.array([eps[0], eps[1], 1e6 * (1.0 + signals.y_max)])
        # (u, f1, f2) of every experiment in the current pass: which branches were driven
        self.switching: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []

    def run(self, theta, P, u, v, count, hist, stride):
        na, nb, nk = self.orders
        N = u.size
        orders = np.array([nb, na, nk, self.n0, stride], dtype=np.int64)
        x, f1, f2 = np.empty(N), np.empty(N), np.empty(N)
        if count == 0:  # a new pass
            self.switching.clear()
        self.switching.append((u, f1, f2))
        status, reason = _k.backlash_aw_rls_run(
            theta, P, u, v, orders, self.params, x, f1, f2, hist, np.empty(N)
        )
        return status, reason, ""

    def to_data_units(self, theta):
        return _to_data_units(theta, self.u_map, self.v_map, self.orders[1])

    def from_data_units(self, theta):
        return _from_data_units(theta, self.u_map, self.v_map, self.orders[1])

    def model(self, theta, data):
        """Read back (A6): the backlash from ``theta_1..theta_4``, then ``b, a``."""
        if not np.all(np.isfinite(theta)):
            raise EstimationError(
                "AW-RLS: the linear block's static gain B(1) is 0, so the backlash offset cannot "
                "be recovered from the centred signals; use normalize=False. See "
                "docs/convergence.md"
            )
        _check_branches_excited(self.switching)
        return self.read_back(theta, data)

    def read_back(self, theta, data):
        """The model of a finite ``theta`` (data units), without :meth:`model`'s check
        that the last pass drove both branches (online learning has no passes)."""
        na, nb, nk = self.orders
        try:
            block = _read_backlash(theta)
            return BacklashModel(
                data.inputs[0],
                data.outputs[0],
                input_block=block,
                na=na,
                nb=nb,
                nk=nk,
                a=theta[self.a],
                b=np.concatenate(([1.0], theta[4 : self.a.start])),
                sampling_time=data.sampling_time,
            )
        except ParameterError as exc:  # pragma: no cover - _read_backlash checks first
            raise EstimationError(f"AW-RLS returned an invalid backlash: {exc}") from None

    def settings(self, common):
        na, nb, nk = self.orders
        settings = {"na": na, "nb": nb, "nk": nk, "eps1": self.eps[0], "eps2": self.eps[1]}
        for key in ("initial_covariance", "initial_parameters", "passes", "passes_run"):
            settings[key] = common[key]
        settings.update(converged=common["converged"], normalize=common["normalize"])
        if common["passes"] > 1:  # tol is not used in one pass
            settings["tol"] = common["tol"]
        return settings


def fit_backlash_aw_rls(
    data: Dataset,
    *,
    na: int = 2,
    nb: int = 1,
    nk: int = 1,
    eps1: float = _AW["eps1"],  # type: ignore[assignment]
    eps2: float = _AW["eps2"],  # type: ignore[assignment]
    initial_covariance: float = _AW["initial_covariance"],  # type: ignore[assignment]
    initial_parameters: Any = 0.01,
    passes: int = _AW["passes"],  # type: ignore[assignment]
    tol: float = _AW["tol"],  # type: ignore[assignment]
    normalize: bool = True,
    record_history: bool = False,
    scales: tuple[float, float] | None = None,
) -> FitResult:
    """Identify a backlash + linear model (paper A's S2) by AW-RLS (A6–A8).

    Parameters
    ----------
    data : Dataset
        One input (backlash input ``u``), one output (``v``).
    na, nb, nk : int
        Linear block orders, MATLAB convention with ``b_0 = 1`` fixed; ``nk >= 1``.
        Paper A: ``na = 2, nb = 1, nk = 1``.
    eps1, eps2 : float
        AW-RLS weight ``lambda(t) = eps1 s(t) + eps2`` (A8), ``eps1 >= 0`` and ``eps2 > 0``
        (the weight's floor once ``s`` vanishes). Paper A
        gives no values, only that a large ``eps1`` helps from bad initial conditions
        and a small ``eps2`` keeps convergence fast. With ``eps1 = 1`` the first
        samples, processed while the internal signals are still wrong, can throw the
        estimate far off and (there is no forgetting) leave a lasting error: on 30
        records of 5000 noise-free samples one ended 32 % off. ``eps1 = 10`` (default)
        damps them: all 30 within 2e-6; ``eps1 = 100`` slows convergence (~1 %).
    initial_covariance : float
        ``P(0) = initial_covariance * I`` (paper A: 1e5), for the normalised signals
        when ``normalize``.
    initial_parameters : float or sequence
        ``theta(0)``: a number is used for every entry of the recursion's vector (on the
        normalised signals when ``normalize``; paper A: 0.01); a sequence gives
        ``theta(0)`` in the data's units, in the order of ``history["names"]``.
    passes : int
        Passes over the data (paper A: one). With more, they stop early once every
        parameter changes by less than ``tol * (1 + |theta_i|)`` over a pass, and not
        reaching that is an error.
    tol : float
        Convergence tolerance for ``passes > 1``.
    normalize : bool
        Run the recursion on ``(u - mean) / std`` and ``(v - mean) / std`` and map the
        parameters back exactly (default); ``False`` works on the raw signals as paper
        A does. On signals recorded around a large operating point (paper A's are
        absolute positions in mm) the raw recursion is badly conditioned: the columns
        ``u f1`` and ``f1`` of (A6) are nearly parallel and the dead-band widths, small
        differences of large numbers, come out wrong or negative.
    record_history : bool
        Keep the trajectory of ``theta`` (in the data's units) in ``result.history``
        (``"theta"``, ``"names"``, ``"update"``).
    scales : (float, float), optional
        Fixed scales ``(s_u, s_v)`` used instead of the measured spreads, without
        centring: the recursion runs on ``u / s_u`` and ``v / s_v`` (``normalize`` is
        then not used), as online learning with ``input_scale``, ``output_scale`` does
        (:mod:`blockid.fitting.online`).

    Returns
    -------
    FitResult
        ``model`` is a :class:`~blockid.models.BacklashModel`.

    Examples
    --------
    Paper A's choke finger (sign-corrected linear block), a command with a new random
    level every sample:

    >>> import numpy as np
    >>> from blockid.blocks import Backlash
    >>> from blockid.data import Dataset
    >>> from blockid.models import BacklashModel
    >>> s2 = BacklashModel("u2", "v2", input_block=Backlash(0.9, 0.8, 0.9, 0.85),
    ...                    na=2, nb=1, nk=1, a=[-1.0, 0.17])
    >>> u = np.random.default_rng(0).uniform(-5.0, 5.0, 3000)
    >>> data = Dataset.from_arrays(u, s2.simulate(u), inputs=["u2"], outputs=["v2"])
    >>> fit = fit_backlash_aw_rls(data)
    >>> {k: round(v, 4) for k, v in fit.model.input_block.parameters.items()}
    {'m_left': 0.9, 'c_left': 0.8, 'm_right': 0.9, 'c_right': 0.85}
    """
    method = BacklashAWRLS.method
    check_siso(data, method)
    na, nb, nk = orders_at_least(BACKLASH_AT_LEAST, na=na, nb=nb, nk=nk)
    # ranges from the options' one declaration (eps1 = 0 is allowed: lambda = eps2 > 0)
    passes, tol = checked("passes", passes), checked("tol", tol)
    eps1, eps2 = checked("eps1", eps1), checked("eps2", eps2)
    mu = checked("initial_covariance", initial_covariance)
    data.check_orders(
        largest_lag(na, nb, nk),
        len(_names(na, nb)),
        what=f"backlash model na={na}, nb={nb}, nk={nk}",
    )
    if scales is None:
        signals = normalised_signals(data, normalize, center=True)
    else:
        signals = given_scale_signals(data, scales)
    return fit_recursive(
        data,
        signals,
        BacklashAWRLS((na, nb, nk), (eps1, eps2), signals),
        initial_parameters=initial_parameters,
        initial_covariance=mu,
        passes=passes,
        tol=tol,
        record_history=record_history,
    )
