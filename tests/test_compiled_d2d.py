"""The compiled D2D kernels (dgmm.compiled.registration) against every pair's exact term and against the numpy
reference: cost, derivatives and Gauss-Newton poses; the central-difference tests of test_registration.py check
the compiled derivatives on their own."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from dgmm import registration as reg
from dgmm.mixture import GaussianMixture
from dgmm.registration import d2d
from dgmm.registration.pose import pivot_pose
from dgmm.registration.solvers import minimise_gauss_newton
from dgmm.registration.fitted import FittedMixture


@pytest.fixture(scope="module")
def surface_mixtures(bunny_res4):
    """Two mixtures of the bunny's surface (thin components, most pairs far apart)."""
    return (FittedMixture.from_fitted("fixed", GaussianMixture(100, random_state=0).fit(bunny_res4)),
            FittedMixture.from_fitted("moving", GaussianMixture(80, random_state=1).fit(bunny_res4)))


def _poses():
    rng = np.random.default_rng(3)
    for angle_deg, shift in ((0.0, 0.0), (3.0, 0.005), (7.0, 0.01)):
        axis = rng.normal(size=3)
        yield (Rotation.from_rotvec(np.radians(angle_deg) * axis / np.linalg.norm(axis)).as_matrix(),
               shift * rng.normal(size=3))


def test_cost_is_the_sum_over_every_pair(surface_mixtures):
    """Against every pair's term by np.linalg.solve: the pairs left out (below e^-50 of the largest) change nothing
    at 1e-12, and more than half of the 8,000 pairs are left out."""
    fixed, moving = surface_mixtures
    tables = d2d.PairTables.of(fixed, moving, moving.centroid)
    for rotation, translation in _poses():
        moved = (moving.means - moving.centroid) @ rotation.T + moving.centroid + translation
        y = fixed.means[:, None, :] - moved[None, :, :]
        s = fixed.covariances[:, None] + (rotation @ moving.covariances @ rotation.T)[None, :]
        log_terms = (np.log(fixed.weights)[:, None] + np.log(moving.weights)[None, :]
                     - 0.5 * np.einsum("ijk,ijk->ij", y, np.linalg.solve(s, y[..., None])[..., 0]))
        assert np.mean(log_terms < log_terms.max() - d2d.SCREEN) > 0.5
        cost = d2d.d2d_pose_cost(tables)(rotation, translation)[0]  # x -> R (x - c) + c + t'
        assert cost == pytest.approx(-np.exp(log_terms).sum(), rel=1e-12)


def test_derivatives_equal_the_numpy_reference(surface_mixtures):
    fixed, moving = surface_mixtures
    tables = d2d.PairTables.of(fixed, moving, moving.centroid)
    compiled, reference = d2d.d2d_pose_cost(tables), d2d.d2d_pose_cost(tables, compiled=False)
    for rotation, translation in _poses():
        (cost, derivatives), (expected_cost, expected) = compiled(rotation, translation), reference(rotation,
                                                                                                     translation)
        assert cost == pytest.approx(expected_cost, rel=1e-13)
        for ours, theirs, name in zip(derivatives(), expected(), ("gradient", "Gauss-Newton", "exact Hessian")):
            np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12 * np.abs(theirs).max(), err_msg=name)


def _moved_mixtures(moving):
    """Odometry-sized motions (benchmarks/registration_speed.py's D2D: ±3°, ±0.005 per axis) of ``moving``."""
    trials = reg.random_trials(6, np.random.default_rng(4), reg.BUNNY_DIAGONAL, moving.centroid, max_angle_deg=3.0,
                               max_translation=0.005)
    return [FittedMixture(moving.weights, trial.apply(moving.means),
                          trial.rotation @ moving.covariances @ trial.rotation.T,
                          np.linalg.inv(np.linalg.cholesky(trial.rotation @ moving.covariances @ trial.rotation.T))
                          .transpose(0, 2, 1)) for trial in trials]


def test_gauss_newton_poses_equal_the_numpy_path(surface_mixtures):
    """The compiled loop and the numpy cost under the Python loop end on the same poses to 1e-9 rad and 1e-9 m."""
    fixed, moving = surface_mixtures
    for m in _moved_mixtures(moving):
        ours = reg.register_d2d(fixed, m, solver="gauss-newton")
        theirs = reg.register_d2d(fixed, m, solver="gauss-newton", compiled=False)
        assert np.radians(reg.rotation_distance_deg(ours.rotation, theirs.rotation)) < 1e-9
        assert np.abs(ours.translation - theirs.translation).max() < 1e-9
        assert ours.iterations == theirs.iterations


def test_compiled_loop_takes_the_python_loops_steps(surface_mixtures):
    """The compiled loop (dgmm.compiled.registration.d2d_gauss_newton) against the Python loop on the same kernels
    (solvers.minimise_gauss_newton on d2d_pose_cost), from a start off the optimum: every kept step's pose and cost to
    rounding, and the same number of iterations."""
    fixed, moving = surface_mixtures
    for m in _moved_mixtures(moving)[:3]:
        start = Rotation.from_rotvec([0.02, -0.01, 0.015]).as_matrix(), np.array([0.003, -0.002, 0.001])
        steps = {"ours": [], "theirs": []}
        ours = reg.register_d2d(fixed, m, *start, solver="gauss-newton",
                                callback=lambda i, r: steps["ours"].append(r))
        tables = d2d.PairTables.of(fixed, m, m.centroid)
        radius = np.sqrt(m.weights @ np.sum((m.means - m.centroid) ** 2, axis=1))
        theirs = minimise_gauss_newton("d2d", d2d.d2d_pose_cost(tables), m.centroid, radius,
                                       *pivot_pose(*start, m.centroid), lambda i, r: steps["theirs"].append(r), None)
        assert ours.iterations == theirs.iterations > 2
        for a, b in zip(steps["ours"] + [ours], steps["theirs"] + [theirs], strict=True):
            np.testing.assert_allclose(a.rotation, b.rotation, rtol=0, atol=1e-13)
            np.testing.assert_allclose(a.translation, b.translation, rtol=0, atol=1e-13)
            assert a.objective == pytest.approx(b.objective, rel=1e-13)
