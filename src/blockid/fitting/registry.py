"""The one registry of model structures, their estimators and their options.

Every structure is declared here once: the blocks it has, the methods that identify it
(the first is the default), and for each method the options it takes. Everything else
is generated from this declaration: :func:`~blockid.fitting.fit_model` resolves and
checks options with it, the command line builds its ``--help`` and its flags from it,
the model-level estimators (:mod:`blockid.fitting.estimator`) take their keywords from
it, and the tests check that every option reaches its fitter.

An option is declared once in :data:`OPTIONS` (:mod:`blockid.fitting.options`, one
layer below, where the fitters read it) with its type, its allowed range and its help
text. :meth:`Option.convert` turns a Python value *or* the text a user typed (on the
command line or in a ``key=value`` network spec) into the typed value, and names the
Python parameter when the value is wrong (the command line maps that name to its flag).

=====================  ==========================================  ==================
structure              methods                                     default
=====================  ==========================================  ==================
arx                    batch, rls, aw-rls, hierarchical-rls        batch
hammerstein            simulation-error, key-term-rls              simulation-error
wiener                 simulation-error, key-term-rls              simulation-error
hammerstein-wiener     simulation-error, key-term-rls              simulation-error
backlash               simulation-error, aw-rls                    simulation-error
output-error           simulation-error                            simulation-error
wiener-hammerstein     simulation-error                            simulation-error
feedback               simulation-error                            simulation-error
=====================  ==========================================  ==================

``integrator`` (output-error, hammerstein, backlash, wiener-hammerstein with method
simulation-error) puts an :class:`~blockid.blocks.integrator.Integrator` after the last
linear block, for plants that integrate; :func:`blockid.fitting.dispatch.run_method`
wires it for any such method (:mod:`blockid.fitting.integrator`).

``identify``'s search space is declared here too: a structure's ``search_rank`` puts it
in the default search, its ``slots`` name the block options every block family fills
(:attr:`blockid.blocks.base.Block.search_specs`), and ``search`` adds fixed option sets.
A new structure or block is searched without editing the search.

Estimators and model classes are named by loaders (:mod:`blockid.fitting._targets`),
imported only when a fit runs, so that importing the registry (and the CLI) stays cheap.
The options themselves are declared one layer down, in :mod:`blockid.fitting.options`,
which the fitters read (and re-exported here).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from blockid.errors import ParameterError
from blockid.fitting import _targets
from blockid.fitting.options import OPTIONS, Option, checked, option_flag, parse_orders

__all__ = [
    "COMPARED_BY_DEFAULT",
    "COMPARED_MULTIVARIABLE",
    "compared_by_default",
    "OPTIONS",
    "STRUCTURES",
    "Method",
    "Option",
    "Structure",
    "check_compared",
    "checked",
    "get_structure",
    "option_flag",
    "parse_orders",
    "resolve_options",
    "searched_structures",
]


# ----------------------------------------------------------------------------- methods
@dataclass(frozen=True)
class Method:
    """An estimator of a structure: the function that runs it and the options it takes.

    ``loader`` returns the function (:mod:`blockid.fitting._targets`: it imports the
    fitting module when called, so declaring a method loads none);
    :func:`blockid.fitting.dispatch.run_method` calls it as ``function(data,
    structure=..., method=..., **options)``, the keywords ``structure``/``method`` only
    where ``passes`` names them. The registry only declares: nothing here runs a fit.
    """

    name: str
    loader: Callable[[], Callable[..., Any]]
    options: tuple[str, ...]
    help: str
    recursive: bool = False
    #: Which of "structure" and "method" the function takes as keywords.
    passes: tuple[str, ...] = ()

    def function(self) -> Callable[..., Any]:
        return self.loader()


@dataclass(frozen=True)
class Structure:
    """A model structure: name, model class (its loader), blocks, methods (default first)."""

    name: str
    model_loader: Callable[[], type]
    help: str
    methods: tuple[Method, ...]
    #: Options every method of the structure takes (handled by fit_model itself).
    common: tuple[str, ...] = ()
    #: Fit around the operating point unless told otherwise.
    center_default: bool = False
    block_oriented: bool = True
    #: A linear model (no static block, no state monomials): ``identify`` chooses a
    #: model beyond linear only when it beats the best linear one consistently.
    linear: bool = False
    #: Place in ``identify``'s default search (smaller first); None: searched only when
    #: asked for by name. The search list is this field, never a list of names.
    search_rank: int | None = None
    #: The block slots ``identify`` fills with every block family that declares the
    #: role (:attr:`blockid.blocks.base.Block.search_specs`): ``(role, option)`` pairs,
    #: e.g. ``("input", "input_block")``.
    slots: tuple[tuple[str, str], ...] = ()
    #: Option sets ``identify`` adds to the linear orders (and to the slots' blocks),
    #: most telling first.
    search: tuple[dict[str, Any], ...] = ({},)
    #: Smallest input delay the structure's fit takes (a loop needs one sample).
    min_delay: int = 0
    #: The search gives the structure ``nb = na + 1`` (a proper BLA of a chain).
    proper: bool = False
    #: How the search gives the structure its orders: ``"polynomial"`` (``na, nb, nk``
    #: of the order stages) or ``"state"`` (a state dimension ``nx``).
    orders: str = "polynomial"
    #: With ``integrator``: the structure and options fitted to the differenced output
    #: for the start, where the structure's own blocks cannot carry the operating point
    #: (None: the structure itself).
    integrator_start: tuple[str, dict[str, Any]] | None = None
    method_names: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "method_names", tuple(m.name for m in self.methods))

    @property
    def default_method(self) -> Method:
        return self.methods[0]

    def method(self, name: str | None) -> Method:
        """The method called ``name`` (None: the default)."""
        if name is None:
            return self.default_method
        for m in self.methods:
            if m.name == name:
                return m
        raise ParameterError(
            f"method={name!r} does not apply to {self.name}; choose one of "
            f"{', '.join(self.method_names)}"
        )

    def accepted(self, method: str | None) -> tuple[str, ...]:
        """Options of this structure fitted by ``method``, in declaration order."""
        return self.common + self.method(method).options

    def model_class(self) -> type:
        return self.model_loader()


_ORDERS = ("na", "nb", "nk")
_RECURSIVE = ("initial_covariance", "passes")
_ARX = _ORDERS + ("center", "allow_unstable", "standard_errors")
_SIMULATION_ERROR = ("max_nfev", "tail_fraction", "patience", "ftol", "xtol", "gtol")
_PAPER = ("passes", "tol", "initial_covariance", "initial_parameters", "normalize")


def _arx_method(name: str, options: tuple[str, ...], help: str) -> Method:
    return Method(
        name,
        _targets.fit_arx,
        _ARX + options,
        help,
        recursive=name != "batch",
        passes=("method",),
    )


def _block_methods(blocks: tuple[str, ...], paper: Method) -> tuple[Method, ...]:
    return (
        Method(
            "simulation-error",
            _targets.fit_simulation_error,
            blocks + _SIMULATION_ERROR,
            "minimise the free-run simulation error (converges; the default)",
            passes=("structure",),
        ),
        paper,
    )


def _key_term(blocks: tuple[str, ...]) -> Method:
    return Method(
        "key-term-rls",
        _targets.fit_key_term_rls,
        blocks + ("forgetting",) + _PAPER + ("record_history",),
        "paper B's key-term RLS with internal-variable estimation (B4, B5)",
        recursive=True,
        passes=("structure",),
    )


_CHECK = ("convergence_check", "max_mse_ratio")
_STATE_SPACE = ("nx", "max_order", "horizon", "weighting", "feedthrough", "standard_errors")
_REFINEMENT = ("max_nfev", "tail_fraction", "patience", "ftol", "xtol", "gtol")

#: The structures, in the order the command line lists them.
STRUCTURES: dict[str, Structure] = {
    s.name: s
    for s in (
        Structure(
            "arx",
            _targets.ARX,
            "linear ARX, multi-input multi-output (MATLAB na/nb/nk)",
            (
                _arx_method("batch", (), "batch least squares (QR)"),
                _arx_method(
                    "rls",
                    ("forgetting",) + _RECURSIVE + _CHECK,
                    "recursive least squares with forgetting factor or schedule",
                ),
                _arx_method(
                    "aw-rls",
                    ("eps1", "eps2") + _RECURSIVE + _CHECK,
                    "adaptive-weighted RLS (A8)",
                ),
                _arx_method(
                    "hierarchical-rls",
                    ("forgetting",) + _RECURSIVE + _CHECK,
                    "hierarchical RLS, one sub-estimator per output lag group (A10)",
                ),
            ),
            block_oriented=False,
            linear=True,
            search_rank=0,
        ),
        Structure(
            "hammerstein",
            _targets.Hammerstein,
            "static input block, then a linear block (N1-L)",
            _block_methods(("r1", "input_block", "integrator"), _key_term(("r1",))),
            common=_ORDERS + ("center", "refine", "standard_errors"),
            search_rank=3,
            slots=(("input", "input_block"),),
        ),
        Structure(
            "wiener",
            _targets.Wiener,
            "linear block, then a static output block (L-N2)",
            _block_methods(("r2", "output_block"), _key_term(("r2",))),
            common=_ORDERS + ("center", "refine", "standard_errors"),
            center_default=True,
            search_rank=4,
            slots=(("output", "output_block"),),
        ),
        Structure(
            "hammerstein-wiener",
            _targets.HammersteinWiener,
            "input block, linear block, output block (N1-L-N2, paper B)",
            _block_methods(("r1", "r2", "input_block", "output_block"), _key_term(("r1", "r2"))),
            common=_ORDERS + ("center", "refine", "standard_errors"),
            search_rank=5,
            slots=(("input", "input_block"), ("output", "output_block")),
        ),
        Structure(
            "backlash",
            _targets.BacklashModel,
            "backlash, then a linear block (paper A's pseudo-Hammerstein)",
            _block_methods(
                ("integrator",),
                Method(
                    "aw-rls",
                    _targets.fit_backlash_aw_rls,
                    ("eps1", "eps2") + _PAPER + ("record_history",),
                    "paper A's adaptive-weighted RLS with internal-variable estimation (A8)",
                    recursive=True,
                ),
            ),
            common=_ORDERS + ("center", "refine", "standard_errors"),
            min_delay=1,
            search_rank=7,
        ),
        Structure(
            "output-error",
            _targets.OutputError,
            "linear output-error model B/A, fitted on free-run simulation error",
            (
                Method(
                    "simulation-error",
                    _targets.fit_simulation_error,
                    ("integrator",) + _SIMULATION_ERROR,
                    "minimise the free-run simulation error from a least-squares ARX start",
                    passes=("structure",),
                ),
            ),
            common=_ORDERS + ("center", "standard_errors"),
            center_default=True,
            # an input offset: the velocity of an integrating plant need not vanish at
            # the mean input, so the start carries an affine input block
            integrator_start=("hammerstein", {"input_block": "polynomial:degree=1"}),
            linear=True,
            search_rank=1,
        ),
        Structure(
            "wiener-hammerstein",
            _targets.WienerHammerstein,
            "linear, static polynomial, linear (L1-N-L2), from the split of the BLA",
            (
                Method(
                    "simulation-error",
                    _targets.fit_wiener_hammerstein,
                    ("r2", "integrator") + _SIMULATION_ERROR,
                    "split the best linear approximation's poles and zeros, score every "
                    "split, refine the best on free-run simulation error",
                ),
            ),
            common=_ORDERS + ("center", "standard_errors"),
            center_default=True,
            search=({"r2": 5},),
            proper=True,
            search_rank=6,
        ),
        Structure(
            "state-space",
            _targets.StateSpace,
            "linear state space x(k+1) = A x + B u, y = C x + D u, multi-input multi-output: "
            "subspace (MOESP or CVA), refined on the free-run error",
            (
                Method(
                    "simulation-error",
                    _targets.fit_state_space,
                    _STATE_SPACE + _REFINEMENT,
                    "subspace estimate, then every parameter refined on the free-run error",
                ),
                Method(
                    "subspace",
                    _targets.fit_subspace,
                    _STATE_SPACE,
                    "subspace estimate only (MOESP or CVA weighting)",
                ),
            ),
            block_oriented=False,
            linear=True,
            orders="state",
            search_rank=8,
        ),
        Structure(
            "polynomial-state-space",
            _targets.PolynomialStateSpace,
            "polynomial nonlinear state space (PNLSS): A x + B u + E z(x, u), C x + D u + "
            "F z(x, u), monomials z of degree 2..r, started from the linear state space",
            (
                Method(
                    "simulation-error",
                    _targets.fit_polynomial_state_space,
                    _STATE_SPACE
                    + ("degree", "monomials", "margin", "start_degree", "rung_nfev")
                    + _REFINEMENT,
                    "linear state-space start, then every parameter refined on the free-run "
                    "error with the monomials",
                ),
            ),
            block_oriented=False,
            orders="state",
            search_rank=9,
        ),
        Structure(
            "block-state-space",
            _targets.BlockStateSpace,
            "a static block per input and/or output channel around a linear state space "
            "(Hammerstein, Wiener, Hammerstein-Wiener of several inputs and outputs)",
            (
                Method(
                    "simulation-error",
                    _targets.fit_block_state_space,
                    ("input_block", "output_block", "loop_block") + _STATE_SPACE + _REFINEMENT,
                    "linear state-space start with every input and output block near the "
                    "identity and every loop open, then every parameter refined on the "
                    "free-run error (exact Jacobian)",
                ),
                Method(
                    "batch",
                    _targets.fit_block_arx,
                    ("input_block", "output_block", "na", "nb", "nk"),
                    "Hammerstein on a matrix-ARX core: least squares on the input powers, "
                    "each channel's block split off by a rank-1 approximation",
                    passes=("method",),
                ),
                Method(
                    "rls",
                    _targets.fit_block_arx,
                    (
                        "input_block",
                        "output_block",
                        "na",
                        "nb",
                        "nk",
                        "forgetting",
                        "initial_covariance",
                        "passes",
                    ),
                    "Hammerstein on a matrix-ARX core: RLS on the input powers (online: "
                    "stream, partial_fit), each channel's block split off by a rank-1 "
                    "approximation",
                    recursive=True,
                    passes=("method",),
                ),
                Method(
                    "key-term-rls",
                    _targets.fit_key_term_block,
                    ("input_block", "output_block", "na", "nb", "nk", "forgetting", "center")
                    + _PAPER
                    + ("record_history",),
                    "paper B's key-term RLS for one output of several inputs (online: "
                    "stream, partial_fit; default: two-segment polynomial per input, cubic "
                    "output block)",
                    recursive=True,
                ),
            ),
            block_oriented=False,
            orders="state",
            search_rank=10,
        ),
        Structure(
            "feedback",
            _targets.LinearFeedback,
            "linear block with a static nonlinearity of the output (polynomial, dead zone, "
            "saturation, piecewise-linear) fed back to its input (Lur'e form: Duffing "
            "oscillator, Silverbox)",
            (
                Method(
                    "simulation-error",
                    _targets.fit_feedback,
                    ("r", "feedback_block") + _SIMULATION_ERROR,
                    "equation-error start, then minimise the free-run simulation error",
                ),
            ),
            common=_ORDERS + ("center", "standard_errors"),
            center_default=True,
            min_delay=1,
            search_rank=2,
            slots=(("feedback", "feedback_block"),),
        ),
    )
}


def searched_structures() -> tuple[str, ...]:
    """The structures ``identify`` searches by default: those with a ``search_rank``,
    in its order."""
    ranked = [s for s in STRUCTURES.values() if s.search_rank is not None]
    return tuple(s.name for s in sorted(ranked, key=lambda s: s.search_rank))


#: The structures ``compare`` identifies unless told otherwise (paper B's four).
COMPARED_BY_DEFAULT = ("arx", "hammerstein", "wiener", "hammerstein-wiener")
#: ... on data of several inputs or outputs, which the chain structures cannot take.
COMPARED_MULTIVARIABLE = ("arx", "state-space", "polynomial-state-space")


def compared_by_default(n_inputs: int, n_outputs: int) -> tuple[str, ...]:
    """The structures ``compare`` and ``report`` identify unless told otherwise, by the
    data's shape: paper B's four on one input and one output, else ARX and the linear
    and polynomial state space."""
    return COMPARED_BY_DEFAULT if n_inputs == n_outputs == 1 else COMPARED_MULTIVARIABLE


def get_structure(name: Any) -> Structure:
    """The declaration of structure ``name``, or a clear error listing the known ones."""
    if name not in STRUCTURES:
        raise ParameterError(
            f"structure={name!r} is unknown; choose one of {', '.join(STRUCTURES)}"
        )
    return STRUCTURES[name]


def check_compared(structures: Sequence[str], method: str | None) -> None:
    """Refuse what a comparison of ``structures`` would drop or fail on late: no or an
    unknown structure, a shared ``method`` none of them offers (each structure takes the
    method where it offers it, else its default)."""
    if not structures:
        raise ParameterError(
            "no structure to compare; name at least one, e.g. arx,hammerstein",
            parameter="structures",
        )
    unknown = [s for s in structures if s not in STRUCTURES]
    if unknown:
        raise ParameterError(
            f"structures {unknown} are unknown; choose among {', '.join(STRUCTURES)}",
            parameter="structures",
        )
    if method is not None and not any(method in STRUCTURES[s].method_names for s in structures):
        raise ParameterError(
            f"method={method!r} is offered by none of {', '.join(structures)}", parameter="method"
        )


#: Option kinds whose conversion imports the numerical stack (blocks, schedules);
#: :func:`resolve_options` with ``light=True`` leaves their values to the fit.
_HEAVY_KINDS = ("block", "forgetting")


def resolve_options(
    structure: str, method: str | None, options: dict[str, Any], *, light: bool = False
) -> tuple[Structure, str, dict[str, Any]]:
    """Check ``options`` against the registry and convert their values.

    Returns the structure, the method name and the typed options (``None`` values
    dropped: the method's default applies). An option the method does not use is an
    error that lists the ones it does. ``light=True`` (the command line, before it
    imports NumPy) checks everything but the block and forgetting values, which are
    returned as given.
    """
    decl = get_structure(structure)
    chosen = decl.method(method)
    given = {k: v for k, v in options.items() if v is not None}
    accepted = decl.accepted(chosen.name)
    unused = [k for k in given if k not in accepted]
    if unused:
        raise ParameterError(
            f"{', '.join(unused)} not used by {structure} with method {chosen.name}; it takes "
            f"{', '.join(accepted)}",
            parameter=unused[0],
        )
    converted = {
        k: v if light and OPTIONS[k].kind in _HEAVY_KINDS else OPTIONS[k].convert(v)
        for k, v in given.items()
    }
    return decl, chosen.name, {k: v for k, v in converted.items() if v is not None}
