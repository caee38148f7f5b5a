"""Paper B's key-term RLS with internal-variable estimation (B4, B5).

Key-term separation makes the Hammerstein-Wiener model linear in its parameters once
the unmeasured internal signals ``w`` and ``x`` are known (B4):

.. math::

    y(k) = \\sum_{l=0}^{r_1} f_l u^l(k-n_k) + \\sum_{l=0}^{r_1} p_l u^l(k-n_k) h(u(k-n_k))
           + \\sum_{i\\ge 1} b_i w(k-n_k-i) - \\sum_{j=1}^{n_a} a_j x(k-j)
           + \\sum_{m=2}^{r_2} q_m x^m(k)

with ``b_0 = q_1 = 1``. The recursion (B5) replaces ``w`` and ``x`` by estimates
computed sample by sample from the newest parameters and takes one RLS step with a
forgetting factor; passes over the data repeat until the parameters stop changing.
The compiled pass is :func:`blockid._kernels.key_term.key_term_run`; the passes, checks
and read-back are run by :func:`blockid.fitting.recursive.fit_recursive`, to which this
module describes the algorithm (:class:`KeyTermRLS`).

The same algorithm with a block removed gives paper B's comparison models:
``"hammerstein"`` (no ``q``; ``x = y`` is measured), ``"wiener"`` (``w = u``, ``b_0``
free) and ``"arx"`` (both removed: plain RLS on the ARX regressor).

Choices (SPEC leaves them open):

* The forgetting schedule restarts with every pass (paper B: lambda = 0.98 over the
  first 200 samples of the data, 1 afterwards); ``theta`` and ``P`` are carried from
  pass to pass. The restart discounts the previous pass, whose regressors were built
  from older internal-signal estimates, by 0.98^200 ~ 0.02, so a pass re-estimates
  from mostly fresh internal signals and the passes converge to a fixed point of the
  iteration. Counting the schedule once over all passes instead leaves lambda = 1 and
  a shrinking ``P`` after the first pass: later passes barely move the estimate and,
  in our experiments, never reached the tolerance (docs/convergence.md).
* Every experiment, in every pass, starts with the internal signals at rest (0 before
  its first sample); ``theta`` and ``P`` are carried from one experiment to the next.
  Convergence is as :mod:`blockid.fitting.recursive` describes: every parameter
  changed by less than ``tol * (1 + |theta_i|)`` over the last pass.
* The recursion runs on ``u / std(u)``, ``y / std(y)`` (``normalize=True``) and the
  parameters are mapped back exactly; on raw signals its behaviour depends on the
  units (``P(0) = 1e6 I`` meets ``x^3`` of large signals).
* Divergence is detected while running: a non-finite RLS step, an internal signal
  ``|x_hat|`` beyond ``1e6 (1 + max|y|)``, and, after every pass, an unstable linear
  block. The returned model then passes :func:`~blockid.fitting.check_model`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from blockid._kernels import key_term as _k
from blockid._kernels.rls import OK
from blockid.blocks import Polynomial, TwoSegmentPolynomial
from blockid.data.dataset import Dataset
from blockid.defaults import DEGREE, RECURSIVE
from blockid.errors import ParameterError
from blockid.estimators.forgetting import ForgettingSchedule
from blockid.fitting.key_term_channels import (
    KEY_TERM_AT_LEAST,
    ChannelKeyTermRLS,
    fit_key_term_channels,
)
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
from blockid.models.arx import ARX
from blockid.models.base import MODEL_TYPES
from blockid.models.block import BlockModel

_KT = RECURSIVE["key-term-rls"]

__all__ = ["KEY_TERM_STRUCTURES", "KeyTermRLS", "fit_key_term_rls"]

#: Structures :func:`fit_key_term_rls` identifies: (input block?, output block?).
KEY_TERM_STRUCTURES = {
    "hammerstein-wiener": (True, True),
    "hammerstein": (True, False),
    "wiener": (False, True),
    "arx": (False, False),
}


def _layout(structure: str, na: int, nb: int, r1: int, r2: int) -> list[str]:
    """Names of the entries of theta in the order of (B4)."""
    has_in, has_out = KEY_TERM_STRUCTURES[structure]
    names = []
    if has_in:
        names += [f"f_{l}" for l in range(r1 + 1)] + [f"p_{l}" for l in range(r1 + 1)]
    names += [f"b_{i}" for i in range(1 if has_in else 0, nb)]
    names += [f"a_{j}" for j in range(1, na + 1)]
    if has_out:
        names += [f"q_{m}" for m in range(2, r2 + 1)]
    return names


def _unscale(structure: str, na: int, nb: int, r1: int, r2: int, su: float, sy: float):
    """Factors taking theta on ``u/su, y/sy`` back to the data's units (element-wise).

    With ``w, x`` scaled like ``y``: ``f_l, p_l`` scale by ``sy/su^l``, ``b`` by
    ``sy/su`` without an input block (else 1), ``a`` by 1 and ``q_m`` by ``sy^(1-m)``.
    """
    has_in, has_out = KEY_TERM_STRUCTURES[structure]
    parts = []
    if has_in:
        fp = sy / su ** np.arange(r1 + 1)
        parts += [fp, fp, np.ones(nb - 1)]
    else:
        parts.append(np.full(nb, sy / su))
    parts.append(np.ones(na))
    if has_out:
        parts.append(sy ** (1.0 - np.arange(2, r2 + 1)))
    return np.concatenate(parts)


class KeyTermRLS(RecursiveAlgorithm):
    """Key-term RLS (B5) for one structure, on ``u / su`` and ``y / sy``.

    ``theta`` is ordered as in (B4): ``f_0..f_r1, p_0..p_r1`` (input block), ``b``,
    ``a_1..a_na``, ``q_2..q_r2`` (output block).
    """

    # one recursion, one or several inputs: the same names and failure reasons
    method, label = ChannelKeyTermRLS.method, ChannelKeyTermRLS.label
    reasons = ChannelKeyTermRLS.reasons

    def __init__(
        self,
        structure: str,
        orders: tuple[int, int, int, int, int],
        schedule: ForgettingSchedule,
        mu: float,
        signals: Signals,
    ) -> None:
        na, nb, nk, r1, r2 = orders
        self.structure = structure
        self.orders = orders  # na, nb, nk, r1, r2
        self.has_in, self.has_out = KEY_TERM_STRUCTURES[structure]
        self.schedule = schedule  # lambda over the updates of a pass (restarts every pass)
        self.names = _layout(structure, na, nb, r1, r2)
        self.n0 = largest_lag(na, nb, nk)
        ia = (2 * r1 + 2 if self.has_in else 0) + nb - (1 if self.has_in else 0)
        self.a = slice(ia, ia + na)
        self.sy = signals.y_map[1]  # to report |x_hat| in the data's units
        self.y_max = signals.y_max
        # P's trace bound, and the |x_hat| beyond which the recursion has diverged
        self.limits = np.array([mu * len(self.names), 1e6 * (1.0 + self.y_max)])
        self.factors = _unscale(structure, na, nb, r1, r2, signals.u_map[1], self.sy)

    def run(self, theta, P, u, y, count, hist, stride):
        na, nb, nk, r1, r2 = self.orders
        N, n0 = u.size, self.n0
        lam = np.ones(N)
        lam[n0:] = self.schedule.factors(count, N - n0)
        orders = np.array(
            [r1, nb, na, r2, nk, self.has_in, self.has_out, n0, stride], dtype=np.int64
        )
        w, x = np.empty(N), np.empty(N)
        status, reason = _k.key_term_run(
            theta, P, u, y, lam, orders, self.limits, w, x, hist, np.empty(N)
        )
        detail = ""
        if status != OK and self.has_out:
            x_max = float(np.max(np.abs(x[:status]), initial=0.0)) * self.sy
            detail = (
                f" (largest |x_hat| so far {x_max:.3g}, largest |y| {self.y_max * self.sy:.3g})"
            )
        return status, reason, detail

    def to_data_units(self, theta):
        return theta * self.factors

    def from_data_units(self, theta):
        return theta / self.factors

    def model(self, theta, data):
        """The identified model from theta (B4 order)."""
        na, nb, nk, r1, _ = self.orders
        pos = 0
        kwargs: dict[str, Any] = dict(na=na, nb=nb, nk=nk, sampling_time=data.sampling_time)
        if self.has_in:
            f, p = theta[: r1 + 1], theta[r1 + 1 : 2 * r1 + 2]
            kwargs["input_block"] = TwoSegmentPolynomial(f, p)
            pos = 2 * r1 + 2
            b = np.concatenate(([1.0], theta[pos : pos + nb - 1]))
            pos += nb - 1
        else:
            b = theta[pos : pos + nb]
            pos += nb
        a = theta[pos : pos + na]
        pos += na
        kwargs.update(a=a, b=b)
        if self.has_out:
            q = np.concatenate(([1.0], theta[pos:]))
            kwargs["output_block"] = Polynomial(q, constant=False)
        u_name, y_name = data.inputs[0], data.outputs[0]
        if not (self.has_in or self.has_out):  # both blocks removed: plain ARX
            return ARX(
                [u_name],
                [y_name],
                na,
                nb,
                nk,
                a={y_name: {y_name: a}},
                b={y_name: {u_name: b}},
                sampling_time=data.sampling_time,
            )
        cls = MODEL_TYPES[self.structure]  # a chain of models.block, imported above
        return cls.cascade(
            u_name,
            y_name,
            input_block=kwargs.pop("input_block", None),
            output_block=kwargs.pop("output_block", None),
            **kwargs,
        )

    def model_to_check(self, model):
        """An ARX result is checked as the same linear model without blocks."""
        if self.has_in or self.has_out:
            return model
        na, nb, nk, _, _ = self.orders
        y_name, u_name = model.outputs[0], model.inputs[0]
        return BlockModel(
            u_name,
            y_name,
            na=na,
            nb=nb,
            nk=nk,
            a=model.a[y_name][y_name],
            b=model.b[y_name][u_name],
            sampling_time=model.sampling_time,
        )

    def settings(self, common):
        na, nb, nk, r1, r2 = self.orders
        settings = {
            "structure": self.structure,
            "na": na,
            "nb": nb,
            "nk": nk,
            "forgetting": str(self.schedule),
            **common,
        }
        if self.has_in:
            settings["r1"] = r1
        if self.has_out:
            settings["r2"] = r2
        return settings


def fit_key_term_rls(
    data: Dataset,
    structure: str,
    *,
    na: int = 3,
    nb: int = 3,
    nk: int = 8,
    r1: int = DEGREE,
    r2: int = DEGREE,
    forgetting: float | str | ForgettingSchedule = _KT["forgetting"],  # type: ignore[assignment]
    passes: int = _KT["passes"],  # type: ignore[assignment]
    tol: float = _KT["tol"],  # type: ignore[assignment]
    initial_covariance: float = _KT["initial_covariance"],  # type: ignore[assignment]
    initial_parameters: Any = 0.01,
    normalize: bool = True,
    record_history: bool = False,
    scales: tuple[float, float] | None = None,
) -> FitResult:
    """Identify a block-oriented model by paper B's key-term RLS (B4, B5).

    Parameters
    ----------
    data : Dataset
        One output and one input; several experiments are processed one after another.
        With several inputs (one output) the same recursion runs channel by channel,
        paper B's two-segment polynomial of order ``r1`` on every input
        (:func:`~blockid.fitting.key_term_channels.fit_key_term_channels`; ``nk`` may
        then give one delay per input).
    structure : {"hammerstein-wiener", "hammerstein", "wiener", "arx"}
        Which blocks the model has (paper B's H-W model and its comparison models).
    na, nb, nk : int
        Linear block orders, MATLAB convention (``nb`` counts ``b_0``, fixed to 1 when
        there is an input block). Paper B: ``na = 3, nb = 3, nk = 8``.
    r1, r2 : int
        Degrees of the two-segment input polynomial (B1, ``>= 1``) and of the output
        polynomial (B3, ``>= 2``). Ignored for a structure without that block.
    forgetting : float, str or ForgettingSchedule
        Forgetting factor or schedule (paper B: ``"0.98:200,1"``), restarting with every
        pass; read once, before anything else, so a bad value fails at once.
    passes : int
        Maximum number of passes over the data.
    tol : float
        Convergence tolerance on the relative parameter change over one pass.
    initial_covariance : float
        ``P(0) = initial_covariance * I`` (paper B: 1e6), for the normalised signals
        when ``normalize``.
    initial_parameters : float or sequence
        ``theta(0)``: a number is used for every entry of the recursion's vector (on the
        normalised signals when ``normalize``; paper: small equal values); a sequence gives
        ``theta(0)`` in the data's units, in the order of ``history["names"]``.
    normalize : bool
        Run the recursion on ``u / std(u)`` and ``y / std(y)`` and map the parameters
        back exactly (default). Only divided, never shifted: the polynomial blocks are
        not invariant to offsets (the two segments meet at ``u = 0``, the output
        polynomial has no constant). The papers work on raw signals
        (``normalize=False``); then
        convergence depends on the units: the same plant with ``u`` in other units
        fails in the first samples (too large) or stalls (too small).
    record_history : bool
        Keep the parameter trajectory (decimated to at most ``history_rows`` rows,
        :mod:`blockid.config`, in the data's units) in ``result.history``: ``"theta"``
        (rows), ``"names"``, ``"update"`` (update count of every row, counted over all passes).
    scales : (float, float), optional
        Fixed scales ``(s_u, s_y)`` used instead of the measured spreads: the recursion
        runs on ``u / s_u`` and ``y / s_y`` (``normalize`` is then not used). This is
        what online learning with ``input_scale``, ``output_scale`` does
        (:mod:`blockid.fitting.online`), which cannot measure a spread in advance.

    Returns
    -------
    FitResult
        ``model`` is a :class:`~blockid.models.HammersteinWiener`,
        :class:`~blockid.models.Hammerstein`, :class:`~blockid.models.Wiener` or
        :class:`~blockid.models.ARX`; with several inputs a
        :class:`~blockid.models.block_state_space.BlockStateSpace` (an ARX without
        blocks).

    Raises
    ------
    EstimationError
        The recursion diverged (non-finite step, exploding internal signal, unstable
        linear block after a pass), did not converge in ``passes``, or the model fails
        :func:`~blockid.fitting.check_model`.

    Examples
    --------
    A Hammerstein plant (two-segment input block, paper B's orders) driven by white
    noise:

    >>> import numpy as np
    >>> from blockid.blocks import TwoSegmentPolynomial
    >>> from blockid.data import Dataset
    >>> from blockid.models import Hammerstein
    >>> n1 = TwoSegmentPolynomial.from_segments(positive=[0, 0.3, 0.1], negative=[0, 0.15])
    >>> plant = Hammerstein("u", "y", input_block=n1, na=3, nb=3, nk=8,
    ...                     a=[-0.9, -0.01, 0.105], b=[1.0, 0.5, 0.2])
    >>> u = np.random.default_rng(0).uniform(-1.0, 1.0, 3000)
    >>> data = Dataset.from_arrays(u, plant.simulate(u), inputs=["u"], outputs=["y"])
    >>> fit = fit_key_term_rls(data, "hammerstein", r1=2)
    >>> fit.settings["converged"], np.round(fit.model.a, 4).tolist()
    (True, [-0.9, -0.01, 0.105])
    """
    method = KeyTermRLS.method
    schedule = ForgettingSchedule.parse(forgetting)  # once, before any data work
    if structure not in KEY_TERM_STRUCTURES:
        raise ParameterError(
            f"unknown structure {structure!r} for key-term RLS; choose one of "
            f"{', '.join(KEY_TERM_STRUCTURES)}"
        )
    has_in, has_out = KEY_TERM_STRUCTURES[structure]
    if isinstance(data, Dataset) and data.n_inputs > 1:  # one output: else it says so
        return _several_inputs(data, structure, scales, na=na, nb=nb, nk=nk, r1=r1, r2=r2,
                               forgetting=schedule, passes=passes, tol=tol,
                               initial_covariance=initial_covariance,
                               initial_parameters=initial_parameters, normalize=normalize,
                               record_history=record_history)  # fmt: skip
    check_siso(data, method)
    na, nb, nk = orders_at_least(KEY_TERM_AT_LEAST, na=na, nb=nb, nk=nk)
    r1 = checked("r1", r1) if has_in else 0
    # the method's own minimum: key-term separation needs a nonlinear output block
    r2 = orders_at_least(KEY_TERM_AT_LEAST, r2=r2)[0] if has_out else 1
    passes, tol = checked("passes", passes), checked("tol", tol)  # one declaration
    mu = checked("initial_covariance", initial_covariance)
    n = len(_layout(structure, na, nb, r1, r2))
    data.check_orders(
        largest_lag(na, nb, nk), n, what=f"key-term RLS {structure} na={na}, nb={nb}, nk={nk}"
    )
    if scales is None:
        signals = normalised_signals(data, normalize)
    else:
        signals = given_scale_signals(data, scales)
    algorithm = KeyTermRLS(structure, (na, nb, nk, r1, r2), schedule, mu, signals)
    return fit_recursive(
        data,
        signals,
        algorithm,
        initial_parameters=initial_parameters,
        initial_covariance=mu,
        passes=passes,
        tol=tol,
        record_history=record_history,
    )


def _several_inputs(data: Dataset, structure: str, scales: Any, **options: Any) -> FitResult:
    """Several inputs, one output: the same recursion channel by channel
    (:func:`~blockid.fitting.key_term_channels.fit_key_term_channels`), with paper B's
    two-segment polynomial of order ``r1`` on every input."""
    has_in, has_out = KEY_TERM_STRUCTURES[structure]
    r1, r2 = options.pop("r1"), options.pop("r2")
    return fit_key_term_channels(
        data,
        input_block=f"two-segment-polynomial:degree={checked('r1', r1)}" if has_in else None,
        output_block=(
            f"polynomial:degree={orders_at_least(KEY_TERM_AT_LEAST, r2=r2)[0]}" if has_out else None
        ),
        scales=scales,
        **options,
    )
