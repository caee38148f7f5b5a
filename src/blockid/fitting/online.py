"""Online learning: the recursive methods fed a record chunk by chunk or sample by sample.

:func:`online_estimator` builds the backend of
:meth:`blockid.fitting.estimator.ModelEstimator.partial_fit` and ``update`` for every
recursive method of the registry: ARX ``rls``, ``aw-rls`` and ``hierarchical-rls``
(A2, A8, A10), paper B's ``key-term-rls`` (B4, B5) for Hammerstein, Wiener and
Hammerstein-Wiener models (of several inputs channel by channel,
:mod:`blockid.fitting.key_term_channels`, also as ``block-state-space``), and paper A's
``aw-rls`` for the backlash model (A6–A8).

Equivalence contract. The samples of one record fed through
:meth:`OnlineEstimator.partial_fit` in any chunks, or one at a time through
:meth:`OnlineEstimator.update`, end with the estimate of the one-pass offline fit of
that record with the same options and the matching scaling (below): bit for bit, since
the same compiled kernels run the same operations. The kernels continue a pass from a
carried state (``start`` entry of their ``orders``, see
:mod:`blockid._kernels.key_term`): what is carried from chunk to chunk is ``theta``,
``P``, the number of samples seen (where a forgetting schedule stands and when the
first update comes) and the last ``max_lag`` samples of ``u``, ``y`` and of the
internal estimates (``w_hat, x_hat``; ``x_hat, f1_hat, f2_hat`` for the backlash), so
the memory does not grow with the record.

Scaling (a choice). The offline paper fitters divide the signals by their spread over
the whole record (``normalize=True``) and :func:`~blockid.fitting.arx.fit_arx` divides
the regressor columns by their RMS over the record; neither is known before the record
has been seen. Online learning therefore runs on the signals as they are, unless the
user gives the scales, ``input_scale`` and ``output_scale`` (options only online
learning takes: the recursion then runs on ``u / input_scale`` and ``y /
output_scale``, and the parameters are mapped back exactly, as offline). So:

=========================  ================================================================
online options             equal to the offline one-pass fit
=========================  ================================================================
(no scales)                ``fit_key_term_rls(.., normalize=False)`` (several inputs:
                           ``fit_key_term_channels(.., normalize=False)``),
                           ``fit_backlash_aw_rls(.., normalize=False)``,
                           ``fit_arx(.., scaling="none")``
``input_scale=su,``        ``fit_key_term_rls(.., scales=(su, sy))`` (several inputs:
                           ``fit_key_term_channels(.., scales=(su, sy))``),
``output_scale=sy``        ``fit_backlash_aw_rls(.., scales=(su, sy))``,
                           ``fit_arx(.., scaling=(su, sy))``
=========================  ================================================================

all with ``passes=1``. ``initial_covariance`` is relative to the signals so scaled (or
raw): on raw signals far from order one, give the scales (their expected spread) or a
``P(0)`` that fits the units. ``normalize=True`` without scales is refused: there is
no spread to divide by. The papers' recursions run on raw signals in any case.

Other options. ``initial`` (only online) is a model of the structure whose parameters
set ``theta(0)`` (its orders are used where none are given; its offsets must be 0);
``initial_parameters`` sets ``theta(0)`` as offline. Whole-record settings cannot
apply to a stream: ``passes`` must be 1, ``center``, ``refine`` and
``record_history`` are refused, and ``tol``, ``convergence_check``,
``max_mse_ratio``, ``allow_unstable`` (checks of a finished offline fit) are accepted
and not used. Online learning does not centre: a Wiener model, centred by default
offline, is learned around 0.

Divergence. A failing step (non-finite, ``P`` no longer positive definite), an
exploding internal estimate (``|x_hat|`` beyond ``1e6 (1 + max|y|)``, ``max|y|`` over
the samples seen so far) or a zero backlash slope raises
:class:`~blockid.errors.EstimationError` naming the sample (counted from the first
sample fed, also in ``error.sample``); the backend is left as it was before the call,
so a stream can report it and go on or stop.

Not learning from a sample (for a caller that judges samples: the outlier guard of
:mod:`blockid.workflows.stream`). ``update(u, y, learn=False)`` takes a sample into the
learner's memory (the window its regressors reach back into, and the internal
estimates) and returns its prediction, leaving ``theta`` and ``P`` as they were: the
samples after it keep their true lags. :meth:`OnlineEstimator.revert` takes back the
last update's change of the estimate, the sample staying in the memory (a sample judged
by its prediction error, which exists only once the update ran); :meth:`~OnlineEstimator.snapshot`
and :meth:`~OnlineEstimator.rewind` save and put back the estimate alone (``theta``,
``P``, where a forgetting schedule stands), the memory staying current. For ARX the
held sample does not touch the recursion at all; the papers' methods run the step and
put ``theta`` and ``P`` back, so their internal estimates of that sample are the
updated estimate's (their window still moves on).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from blockid.errors import ParameterError
from blockid.fitting.arx import fit_arx
from blockid.fitting.backlash import fit_backlash_aw_rls
from blockid.fitting.block_arx import (
    fit_block_arx,
)
from blockid.fitting.dispatch import resolve_options
from blockid.fitting.key_term import fit_key_term_rls
from blockid.fitting.key_term_channels import fit_key_term_block
from blockid.fitting.online_arx import _OnlineARX, _OnlineBlockARX
from blockid.fitting.online_base import (
    _NOT_USED,
    ONLINE_OPTIONS,
    OnlineEstimator,
    _check_orders_against,
    _refuse_whole_record,
    _scales,
    model_parameters,
)
from blockid.fitting.online_paper import _OnlineBacklash, _OnlineKeyTerm, _OnlineKeyTermChannels

__all__ = ["model_parameters", "ONLINE_OPTIONS", "OnlineEstimator", "online_estimator"]


# ---------------------------------------------------------------------- entry point
def online_estimator(
    structure: str,
    method: str | None,
    options: dict[str, Any],
    inputs: Any,
    outputs: Any,
) -> OnlineEstimator:
    """The online learner of ``structure`` fitted by the recursive ``method``.

    Parameters
    ----------
    structure, method : str
        As in :func:`~blockid.fitting.fit_model`; the method must be recursive.
    options : dict
        The method's options (registry, values may be text), plus ``initial``,
        ``input_scale`` and ``output_scale`` (module docstring).
    inputs, outputs : sequence of str
        Signal names of the model.

    Examples
    --------
    >>> import numpy as np
    >>> from blockid.models import ARX
    >>> plant = ARX(["u"], ["y"], na=1, nb=1, nk=1,
    ...             a={"y": {"y": [-0.5]}}, b={"y": {"u": [2.0]}})
    >>> u = np.random.default_rng(0).standard_normal((300, 1))
    >>> online = online_estimator("arx", "rls", {}, ["u"], ["y"])
    >>> online.partial_fit(u, plant.simulate(u)).n_samples
    300
    >>> {k: np.round(v, 6).tolist() for k, v in online.parameters()["y"]["a"].items()}
    {'y': [-0.5]}
    """
    options = dict(options)
    extra = {k: options.pop(k) for k in ONLINE_OPTIONS if options.get(k) is not None}
    decl, method, opts = resolve_options(structure, method, options)
    if not decl.method(method).recursive:
        raise ParameterError(
            f"method={method!r} of {structure} is not recursive: it cannot learn online. Use "
            f"one of {', '.join(m.name for m in decl.methods if m.recursive)}"
        )
    for key in _NOT_USED:
        opts.pop(key, None)
    _refuse_whole_record(opts)
    names = (tuple(inputs), tuple(outputs))
    initial = extra.get("initial")
    if initial is not None:
        if not isinstance(initial, decl.model_class()):
            raise ParameterError(
                f"initial must be a {decl.model_class().__name__} model (structure "
                f"{structure}), got {type(initial).__name__}"
            )
        if np.any(np.asarray(initial.input_offset) != 0) or np.any(
            np.asarray(initial.output_offset) != 0
        ):
            raise ParameterError(
                "initial has non-zero offsets; online learning does not centre the signals, "
                "so it starts only from a model without offsets"
            )
        if "initial_parameters" in opts:
            raise ParameterError("give initial (a model) or initial_parameters, not both")
        _check_orders_against(initial, opts)
    scales = _scales(extra, opts)
    # the backend of the offline fitter the registry names for this method
    backend = {
        fit_arx: _OnlineARX,
        fit_key_term_rls: _OnlineKeyTerm,
        fit_backlash_aw_rls: _OnlineBacklash,
        fit_block_arx: _OnlineBlockARX,
        fit_key_term_block: _OnlineKeyTermChannels,
    }[decl.method(method).function()]
    if backend is _OnlineKeyTerm and len(names[0]) > 1:  # several inputs: channel by channel
        backend = _OnlineKeyTermChannels
    return backend(structure, method, opts, names, scales, initial)
