"""The damped Gauss-Newton pose solver (``dgmm.registration.solvers.minimise_gauss_newton``) on a cost written here.

The cost is the squared distance of moved points to their known targets,
``f(R, t') = Σ |R (x_n − c) + c + t' − y_n|²``, with its gradient, Gauss-Newton matrix and exact Hessian over
``(δ, ω)`` (translation ``t' + δ``, left rotation ``exp([ω]x) R``) derived by hand below and checked against central
differences. The true pose is known, so the solver's result is checked against it, not against another solver.
"""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from dgmm.errors import FitError
from dgmm.registration.solvers import minimise_gauss_newton, next_over_relaxation


def skew(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


class PointCost:
    """``Σ |R (x_n − c) + c + t' − y_n|²`` with targets ``y_n`` made by a known pose; counts its evaluations."""

    def __init__(self, seed=0, n=30):
        rng = np.random.default_rng(seed)
        self.points = rng.normal(size=(n, 3)) * [1.0, 0.6, 0.3]
        self.centre = self.points.mean(axis=0)
        self.true_rotation = Rotation.from_rotvec([0.2, -0.3, 0.25]).as_matrix()
        self.true_translation = np.array([0.3, -0.2, 0.1])  # t' of the pose about the centre
        self.targets = self.moved(self.true_rotation, self.true_translation)
        self.radius = np.sqrt(np.mean(np.sum((self.points - self.centre) ** 2, axis=1)))
        self.evaluations = 0

    def moved(self, rotation, translation):
        return (self.points - self.centre) @ rotation.T + self.centre + translation

    def derivatives(self, rotation, translation):
        """Gradient (6,), Gauss-Newton matrix and exact Hessian (6, 6) over (δ, ω).

        With ``p = R (x − c)`` and residual ``r``: ``dr = δ − [p]x ω``, so the gradient is ``2 (Σ r, Σ p x r)``,
        the Gauss-Newton matrix ``2 Σ Jᵀ J`` with ``J = [I, −[p]x]``, and the exact Hessian adds to its ``ωω``
        block ``2 Σ (sym(r pᵀ) − (r·p) I)`` from the second-order term ``½ ω x (ω x p)`` of the rotation."""
        rotated = (self.points - self.centre) @ rotation.T
        residuals = self.moved(rotation, translation) - self.targets
        gradient = 2 * np.concatenate([residuals.sum(axis=0), np.cross(rotated, residuals).sum(axis=0)])
        gauss_newton = np.zeros((6, 6))
        for p in rotated:
            jacobian = np.hstack([np.eye(3), -skew(p)])
            gauss_newton += 2 * jacobian.T @ jacobian
        outer = residuals.T @ rotated
        exact = gauss_newton.copy()
        exact[3:, 3:] += (outer + outer.T) - 2 * np.trace(outer) * np.eye(3)
        return gradient, gauss_newton, exact

    def evaluate(self, rotation, translation, hessians=None):
        """``(cost, derivatives)`` as the solver takes them; ``hessians`` may alter the derivatives."""
        self.evaluations += 1
        if self.evaluations > 5000:
            raise RuntimeError("the solver does not stop")
        cost = float(np.sum((self.moved(rotation, translation) - self.targets) ** 2))
        if hessians is None:
            return cost, lambda: self.derivatives(rotation, translation)
        return cost, lambda: hessians(*self.derivatives(rotation, translation))

    def solve(self, hessians=None, options=None, callback=None, rotation=None, translation=None):
        def evaluate(rotation, translation):
            return self.evaluate(rotation, translation, hessians)
        start_rotation = Rotation.from_rotvec([-0.2, 0.3, 0.1]).as_matrix() if rotation is None else rotation
        return minimise_gauss_newton("test", evaluate, self.centre, self.radius, start_rotation,
                                     np.zeros(3) if translation is None else translation, callback, options)

    def error(self, result):
        """Rotation angle (rad) to the true pose and translation error of the returned ``x -> R x + t``."""
        angle = Rotation.from_matrix(result.rotation @ self.true_rotation.T).magnitude()
        translation = self.centre + self.true_translation - self.true_rotation @ self.centre
        return angle, np.linalg.norm(result.translation - translation)


def test_the_hand_derivatives_match_central_differences():
    cost = PointCost(seed=1)
    rotation, translation = Rotation.from_rotvec([0.4, 0.1, -0.2]).as_matrix(), np.array([0.1, 0.2, -0.3])

    def f(x):
        return cost.evaluate(Rotation.from_rotvec(x[3:]).as_matrix() @ rotation, translation + x[:3])[0]

    gradient, _, exact = cost.derivatives(rotation, translation)
    h = 1e-5
    steps = np.eye(6) * h
    numeric_gradient = np.array([(f(e) - f(-e)) / (2 * h) for e in steps])
    np.testing.assert_allclose(gradient, numeric_gradient, rtol=1e-7, atol=1e-7)
    numeric_hessian = np.array([[(f(a + b) - f(a - b) - f(b - a) + f(-a - b)) / (4 * h * h) for b in steps]
                                for a in steps])
    np.testing.assert_allclose(exact, numeric_hessian, rtol=1e-4, atol=1e-4)


def test_reaches_the_true_pose_from_35_degrees_away():
    """From 35 deg and 0.4 radii away, converged within the stopping tolerance (steps below 1e-8 rad and radii) of
    the known pose."""
    cost = PointCost()
    result = cost.solve()
    angle, translation = cost.error(result)
    assert result.converged and result.method == "test"
    assert angle < 1e-8 and translation < 1e-8 * cost.radius
    assert result.objective < 1e-15


def test_newton_steps_where_the_hessian_is_positive_definite():
    """The exact Hessian is used where positive definite: with it exact and the Gauss-Newton matrix 10,000 times too
    large, the solver still converges in a few Newton steps (quadratic convergence: ≤ 8 iterations). A solver that
    never takes Newton steps crawls with steps 10,000 times too short (over-relaxed at most twice as far per step)
    and stops after 14 iterations 6e-7 rad from the pose (tried)."""
    cost = PointCost()
    result = cost.solve(hessians=lambda g, gauss_newton, exact: (g, 1e4 * gauss_newton, exact),
                        options={"max_iter": 30})
    assert result.converged and result.iterations <= 8
    assert cost.error(result)[0] < 1e-8


def test_gauss_newton_steps_where_the_hessian_is_not_positive_definite():
    """An exact Hessian that is negative definite must not be used (its step goes uphill): the Gauss-Newton
    matrix is, and the solver converges. One that uses any exact Hessian it is given fails (tried)."""
    cost = PointCost()
    result = cost.solve(hessians=lambda g, gauss_newton, exact: (g, gauss_newton, -np.eye(6)),
                        options={"max_iter": 60})
    assert result.converged and cost.error(result)[0] < 1e-8


def test_a_short_full_newton_step_ends_the_solve_without_derivatives_at_its_pose():
    """Newton's steps here shrink 0.15 → 1.1e-3 → 1.4e-9 (quadratic convergence). With ``tol = 1e-3`` the step of
    1.1e-3 is followed by one far below ``tol`` (``κ s² = 100 × 1.2e-6 < tol``): the solver stops on its pose, with
    no derivatives there (4 evaluations of them for 4 steps), within 1.5e-9 of the true pose. A solver that asks
    for the derivatives at the last pose to see that the next step is short evaluates them 5 times."""
    cost = PointCost()
    derivative_calls = []

    def counted(gradient, gauss_newton, exact):
        derivative_calls.append(1)
        return gradient, gauss_newton, exact

    result = cost.solve(hessians=counted, options={"tol": 1e-3})
    assert result.converged and result.iterations == 4 and len(derivative_calls) == 4
    assert cost.error(result)[0] < 1e-8


def test_short_steps_of_a_linearly_converging_solve_do_not_end_it():
    """Gauss-Newton steps (no exact Hessian) with a matrix ``1.5 D G D``, ``D`` doubling the rotation, wrong by a
    different factor in each direction so that no multiplier of the step makes it right: convergence is linear
    (17 iterations). The quadratic stopping rule does not apply to them; applied, it stops 1.5e-5 rad from the
    pose, where the tolerance is 1e-8 (tried)."""
    cost = PointCost()
    scaling = np.diag([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])
    result = cost.solve(hessians=lambda g, gauss_newton, exact: (g, 1.5 * scaling @ gauss_newton @ scaling, None),
                        options={"max_iter": 100})
    angle, translation = cost.error(result)
    assert result.converged and angle < 1e-8 and translation < 1e-8 * cost.radius


def test_over_relaxation_is_the_parabola_s_minimum_up_to_twice_the_last():
    """A kept Gauss-Newton step at 8 times the step: the next multiplier is the minimum of the parabola through the
    cost (10), its slope along the step (-1 per step) and the new cost, at most twice 8 and at least 1."""
    assert next_over_relaxation(10.0, -1.0, 8.0, 10.0 - 8.0 + 3.2) == pytest.approx(10.0)  # curvature 0.05
    assert next_over_relaxation(10.0, -1.0, 8.0, 10.0 - 8.0 + 0.64) == 16.0  # the minimum at 50: twice as far
    assert next_over_relaxation(10.0, -1.0, 8.0, 10.0 - 8.0) == 16.0  # a straight line: twice as far
    assert next_over_relaxation(10.0, -1.0, 8.0, 10.0) == pytest.approx(4.0)  # no lower: half way
    assert next_over_relaxation(10.0, -1.0, 1.0, 10.0) == 1.0  # never below one step


def test_damping_grows_until_a_step_lowers_the_cost():
    """A Gauss-Newton matrix 1e4 times too small (and no exact Hessian) makes every first step 1e4 times too long;
    three backtracks shorten it 1000-fold at most, so only a growing damping λ (x10 per failed search) makes the
    step short enough. The solver must still reach the true pose. Without the escalation it never stops (the
    evaluation counter stops it; tried)."""
    cost = PointCost()
    result = cost.solve(hessians=lambda g, gauss_newton, exact: (g, 1e-4 * gauss_newton, None),
                        options={"max_step": 1e9, "max_iter": 200})
    assert result.converged and cost.error(result)[0] < 1e-8


def test_a_search_that_never_lowers_the_cost_stops_where_it_started():
    """Derivatives that point the wrong way (the gradient negated): no step lowers the cost, λ grows past 1e12
    and the solver gives up after its first iteration at the initial pose, not converged (with ``tol=0``, so that
    a vanishing damped step cannot pass for convergence). The evaluations are 4 per λ (full step and 3
    backtracks) for the 18 values from 1e-4 to 1e13, the first above the 1e12 cap."""
    cost = PointCost()
    start = Rotation.from_rotvec([-0.2, 0.3, 0.1]).as_matrix()
    result = cost.solve(hessians=lambda g, gauss_newton, exact: (-g, gauss_newton, None),
                        options={"tol": 0.0}, rotation=start)
    assert not result.converged and result.iterations == 1
    np.testing.assert_array_equal(result.rotation, start)
    assert cost.evaluations == 1 + 4 * 18


@pytest.mark.parametrize("bad", ["cost", "gradient", "hessian"])
def test_non_finite_cost_or_derivatives_is_a_fit_error(bad):
    cost = PointCost()

    def evaluate(rotation, translation):
        value, derivatives = cost.evaluate(rotation, translation)

        def broken():
            gradient, gauss_newton, exact = derivatives()
            if bad == "gradient":
                gradient = gradient * np.nan
            if bad == "hessian":
                gauss_newton, exact = np.full_like(gauss_newton, np.inf), None
            return gradient, gauss_newton, exact
        return (np.nan if bad == "cost" else value), broken

    with pytest.raises(FitError, match="test registration: the cost or its derivatives are not finite at "
                                       "Gauss-Newton iteration 0"):
        minimise_gauss_newton("test", evaluate, cost.centre, cost.radius, np.eye(3), np.zeros(3), None, None)


def test_callback_sees_every_kept_step_and_the_last_is_the_result():
    cost = PointCost()
    seen = []
    result = cost.solve(callback=lambda iteration, registration: seen.append((iteration, registration)))
    assert [iteration for iteration, _ in seen] == list(range(1, result.iterations + 1))
    assert all(not registration.converged and registration.iterations == iteration for iteration, registration in seen)
    np.testing.assert_array_equal(seen[-1][1].rotation, result.rotation)
    np.testing.assert_array_equal(seen[-1][1].translation, result.translation)
    costs = [registration.objective for _, registration in seen]
    assert all(later <= earlier for earlier, later in zip(costs, costs[1:]))  # kept steps never raise the cost


def test_d2d_gauss_newton_registers_a_mixture_onto_its_moved_copy_exactly():
    """D2D of a mixture fitted to the bunny onto the same mixture moved by a known pose (10 deg, 1 cm): the cost's
    minimum is that pose, so Gauss-Newton must return its inverse to the stopping tolerance (1e-8)."""
    import trimesh

    from conftest import SHARED_DATA
    from dgmm.mixture import GaussianMixture
    from dgmm.registration import register_d2d

    mixture = GaussianMixture(10, random_state=0).fit(trimesh.load(SHARED_DATA / "stanford" / "bunny_res4.ply",
                                                                   process=False))
    rotation = Rotation.from_rotvec(np.radians(10) * np.array([0.6, 0.0, 0.8])).as_matrix()
    translation = np.array([0.01, -0.004, 0.006])
    covariances = rotation @ mixture.covariances_ @ rotation.T
    moved = GaussianMixture.from_parameters(mixture.weights_, mixture.means_ @ rotation.T + translation, covariances)
    result = register_d2d(mixture, moved, solver="gauss-newton")
    assert result.converged
    assert Rotation.from_matrix(result.rotation @ rotation).magnitude() < 1e-8
    np.testing.assert_allclose(result.translation, -rotation.T @ translation, atol=1e-8 * 0.1)
