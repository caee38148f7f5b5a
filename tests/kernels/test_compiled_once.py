"""A kernel is compiled once, whatever arrays the library hands it: a model's frozen
(read-only) parameter arrays and a fit's fresh ones are one numba type after
``blockid._kernels.writable`` (before it, one test run compiled the polynomial state
space's free run six times, and most kernels twice)."""

import subprocess
import sys
import textwrap

import numpy as np

from blockid._kernels import writable

SCRIPT = textwrap.dedent(
    """
    import numpy as np
    from reference import squared_state_record
    from blockid import fit_model
    from blockid._kernels import feedback, simulation, state_space
    data = squared_state_record(400)
    u = data.experiments[0].u
    model = fit_model(data, "polynomial-state-space", nx=2, degree=3, max_nfev=3).model
    model.simulate(u), model.states(u)
    lure = fit_model(data, "feedback", na=2, nb=1, nk=1, max_nfev=3).model
    lure.simulate(u)
    hammer = fit_model(data, "hammerstein", na=2, nb=2, nk=1, max_nfev=3).model
    hammer.simulate(u)
    from blockid._kernels import rls
    from blockid.estimators import AdaptiveWeightedRLS, RecursiveLeastSquares
    rng = np.random.default_rng(0)
    for frozen in (False, True):  # a caller's regressors, writable or read-only
        Phi, y = rng.standard_normal((50, 3)), rng.standard_normal(50)
        Phi.flags.writeable = y.flags.writeable = not frozen
        RecursiveLeastSquares().fit(Phi, y)
        AdaptiveWeightedRLS().fit(Phi, y)
    kernels = {
        "rls_run": rls.rls_run,
        "aw_rls_run": rls.aw_rls_run,
        "pnlss_simulate": state_space.pnlss_simulate,
        "pnlss_trajectory": state_space.pnlss_trajectory,
        "pnlss_trajectory_jacobians": state_space.pnlss_trajectory_jacobians,
        "pnlss_local_jacobians": state_space.pnlss_local_jacobians,
        "pnlss_sensitivities": state_space.pnlss_sensitivities,
        "pnlss_sensitivities_serial": state_space.pnlss_sensitivities_serial,
        "feedback_simulate": feedback.feedback_simulate,
        "feedback_sensitivity": feedback.feedback_sensitivity,
        "allpole_run": simulation.allpole_run,
    }
    print({name: len(k.signatures) for name, k in kernels.items()})
    """
)


def test_the_kernels_of_fits_simulations_and_estimators_are_compiled_for_one_type():
    """The free runs and sensitivities of the polynomial state space, the feedback and
    the chain models, and the RLS kernels behind the regressor-level estimators (fed
    writable and read-only arrays), in a process of its own (``signatures``: the types compiled or loaded from the
    cache in this process, as the calls asked for them)."""
    import os
    from pathlib import Path

    tests = Path(__file__).resolve().parents[1]
    env = {**os.environ, "PYTHONPATH": str(tests)}
    out = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                         env=env, check=True, timeout=600)  # fmt: skip
    counts = eval(out.stdout.strip().splitlines()[-1])  # noqa: S307 - our own dict literal
    # a small model's walk runs on the calling thread (pnlss_walk chooses by size): the
    # one-pass trajectory with its Jacobians and the serial walk, never the parallel forms
    assert counts.pop("pnlss_trajectory_jacobians") == counts.pop("pnlss_sensitivities_serial") == 1
    parallel = ("pnlss_trajectory", "pnlss_local_jacobians", "pnlss_sensitivities")
    assert [counts.pop(name) for name in parallel] == [0, 0, 0]
    assert counts == dict.fromkeys(counts, 1)


def test_writable_copies_only_what_numba_would_compile_again():
    a = np.arange(6.0).reshape(2, 3)
    assert writable(a) is a
    frozen = a.copy()
    frozen.flags.writeable = False
    strided = a[:, ::2]
    for arr in (frozen, strided):
        out = writable(arr)
        assert out is not arr and out.flags.writeable and out.flags.c_contiguous
        np.testing.assert_array_equal(out, arr)
