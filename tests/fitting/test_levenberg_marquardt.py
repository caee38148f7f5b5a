"""Levenberg-Marquardt on the normal equations: where it stops, and why."""

import numpy as np

from blockid.fitting.levenberg_marquardt import levenberg_marquardt


class _Tracker:
    def __init__(self) -> None:
        self.nfev = 0
        self.njev = 0


class _Curve:
    """Residuals ``y - a exp(b t)`` of a noisy exponential: a small problem with a unique
    optimum that Gauss-Newton reaches in a few steps."""

    def __init__(self, seed: int = 0) -> None:
        rng = np.random.default_rng(seed)
        self.t = np.linspace(0, 1, 50)
        self.y = 2.0 * np.exp(-1.5 * self.t) + 0.01 * rng.standard_normal(50)
        self.tracker = _Tracker()

    def residuals(self, theta):
        self.tracker.nfev += 1
        return self.y - theta[0] * np.exp(theta[1] * self.t)

    def normal_equations(self, theta):
        self.tracker.njev += 1
        e = np.exp(theta[1] * self.t)
        J = -np.column_stack([e, theta[0] * self.t * e])
        r = self.y - theta[0] * e
        return J.T @ J, J.T @ r  # the gradient of the cost: J = dr/dtheta


def test_a_converged_fit_stops_on_ftol_at_the_least_squares_optimum():
    problem = _Curve()
    bounds = (np.full(2, -np.inf), np.full(2, np.inf))
    theta, reason = levenberg_marquardt(problem, np.array([1.0, -1.0]), bounds, 200, 1e-10,
                                        1e-15, 1e-15)  # fmt: skip
    assert "ftol" in reason
    H, g = problem.normal_equations(theta)
    assert np.linalg.norm(g) < 1e-6 * np.linalg.norm(H)  # a stationary point
    np.testing.assert_allclose(theta, [2.0, -1.5], atol=0.05)


def test_a_step_that_gains_little_where_the_model_predicts_more_is_no_convergence():
    """A problem whose trial steps fall short of the prediction (the residual carries a
    term the Jacobian ignores, so every accepted step gains a small fraction of what was
    predicted): the ftol test asks the predicted reduction to be small too, and the
    solver goes on until the cost stops moving, not at the first small gain."""

    class Crawl(_Curve):
        def residuals(self, theta):
            r = super().residuals(theta)
            return r + 1e-3 * np.sin(50 * theta[0])  # unmodelled ripple

    problem = Crawl()
    bounds = (np.full(2, -np.inf), np.full(2, np.inf))
    theta, reason = levenberg_marquardt(problem, np.array([1.0, -1.0]), bounds, 500, 1e-6,
                                        1e-15, 1e-15)  # fmt: skip
    # stopped as converged only where the predicted gain was small as well
    np.testing.assert_allclose(theta, [2.0, -1.5], atol=0.1)
    assert problem.tracker.nfev > 5
