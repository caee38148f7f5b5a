"""Model-level estimators in the scikit-learn style, one per structure of the registry.

.. code-block:: python

    import blockid

    est = blockid.HammersteinWienerEstimator(na=3, nb=3, nk=8, r1=3, r2=3)
    est.fit(data)                 # returns est
    est.model_                    # the identified HammersteinWiener model
    est.result_.settings          # what the estimator did
    est.simulate(u)               # free run of the identified model

The contract (scikit-learn, ``sklearn/linear_model/_bayes.py``): the constructor only
stores its keywords; :meth:`ModelEstimator.fit` validates them (through the registry,
:mod:`blockid.fitting.registry`), identifies the model and returns ``self``; what was
learned ends in ``_``. :meth:`~ModelEstimator.get_params` and
:meth:`~ModelEstimator.set_params` work as in scikit-learn.

Recursive methods (``rls``, ``aw-rls``, ``hierarchical-rls`` for ARX, paper B's
``key-term-rls``, paper A's ``aw-rls`` for backlash) also learn online:
:meth:`~ModelEstimator.partial_fit` takes the next chunk of a record and
:meth:`~ModelEstimator.update` the next sample, returning the one-step prediction made
before the sample was used and its error. Fed the samples of a record in any chunks,
they end with the estimate of the one-pass offline fit of that record.

The classes are generated from the registry: a structure added there gets an
estimator here without further code. Their names end in ``Estimator`` because the model
classes (``blockid.models.HammersteinWiener``) and blocks (``blockid.Backlash``) already
carry the plain names.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from blockid.data.dataset import Dataset
from blockid.errors import DataError, ParameterError
from blockid.fitting.registry import STRUCTURES, get_structure

__all__ = [
    "ModelEstimator",
    "ESTIMATORS",
    "ARXEstimator",
    "HammersteinEstimator",
    "WienerEstimator",
    "HammersteinWienerEstimator",
    "BacklashEstimator",
]


def _names(prefix: str, n: int) -> tuple[str, ...]:
    return (prefix,) if n == 1 else tuple(f"{prefix}{i + 1}" for i in range(n))


def _as_dataset(data: Any, y: Any, inputs: Any, outputs: Any) -> Dataset:
    if isinstance(data, Dataset):
        if y is not None:
            raise DataError("give a Dataset, or input and output arrays, not both")
        return data
    if y is None:
        raise DataError("give a Dataset, or the input array and the output array")
    u = np.asarray(data, dtype=float)
    y = np.asarray(y, dtype=float)
    nu = 1 if u.ndim == 1 else u.shape[1]
    ny = 1 if y.ndim == 1 else y.shape[1]
    inputs = list(inputs) if inputs is not None else [f"u{i + 1}" for i in range(nu)]
    outputs = list(outputs) if outputs is not None else [f"y{i + 1}" for i in range(ny)]
    if nu == 1 and inputs == ["u1"]:
        inputs = ["u"]
    if ny == 1 and outputs == ["y1"]:
        outputs = ["y"]
    return Dataset.from_arrays(u, y, inputs, outputs)


class ModelEstimator:
    """Identify a model of one structure; see the module docstring.

    Parameters
    ----------
    method : str, optional
        One of the structure's methods (``registry.STRUCTURES[structure].method_names``);
        the default is the first.
    **options
        The method's options (orders, blocks, settings), as
        :func:`~blockid.fitting.fit_model` takes them. Checked by :meth:`fit`.

    Attributes
    ----------
    model_ : Model
        The identified model.
    result_ : FitResult
        The fit's record (settings, estimation metrics, history).
    n_samples_ : int
        Samples the estimate was learned from.
    """

    structure: ClassVar[str] = ""

    def __init__(self, *, method: str | None = None, **options: Any) -> None:
        self.method = method
        self.options = dict(options)

    # ------------------------------------------------------------------ params
    def get_params(self, deep: bool = True) -> dict[str, Any]:
        """The constructor's keywords."""
        return {"method": self.method, **self.options}

    def set_params(self, **params: Any) -> ModelEstimator:
        """Change constructor keywords; returns ``self``."""
        if "method" in params:
            self.method = params.pop("method")
        self.options.update(params)
        return self

    def __repr__(self) -> str:
        inner = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items() if v is not None)
        return f"{type(self).__name__}({inner})"

    # ------------------------------------------------------------------ batch
    def fit(
        self, data: Any, y: Any = None, *, inputs: Any = None, outputs: Any = None
    ) -> ModelEstimator:
        """Identify the model from a :class:`~blockid.data.Dataset` (or arrays ``u, y``).

        Returns ``self``; the model is ``self.model_``.
        """
        from blockid.fitting.dispatch import fit_model

        dataset = _as_dataset(data, y, inputs, outputs)
        result = fit_model(dataset, self.structure, method=self.method, **self.options)
        self.result_ = result
        self._model = result.model
        self.n_samples_ = result.n_samples
        self._online = None
        return self

    @property
    def model_(self) -> Any:
        """The identified model: of :meth:`fit`, or of the newest online estimate (built
        when asked for, so that an online estimate that has no valid model yet, such as
        a backlash whose slopes are not positive early in a record, does not stop
        learning)."""
        if getattr(self, "_online", None) is not None:
            return self._online.model()
        model = getattr(self, "_model", None)
        if model is None:
            raise ParameterError(
                f"this {type(self).__name__} has no model yet: call fit (or partial_fit) first"
            )
        return model

    def _check_fitted(self) -> None:
        self.model_  # noqa: B018 - raises when there is none

    def simulate(self, u: Any, y_initial: Any = None) -> np.ndarray:
        """Free-run simulation of the identified model."""
        self._check_fitted()
        return self.model_.simulate(u, y_initial)

    def predict(self, u: Any, y: Any) -> np.ndarray:
        """One-step-ahead prediction of the identified model."""
        self._check_fitted()
        return self.model_.predict(u, y)

    def score(self, data: Any, y: Any = None, *, mode: str = "simulation") -> float:
        """Fit percent (NRMSE fit, 100 is perfect) on ``data``, averaged over outputs."""
        from blockid.evaluation.validate import evaluate

        self._check_fitted()
        dataset = _as_dataset(data, y, self.model_.inputs, self.model_.outputs)
        fit = evaluate(self.model_, dataset, mode).metrics["fit_percent"]
        return float(np.mean(list(fit.values())))

    # ------------------------------------------------------------------ online
    def _online_backend(self, names: tuple[tuple[str, ...], tuple[str, ...]]) -> Any:
        from blockid.fitting.online import online_estimator

        decl = get_structure(self.structure)
        method = decl.method(self.method)
        if not method.recursive:
            raise ParameterError(
                f"method={method.name!r} of {self.structure} is not recursive: it cannot "
                f"learn sample by sample. Use one of "
                f"{', '.join(m.name for m in decl.methods if m.recursive)}, or fit"
            )
        return online_estimator(self.structure, method.name, self.options, *names)

    def partial_fit(
        self, data: Any, y: Any = None, *, inputs: Any = None, outputs: Any = None
    ) -> ModelEstimator:
        """Learn from the next chunk of a record (recursive methods); returns ``self``.

        Chunks continue one another: the first samples of a chunk see the last samples
        of the previous one. ``model_`` is the model of the newest estimate.
        """
        dataset = _as_dataset(data, y, inputs, outputs)
        if getattr(self, "_online", None) is None:
            self._online = self._online_backend((dataset.inputs, dataset.outputs))
        for exp in dataset.experiments:
            self._online.partial_fit(exp.u, exp.y)
        self.n_samples_ = self._online.n_samples
        return self

    def update(self, u: Any, y: Any) -> tuple[np.ndarray, np.ndarray]:
        """Learn from one sample; returns the one-step prediction of ``y`` made before
        the update and its error ``y - prediction`` (arrays, one entry per output)."""
        if getattr(self, "_online", None) is None:
            n_u = np.atleast_1d(np.asarray(u, dtype=float)).size
            n_y = np.atleast_1d(np.asarray(y, dtype=float)).size
            names = (_names("u", n_u), _names("y", n_y))
            self._online = self._online_backend(names)
        prediction = self._online.update(u, y)
        self.n_samples_ = self._online.n_samples
        return prediction, np.atleast_1d(np.asarray(y, dtype=float)) - prediction

    @property
    def online_model_(self) -> Any:
        """The model of the newest online estimate (built on demand)."""
        if getattr(self, "_online", None) is None:
            raise ParameterError("nothing learned online yet: call partial_fit or update")
        return self._online.model()


def _class_name(structure: str) -> str:
    special = {"arx": "ARX"}
    base = special.get(structure) or "".join(p.capitalize() for p in structure.split("-"))
    return f"{base}Estimator"


def _make(structure: str) -> type[ModelEstimator]:
    decl = STRUCTURES[structure]
    methods = ", ".join(decl.method_names)
    doc = (
        f"Estimator of {decl.help} models (structure ``{structure}``).\n\n"
        f"Methods: {methods} (default {decl.default_method.name}). See "
        ":class:`ModelEstimator` for the interface and "
        ":mod:`blockid.fitting.registry` for the options of each method."
    )
    return type(_class_name(structure), (ModelEstimator,), {"structure": structure, "__doc__": doc})


#: ``structure -> estimator class``, one per structure of the registry.
ESTIMATORS: dict[str, type[ModelEstimator]] = {name: _make(name) for name in STRUCTURES}

ARXEstimator = ESTIMATORS["arx"]
HammersteinEstimator = ESTIMATORS["hammerstein"]
WienerEstimator = ESTIMATORS["wiener"]
HammersteinWienerEstimator = ESTIMATORS["hammerstein-wiener"]
BacklashEstimator = ESTIMATORS["backlash"]
