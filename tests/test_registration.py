"""Tests of dgmm.registration against independent references: scipy's Rotation, closed-form rotations,
central finite differences, scikit-learn's log-likelihood and a per-pair loop for the D2D cost."""
from functools import partial
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation
from sklearn.mixture import GaussianMixture

from dgmm import InputError
from dgmm.mixture import GaussianMixture as DgmmGaussianMixture
from dgmm import registration as reg
from dgmm.registration import d2d, p2d, pose
from dgmm.registration.fitted import FittedMixture
from dgmm.registration.rotations import exp_rotation

BUNNY = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "stanford" / "bunny_res4.ply"


def _rodrigues(axis, angle_deg):
    """Rotation of ``angle_deg`` about ``axis``: I + sin θ K + (1 − cos θ) K²."""
    x, y, z = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    k = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    theta = np.radians(angle_deg)
    return np.eye(3) + np.sin(theta) * k + (1 - np.cos(theta)) * k @ k


def _random_mixture(rng, n_components):
    """A mixture with random well-conditioned covariances; precisions_cholesky_ as scikit-learn builds it."""
    a = rng.normal(size=(n_components, 3, 3))
    covariances = 0.3 * a @ a.transpose(0, 2, 1) + 0.2 * np.eye(3)
    lower = np.linalg.cholesky(covariances)
    weights = rng.uniform(0.5, 1.0, n_components)
    return SimpleNamespace(weights_=weights / weights.sum(), means_=2 * rng.normal(size=(n_components, 3)),
                           covariances_=covariances,
                           precisions_cholesky_=np.linalg.inv(lower).transpose(0, 2, 1))


def _transformed_mixture(mixture, rotation, translation):
    """The mixture of the moved variable ``R x + t``."""
    covariances = rotation @ mixture.covariances_ @ rotation.T
    return SimpleNamespace(weights_=mixture.weights_, means_=mixture.means_ @ rotation.T + translation,
                           covariances_=covariances,
                           precisions_cholesky_=np.linalg.inv(np.linalg.cholesky(covariances)).transpose(0, 2, 1))


def _central_differences(function, x, step):
    return np.array([(function(x + step * e) - function(x - step * e)) / (2 * step) for e in np.eye(len(x))])


def _random_params(rng):
    """A pose vector (t', q) with an unnormalised quaternion far from the identity."""
    return np.concatenate([0.5 * rng.normal(size=3), rng.normal(size=4)])


@pytest.fixture(scope="module")
def bunny():
    if not BUNNY.exists():
        pytest.skip(f"{BUNNY} not present")
    vertices = np.asarray(trimesh.load(BUNNY, process=False).vertices)
    diagonal = float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))
    mixture = GaussianMixture(20, tol=1e-5, max_iter=100, random_state=0).fit(vertices)
    return SimpleNamespace(vertices=vertices, diagonal=diagonal, mixture=mixture)


@pytest.fixture(scope="module")
def bunny_trial(bunny):
    """A fixed small rigid motion of the bunny: about 7° and 10% of the diagonal."""
    centre = bunny.vertices.mean(axis=0)
    rotation = Rotation.from_euler("xyz", [5.0, -4.0, 3.0], degrees=True).as_matrix()
    return reg.RigidTrial(rotation, np.array([0.01, -0.02, 0.015]), centre)


# ------------------------------------------------------------------------------------------- rotations
def test_quaternion_to_matrix_matches_scipy():
    q = np.random.default_rng(1).normal(size=(20, 4))  # unnormalised on purpose
    expected = Rotation.from_quat(q, scalar_first=True).as_matrix()
    np.testing.assert_allclose(reg.quaternion_to_matrix(q), expected, atol=1e-14)
    np.testing.assert_allclose(reg.quaternion_to_matrix(q[3]), expected[3], atol=1e-14)


def test_matrix_to_quaternion_round_trip():
    rotations = Rotation.random(50, rng=np.random.default_rng(2))
    q = reg.matrix_to_quaternion(rotations.as_matrix())
    reference = rotations.as_quat(scalar_first=True)
    sign = np.sign(np.sum(q * reference, axis=1))[:, None]
    np.testing.assert_allclose(q, sign * reference, atol=1e-12)
    assert np.all(q[:, 0] >= 0)
    np.testing.assert_allclose(reg.quaternion_to_matrix(q), rotations.as_matrix(), atol=1e-12)


def test_rotvec_round_trip_matches_scipy():
    v = np.random.default_rng(3).normal(size=(30, 3))
    v *= (np.random.default_rng(4).uniform(0, np.pi, 30) / np.linalg.norm(v, axis=1))[:, None]
    rotations = reg.rotvec_to_matrix(v)
    np.testing.assert_allclose(rotations, Rotation.from_rotvec(v).as_matrix(), atol=1e-14)
    np.testing.assert_allclose(reg.matrix_to_rotvec(rotations), v, atol=1e-10)


def test_euler_is_static_xyz():
    a, b, c = np.radians([10.0, -7.0, 13.0])
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rz = np.array([[np.cos(c), -np.sin(c), 0], [np.sin(c), np.cos(c), 0], [0, 0, 1]])
    np.testing.assert_allclose(reg.euler_to_matrix([10.0, -7.0, 13.0]), rz @ ry @ rx, atol=1e-14)


@pytest.mark.parametrize("angle", [1e-4, 0.5, 15.0, 90.0, 179.5])
def test_rotation_distance_is_the_closed_form_angle(angle):
    rng = np.random.default_rng(5)
    base = Rotation.random(rng=rng).as_matrix()
    relative = _rodrigues(rng.normal(size=3), angle)
    assert reg.rotation_distance_deg(base, base @ relative) == pytest.approx(angle, rel=1e-9, abs=1e-9)
    assert reg.rotation_distance_deg(relative, np.eye(3)) == pytest.approx(angle, rel=1e-9, abs=1e-9)


# ------------------------------------------------------------------------------------ trials and errors
def test_random_trials_follow_the_protocol():
    diagonal, centre = 2 * reg.BUNNY_DIAGONAL, np.array([0.1, 0.2, 0.3])
    trials = reg.random_trials(200, 7, diagonal, centre)
    angles = Rotation.from_matrix([t.rotation for t in trials]).as_euler("xyz", degrees=True)
    translations = np.array([t.translation for t in trials])
    assert np.all(np.abs(angles) <= 15.0) and np.abs(angles).max() > 14.0
    assert np.all(np.abs(translations) <= 0.1) and np.abs(translations).max() > 0.095
    again = reg.random_trials(200, 7, diagonal, centre)
    np.testing.assert_array_equal(translations, [t.translation for t in again])
    assert not np.allclose(translations, [t.translation for t in reg.random_trials(200, 8, diagonal, centre)])


def test_errors_of_the_exact_inverse_and_of_known_offsets():
    trial = reg.random_trials(1, 11, reg.BUNNY_DIAGONAL, [0.05, -0.02, 0.3])[0]
    c, r, t = trial.centre, trial.rotation, trial.translation
    # The inverse of x -> R(x - c) + c + t is y -> Rᵀ y + c - Rᵀ(c + t).
    exact = reg.Registration(r.T, c - r.T @ (c + t), 0, 0.0, 0.0, True, "test")
    points = np.random.default_rng(12).normal(size=(10, 3))
    np.testing.assert_allclose(exact.apply(trial.apply(points)), points, atol=1e-12)
    assert reg.registration_errors(exact, trial, reg.BUNNY_DIAGONAL) == pytest.approx((0.0, 0.0), abs=1e-9)
    # Follow the exact inverse by a 3° turn about the centre: 3° of rotation error, none of translation.
    turn = _rodrigues([1.0, 2.0, -1.0], 3.0)
    turned = reg.Registration(turn @ exact.rotation, turn @ (exact.translation - c) + c, 0, 0.0, 0.0, True, "t")
    assert reg.registration_errors(turned, trial, reg.BUNNY_DIAGONAL) == pytest.approx((3.0, 0.0), abs=1e-9)
    # Or by a shift d: |d| / diagonal percent of translation error.
    d = np.array([0.001, -0.002, 0.0005])
    shifted = reg.Registration(exact.rotation, exact.translation + d, 0, 0.0, 0.0, True, "t")
    expected = 100 * np.linalg.norm(d) / reg.BUNNY_DIAGONAL
    assert reg.registration_errors(shifted, trial, reg.BUNNY_DIAGONAL) == pytest.approx((0.0, expected), abs=1e-9)


# ------------------------------------------------------------------------------------- costs, gradients
def test_p2d_cost_is_sklearn_negative_mean_log_likelihood():
    rng = np.random.default_rng(20)
    points = rng.normal(size=(200, 3)) * [1.0, 2.0, 0.5]
    mixture = GaussianMixture(5, random_state=0).fit(points)
    params = _random_params(rng)
    rotation, translation = pose.pose_from_params(params, points.mean(axis=0))
    cost = p2d.p2d_cost(params, points, points.mean(axis=0), FittedMixture.from_fitted("m", mixture), False)
    assert cost == pytest.approx(-mixture.score(points @ rotation.T + translation), rel=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_p2d_gradient_matches_central_differences(seed):
    rng = np.random.default_rng(seed)
    mixture = FittedMixture.from_fitted("m", _random_mixture(rng, 7))
    points = 2 * rng.normal(size=(40, 3))
    centre = points.mean(axis=0)
    params = _random_params(rng)
    _, gradient = p2d.p2d_cost(params, points, centre, mixture, True)
    numeric = _central_differences(lambda x: p2d.p2d_cost(x, points, centre, mixture, False), params, 1e-6)
    np.testing.assert_allclose(gradient, numeric, rtol=0, atol=1e-7 * np.linalg.norm(numeric))


def _tables(fixed, moving):
    """The D2D tables of two mixtures, rotating about the moving one's centroid."""
    fixed, moving = FittedMixture.from_fitted("f", fixed), FittedMixture.from_fitted("m", moving)
    return d2d.PairTables.of(fixed, moving, moving.centroid)


def test_d2d_cost_matches_a_per_pair_loop():
    rng = np.random.default_rng(30)
    fixed, moving = _random_mixture(rng, 4), _random_mixture(rng, 3)
    params = _random_params(rng)
    centre = FittedMixture.from_fitted("moving", moving).centroid
    rotation, translation = pose.pose_from_params(params, centre)
    expected = 0.0
    for i in range(4):
        for j in range(3):
            y = fixed.means_[i] - translation - rotation @ moving.means_[j]
            s = fixed.covariances_[i] + rotation @ moving.covariances_[j] @ rotation.T
            expected -= fixed.weights_[i] * moving.weights_[j] * np.exp(-0.5 * y @ np.linalg.inv(s) @ y)
    cost = d2d.d2d_cost(params, _tables(fixed, moving), False)
    assert cost == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_d2d_gradient_matches_central_differences(seed):
    rng = np.random.default_rng(100 + seed)
    fixed = FittedMixture.from_fitted("f", _random_mixture(rng, 6))
    moving = FittedMixture.from_fitted("m", _random_mixture(rng, 5))
    params = _random_params(rng)
    tables = _tables(fixed, moving)
    _, gradient = d2d.d2d_cost(params, tables, True)
    numeric = _central_differences(lambda x: d2d.d2d_cost(x, tables, False), params, 1e-6)
    np.testing.assert_allclose(gradient, numeric, rtol=0, atol=1e-7 * np.linalg.norm(numeric))


def _all_pair_log_terms(fixed, moving, centre, rotation, translation):
    """``log πᵢ πⱼ - ½ yᵀ S⁻¹ y`` of every pair (n_fixed, n_moving), by np.linalg.solve, no screen."""
    moved = (moving.means_ - centre) @ rotation.T + centre + translation
    y = fixed.means_[:, None, :] - moved[None, :, :]
    s = fixed.covariances_[:, None] + (rotation @ moving.covariances_ @ rotation.T)[None, :]
    quadratic = np.einsum("ijk,ijk->ij", y, np.linalg.solve(s, y[..., None])[..., 0])
    return np.log(fixed.weights_)[:, None] + np.log(moving.weights_)[None, :] - 0.5 * quadratic


@pytest.fixture(scope="module")
def surface_mixtures(bunny_res4):
    """Two mixtures of the bunny's surface (thin components, many pairs far apart) and a pose 7 deg, 1 cm away."""
    fixed = DgmmGaussianMixture(100, random_state=0).fit(bunny_res4)
    moving = DgmmGaussianMixture(80, random_state=1).fit(bunny_res4)
    rotation = Rotation.from_euler("xyz", [5.0, -4.0, 3.0], degrees=True).as_matrix()
    return fixed, moving, rotation, np.array([0.01, -0.004, 0.006])


def test_d2d_pair_screen_keeps_every_pair_within_its_bound(surface_mixtures):
    """The screen (``PairTables.candidates``) may drop a pair only if its term is below ``e^-SCREEN`` times
    the largest: checked against every pair's exact term. A third of the 8000 pairs are dropped (a screen that
    drops none would make this test vacuous), and thousands lie between ``e^-50`` and ``e^-5`` of the largest,
    so a screen that drops pairs it should keep (a wrong bound, a wrong threshold) fails."""
    fixed, moving, rotation, translation = surface_mixtures
    tables = _tables(fixed, moving)
    centre = tables.centre
    log_terms = _all_pair_log_terms(fixed, moving, centre, rotation, translation)
    moved = (moving.means_ - centre) @ rotation.T + centre + translation
    kept = np.zeros(log_terms.shape, dtype=bool)
    kept[tables.candidates(moved, rotation @ moving.covariances_ @ rotation.T)] = True
    needed = log_terms >= log_terms.max() - d2d.SCREEN
    assert np.count_nonzero(~kept) > 2000  # the screen is at work
    assert np.count_nonzero(needed & (log_terms < log_terms.max() - 5)) > 2000  # pairs near the edge exist
    assert np.all(kept[needed]), f"{np.count_nonzero(needed & ~kept)} pairs within e^-50 dropped"


def test_d2d_cost_and_derivatives_with_the_screen_equal_the_unscreened_ones(surface_mixtures, monkeypatch):
    """Cost against the sum over all pairs computed here, gradient against its central differences; gradient,
    Gauss-Newton matrix and Hessian against the same code with the screen off (``SCREEN`` infinite). Dropped
    pairs are below ``e^-50`` (2e-22) of the largest term each, so the costs agree to rounding (1e-12 relative)
    and the gradients to the differences' error (1e-7); keeping only pairs within ``e^-5`` of the largest
    changes the cost by 5e-3 of it and the gradient by more than 1e-4 (both tried)."""
    fixed, moving, rotation, translation = surface_mixtures
    evaluate = d2d.d2d_pose_cost(_tables(fixed, moving), compiled=False)  # the numpy path's screen
    cost, derivatives = evaluate(rotation, translation)
    centre = FittedMixture.from_fitted("m", moving).centroid

    def all_pairs_cost(x):  # at translation t' + δ and left rotation exp([ω]x) R, x = (δ, ω)
        moved_rotation = Rotation.from_rotvec(x[3:]).as_matrix() @ rotation
        return -np.exp(_all_pair_log_terms(fixed, moving, centre, moved_rotation, translation + x[:3])).sum()
    assert cost == pytest.approx(all_pairs_cost(np.zeros(6)), rel=1e-12)
    screened = derivatives()
    numeric = _central_differences(all_pairs_cost, np.zeros(6), 1e-6)
    np.testing.assert_allclose(screened[0], numeric, rtol=0, atol=1e-7 * np.linalg.norm(numeric))
    expected = all_pairs_cost(np.zeros(6))
    monkeypatch.setattr(d2d, "SCREEN", np.inf)
    unscreened_cost, unscreened = evaluate(rotation, translation)
    assert unscreened_cost == pytest.approx(expected, rel=1e-12)
    for ours, reference in zip(screened, unscreened()):
        np.testing.assert_allclose(ours, reference, rtol=0, atol=1e-12 * np.abs(reference).max())


def _perturbed(evaluate, rotation, translation):
    """The cost and the first output of ``derivatives()`` as functions of ``(δ, ω)``: ``exp([ω]x) R``, ``t' + δ``."""
    def at(x):
        return evaluate(exp_rotation(x[3:]) @ rotation, translation + x[:3])
    return (lambda x: at(x)[0]), (lambda x: at(x)[1]()[0])


def _pose_cost_cases(seed):
    """(name, evaluate, rotation, translation) of a P2D and a D2D pose cost away from their optimum."""
    rng = np.random.default_rng(200 + seed)
    fixed = FittedMixture.from_fitted("f", _random_mixture(rng, 6))
    moving = FittedMixture.from_fitted("m", _random_mixture(rng, 5))
    points = 2 * rng.normal(size=(40, 3))
    rotation, translation = Rotation.random(rng=rng).as_matrix(), 0.5 * rng.normal(size=3)
    return [("p2d", p2d.p2d_pose_cost(points, points.mean(axis=0), fixed), rotation, translation),
            ("d2d", d2d.d2d_pose_cost(_tables(fixed, moving)), rotation, translation)]


@pytest.mark.parametrize("seed", range(3))
def test_pose_gradients_match_central_differences(seed):
    """The Gauss-Newton solver's 6-dof gradients (left rotation, translation) against the costs themselves."""
    for name, evaluate, rotation, translation in _pose_cost_cases(seed):
        cost, gradient = _perturbed(evaluate, rotation, translation)
        numeric = _central_differences(cost, np.zeros(6), 1e-6)
        np.testing.assert_allclose(gradient(np.zeros(6)), numeric, rtol=0, atol=1e-7 * np.linalg.norm(numeric),
                                   err_msg=name)


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("case", [0, 1], ids=["p2d", "d2d"])
def test_exact_hessians_match_central_differences_of_the_cost(seed, case):
    """The exact P2D and D2D Hessians against second central differences of the cost along 24 random directions
    (more than the 21 entries of a symmetric 6x6; Richardson extrapolated from steps h and h/2, so the truncation
    error is O(h⁴))."""
    _, evaluate, rotation, translation = _pose_cost_cases(seed)[case]
    cost, _ = _perturbed(evaluate, rotation, translation)
    hessian = evaluate(rotation, translation)[1]()[2]
    np.testing.assert_allclose(hessian, hessian.T, rtol=0, atol=1e-12 * np.abs(hessian).max())

    def second(direction, h):
        return (cost(h * direction) - 2 * cost(np.zeros(6)) + cost(-h * direction)) / h**2

    for direction in np.random.default_rng(seed).normal(size=(24, 6)):
        numeric = (4 * second(direction, 5e-5) - second(direction, 1e-4)) / 3
        assert direction @ hessian @ direction == pytest.approx(numeric, rel=1e-5, abs=1e-6 * np.abs(hessian).max())


def test_gauss_newton_matrices_are_positive_semi_definite():
    for name, evaluate, rotation, translation in _pose_cost_cases(0):
        gauss_newton = evaluate(rotation, translation)[1]()[1]
        assert np.linalg.eigvalsh(gauss_newton).min() >= -1e-12 * np.abs(gauss_newton).max(), name


def _pose_difference(a, b, diagonal):
    """Rotation angle between two results (radians) and the largest entry of their translation difference."""
    return np.radians(reg.rotation_distance_deg(a.rotation, b.rotation)), np.abs(a.translation - b.translation).max()


@pytest.mark.slow
def test_p2d_solvers_reach_the_same_optimum(bunny):
    """On well-posed bunny trials BFGS (driven to its tightest gradient test) and Gauss-Newton agree: at P2D's
    stopping tolerance (P2D_TOL, 1e-6) on the pose, and driven to 1e-8 on the cost too."""
    for trial in reg.random_trials(5, 50, bunny.diagonal, bunny.vertices.mean(axis=0)):
        source = trial.apply(bunny.vertices)
        bfgs = reg.register_p2d(source, bunny.mixture, options={"gtol": 1e-9})
        newton = reg.register_p2d(source, bunny.mixture, solver="gauss-newton")
        assert newton.converged and newton.method == "p2d"
        rotation_rad, translation = _pose_difference(bfgs, newton, bunny.diagonal)
        assert rotation_rad < 1e-6 and translation < 1e-6 * bunny.diagonal
        tight = reg.register_p2d(source, bunny.mixture, solver="gauss-newton", options={"tol": 1e-8})
        assert tight.objective <= bfgs.objective + 1e-12 * abs(bfgs.objective)


@pytest.mark.slow
def test_d2d_solvers_reach_the_same_optimum(bunny, bunny_trial):
    c = bunny_trial.centre
    for trial in reg.random_trials(3, 51, bunny.diagonal, c, max_angle_deg=3.0, max_translation=0.005):
        moving = _transformed_mixture(bunny.mixture, trial.rotation, trial.centre + trial.translation
                                      - trial.rotation @ trial.centre)
        bfgs = reg.register_d2d(bunny.mixture, moving, options={"gtol": 1e-9})
        newton = reg.register_d2d(bunny.mixture, moving, solver="gauss-newton")
        assert newton.converged and newton.method == "d2d"
        rotation_rad, translation = _pose_difference(bfgs, newton, bunny.diagonal)
        assert rotation_rad < 1e-6 and translation < 1e-6 * bunny.diagonal
        assert reg.registration_errors(newton, trial, bunny.diagonal)[0] < 1e-4


def test_gauss_newton_started_at_the_optimum_stops_there(bunny):
    """A mixture registered to itself from the identity: the first step is below tol, so the solver stops at once
    with the identity (it used to fail on the step it never took)."""
    result = reg.register_d2d(bunny.mixture, bunny.mixture, solver="gauss-newton")
    assert result.converged and result.iterations == 1
    np.testing.assert_allclose(result.rotation, np.eye(3), atol=1e-9)
    np.testing.assert_allclose(result.translation, 0.0, atol=1e-9 * bunny.diagonal)


# ----------------------------------------------------------------------------------- recovering a pose
@pytest.mark.slow
@pytest.mark.parametrize("gradient", ["analytic", "numeric"])
def test_p2d_recovers_a_known_motion(bunny, bunny_trial, gradient):
    result = reg.register_p2d(bunny_trial.apply(bunny.vertices), bunny.mixture, gradient=gradient)
    rotation_deg, translation_pct = reg.registration_errors(result, bunny_trial, bunny.diagonal)
    # Forward differences usually stop on scipy's "precision loss" near the optimum, so only the analytic
    # gradient is expected to meet BFGS's gradient test.
    assert result.method == "p2d" and (result.converged or gradient == "numeric")
    assert rotation_deg < 1.0 and translation_pct < 0.5


def _scaled_mixture(mixture, factor):
    """The mixture of ``factor * x``: the same model in other length units."""
    covariances = factor**2 * mixture.covariances_
    return SimpleNamespace(weights_=mixture.weights_, means_=factor * mixture.means_, covariances_=covariances,
                           precisions_cholesky_=np.linalg.inv(np.linalg.cholesky(covariances)).transpose(0, 2, 1))


@pytest.mark.slow
@pytest.mark.parametrize("method", ["p2d", "d2d"])
def test_registration_does_not_depend_on_length_units(bunny, bunny_trial, method):
    """The same problem in metres and in millimetres must give the same rotation and the same translation."""
    c, r, t = bunny_trial.centre, bunny_trial.rotation, bunny_trial.translation
    source = bunny_trial.apply(bunny.vertices)
    moving = _transformed_mixture(bunny.mixture, r, c + t - r @ c)
    register = {"p2d": lambda f: reg.register_p2d(f * source, _scaled_mixture(bunny.mixture, f)),
                "d2d": lambda f: reg.register_d2d(_scaled_mixture(bunny.mixture, f), _scaled_mixture(moving, f))}
    metres, millimetres = register[method](1.0), register[method](1000.0)
    assert reg.rotation_distance_deg(metres.rotation, millimetres.rotation) < 1e-4
    np.testing.assert_allclose(millimetres.translation / 1000.0, metres.translation, atol=1e-6 * bunny.diagonal)


def test_p2d_callback_sees_every_iteration(bunny, bunny_trial):
    source = bunny_trial.apply(bunny.vertices)
    seen = []
    result = reg.register_p2d(source, bunny.mixture, callback=lambda i, r: seen.append((i, r)))
    assert [i for i, _ in seen] == list(range(1, result.iterations + 1))
    np.testing.assert_allclose(seen[-1][1].rotation, result.rotation, atol=1e-12)
    assert seen[-1][1].objective == pytest.approx(-bunny.mixture.score(seen[-1][1].apply(source)), rel=1e-10)


def test_d2d_recovers_a_known_motion(bunny, bunny_trial):
    # The moving mixture is the fixed one moved by the trial, so the transform to find is the trial's inverse.
    c, r, t = bunny_trial.centre, bunny_trial.rotation, bunny_trial.translation
    moving = _transformed_mixture(bunny.mixture, r, c + t - r @ c)
    result = reg.register_d2d(bunny.mixture, moving)
    rotation_deg, translation_pct = reg.registration_errors(result, bunny_trial, bunny.diagonal)
    assert rotation_deg < 0.5 and translation_pct < 0.5
    start_rotation = r.T @ _rodrigues([0, 1, 1], 2.0)
    started = reg.register_d2d(bunny.mixture, moving, start_rotation, c - r.T @ (c + t))
    assert reg.rotation_distance_deg(started.rotation, result.rotation) < 0.05


def test_icp_with_exact_correspondences_reaches_the_exact_pose(bunny, bunny_trial):
    result = reg.register_icp(bunny_trial.apply(bunny.vertices), bunny.vertices)
    rotation_deg, translation_pct = reg.registration_errors(result, bunny_trial, bunny.diagonal)
    assert result.converged and rotation_deg < 1e-6 and translation_pct < 1e-6


def test_kabsch_with_weights_recovers_the_exact_pose():
    rng = np.random.default_rng(40)
    source = rng.normal(size=(25, 3))
    rotation = Rotation.random(rng=rng).as_matrix()
    translation = rng.normal(size=3)
    target = source @ rotation.T + translation
    target_noisy = target + np.where(np.arange(25)[:, None] < 5, rng.normal(size=(25, 3)), 0.0)
    weights = (np.arange(25) >= 5).astype(float)  # the noisy pairs get zero weight
    estimate = reg.kabsch(source, target_noisy, weights)
    np.testing.assert_allclose(estimate[0], rotation, atol=1e-12)
    np.testing.assert_allclose(estimate[1], translation, atol=1e-12)


def test_cpd_with_exact_correspondences_reaches_the_exact_pose(bunny, bunny_trial):
    # Every source point has its exact partner in the target: CPD's variance shrinks to zero on the true pose
    # (7.1 deg and 11% of the diagonal away), so only rounding is left, as for ICP above.
    result = reg.register_cpd(bunny_trial.apply(bunny.vertices), bunny.vertices)
    rotation_deg, translation_pct = reg.registration_errors(result, bunny_trial, bunny.diagonal)
    assert result.method == "cpd" and result.converged and rotation_deg < 1e-6 and translation_pct < 1e-6


@pytest.mark.parametrize("register", [reg.register_icp, partial(reg.register_cpd, max_iter=20)])
def test_point_set_callbacks_see_every_iteration(bunny, bunny_trial, register):
    source = bunny_trial.apply(bunny.vertices)
    seen = []
    result = register(source, bunny.vertices, callback=lambda i, r: seen.append((i, r)))
    assert [i for i, _ in seen] == list(range(1, result.iterations + 1))
    np.testing.assert_allclose(seen[-1][1].apply(source), result.apply(source), atol=1e-12)


# ------------------------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("source", [np.full((5, 3), np.nan), np.zeros((5, 2)), np.zeros((0, 3)), "abc"])
def test_bad_points_raise_input_error(source):
    mixture = _random_mixture(np.random.default_rng(0), 3)
    with pytest.raises(InputError):
        reg.register_p2d(source, mixture)
    with pytest.raises(InputError):
        reg.register_icp(source, np.zeros((4, 3)))


def test_bad_mixtures_and_options_raise_input_error():
    rng = np.random.default_rng(0)
    good = _random_mixture(rng, 3)
    points = rng.normal(size=(10, 3))
    with pytest.raises(InputError, match="precisions_cholesky_"):
        reg.register_p2d(points, SimpleNamespace(weights_=good.weights_, means_=good.means_,
                                                 covariances_=good.covariances_))
    with pytest.raises(InputError, match="n_components"):
        reg.register_d2d(good, SimpleNamespace(**{**vars(good), "weights_": np.ones(4) / 4}))
    with pytest.raises(InputError, match="gradient"):
        reg.register_p2d(points, good, gradient="central")
    with pytest.raises(InputError, match="solver"):
        reg.register_p2d(points, good, solver="newton")
    with pytest.raises(InputError, match="bfgs"):
        reg.register_d2d(good, good, solver="gauss-newton", gradient="numeric")
    with pytest.raises(InputError, match="max_iter"):
        reg.register_p2d(points, good, solver="gauss-newton", options={"maxiter": 3})
    with pytest.raises(InputError):
        reg.quaternion_to_matrix(np.zeros(4))
    with pytest.raises(InputError):
        reg.random_trials(3, 0, -1.0, np.zeros(3))
