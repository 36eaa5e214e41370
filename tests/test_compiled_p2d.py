"""The compiled P2D kernels (dgmm.compiled.registration) against the numpy reference (every pair, numpy's exp):
costs, derivatives and the poses of both solvers; the central-difference tests of test_registration.py check the
compiled derivatives on their own."""
import math
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from sklearn.mixture import GaussianMixture

from dgmm import registration as reg
from dgmm.compiled import registration as kernels
from dgmm.errors import FitError
from dgmm.gaussian import SCREEN, quadratic_features
from dgmm.registration import p2d
from dgmm.registration.fitted import FittedMixture
from dgmm.registration.p2d import p2d_pose_cost
from dgmm.registration.rotations import rotation_and_jacobian


def _both(points, mixture):
    centre = points.mean(axis=0)
    return p2d_pose_cost(points, centre, mixture), p2d_pose_cost(points, centre, mixture, compiled=False)


def _assert_same_terms(compiled, reference, rotation, translation):
    cost, derivatives = compiled(rotation, translation)
    expected_cost, expected = reference(rotation, translation)
    assert cost == pytest.approx(expected_cost, rel=1e-13)
    for ours, theirs, name in zip(derivatives(), expected(), ("gradient", "Gauss-Newton", "exact Hessian")):
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-11 * np.abs(theirs).max(), err_msg=name)


@pytest.fixture(scope="module")
def bunny_mixture(bunny_res4):
    vertices = np.asarray(bunny_res4.vertices)
    fitted = GaussianMixture(100, init_params="kmeans", tol=1e-5, max_iter=100, random_state=0).fit(vertices)
    return vertices, FittedMixture.from_fitted("bunny", fitted)


def _mixture(means, covariances, weights):
    """A fitted-mixture-like object, precisions_cholesky_ as scikit-learn builds it."""
    return SimpleNamespace(weights_=weights, means_=means, covariances_=covariances,
                           precisions_cholesky_=np.linalg.inv(np.linalg.cholesky(covariances)).transpose(0, 2, 1))


def test_bunny_terms_equal_the_numpy_reference_at_random_poses(bunny_mixture):
    """K=100 on the bunny, where most pairs lie beyond the screen: it is tested as well as the arithmetic."""
    vertices, mixture = bunny_mixture
    log_density = quadratic_features(vertices - mixture.origin) @ mixture.log_density_table
    assert np.mean(log_density < log_density.max(axis=1, keepdims=True) - SCREEN) > 0.5
    compiled, reference = _both(vertices, mixture)
    rng = np.random.default_rng(0)
    for angle in (0.0, 5.0, 15.0):
        axis = rng.normal(size=3)
        rotation = Rotation.from_rotvec(np.radians(angle) * axis / np.linalg.norm(axis)).as_matrix()
        _assert_same_terms(compiled, reference, rotation, 0.003 * rng.normal(size=3))


def test_components_far_beyond_the_screen_change_nothing():
    """A mixture and a copy of it 100 standard deviations away, half the weight each: every pair of the copy is
    screened out, and the cost is the mixture's alone plus log 2, its derivatives the mixture's."""
    rng = np.random.default_rng(1)
    means = rng.normal(size=(8, 3))
    covariances = np.repeat(0.05 * np.eye(3)[None], 8, axis=0)
    points = means[rng.integers(8, size=200)] + 0.2 * rng.normal(size=(200, 3))
    near = FittedMixture.from_fitted("near", _mixture(means, covariances, np.full(8, 1 / 8)))
    both = FittedMixture.from_fitted("both", _mixture(np.concatenate([means, means + 100 * np.sqrt(0.05)]),
                                                      np.concatenate([covariances, covariances]), np.full(16, 1 / 16)))
    centre = points.mean(axis=0)
    near_cost, near_derivatives = p2d_pose_cost(points, centre, near)(np.eye(3), np.zeros(3))
    cost, derivatives = p2d_pose_cost(points, centre, both)(np.eye(3), np.zeros(3))
    assert cost == pytest.approx(near_cost + np.log(2.0), rel=1e-14)
    for ours, theirs in zip(derivatives(), near_derivatives()):
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12 * np.abs(theirs).max())


@pytest.mark.parametrize("vector_exp", [True, False])
def test_a_points_terms_do_not_depend_on_its_block(bunny_mixture, vector_exp):
    """The cost computes points a block at a time: each point alone (a block of one) gives its pairs and sums
    to the bit, with either exponential, and sets of fewer, as many and more points than a block agree with numpy's
    cost."""
    vertices, mixture = bunny_mixture
    rotation, shift = Rotation.from_rotvec([0.1, -0.2, 0.05]).as_matrix(), 0.002 * np.ones(3)
    local = np.ascontiguousarray(vertices[:70] - vertices[:70].mean(axis=0))
    table = mixture.log_density_table
    buffers = kernels.p2d_pose_buffers(len(local), table.shape[1])
    kernels.p2d_negative_mean_log_likelihood(local, rotation, shift, table, SCREEN, vector_exp, *buffers)
    starts, components, terms, sums = buffers[2:]
    for n in range(len(local)):
        alone = kernels.p2d_pose_buffers(1, table.shape[1])
        kernels.p2d_negative_mean_log_likelihood(local[n:n + 1], rotation, shift, table, SCREEN, vector_exp, *alone)
        kept = slice(starts[n], starts[n + 1])
        np.testing.assert_array_equal(alone[3][:alone[2][1]], components[kept])
        np.testing.assert_array_equal(alone[4][:alone[2][1]], terms[kept])
        assert alone[5][0] == sums[n]
    for size in (kernels.BLOCK - 1, kernels.BLOCK, kernels.BLOCK + 1):
        points = vertices[:size]
        compiled, reference = _both(points, mixture)
        assert compiled(rotation, shift)[0] == pytest.approx(reference(rotation, shift)[0], rel=1e-13)


@pytest.mark.slow
def test_gauss_newton_poses_equal_the_numpy_path(bunny_mixture):
    """The registrations of benchmarks/registration_speed.py's protocol (±15°, ±5% of the diagonal): the compiled
    and the numpy costs end on the same poses to 1e-9 rad and 1e-9 of the diagonal."""
    vertices, mixture = bunny_mixture
    diagonal = float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))
    for trial in reg.random_trials(8, np.random.default_rng(2), diagonal, vertices.mean(axis=0)):
        ours, theirs = (reg.register_p2d(trial.apply(vertices), mixture, solver="gauss-newton", compiled=c)
                        for c in (True, False))
        assert np.radians(reg.rotation_distance_deg(ours.rotation, theirs.rotation)) < 1e-9
        assert np.abs(ours.translation - theirs.translation).max() < 1e-9 * diagonal
        assert ours.iterations == theirs.iterations


def test_the_compiled_loop_s_callback_sees_the_numpy_path_s_steps(bunny_mixture):
    """The compiled Gauss-Newton loop reports its kept steps after the solve: the same iterations and poses (to
    1e-9 rad) as the numpy path's callback saw during its solve, and the last one is the result's pose."""
    vertices, mixture = bunny_mixture
    diagonal = float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))
    trial = reg.random_trials(1, np.random.default_rng(5), diagonal, vertices.mean(axis=0))[0]
    seen = {True: [], False: []}
    results = {c: reg.register_p2d(trial.apply(vertices), mixture, solver="gauss-newton", compiled=c,
                                   callback=lambda i, r, c=c: seen[c].append((i, r)))
               for c in (True, False)}
    assert [i for i, _ in seen[True]] == [i for i, _ in seen[False]] == list(range(1, results[True].iterations + 1))
    for (_, ours), (_, theirs) in zip(seen[True], seen[False]):
        assert not ours.converged
        assert np.radians(reg.rotation_distance_deg(ours.rotation, theirs.rotation)) < 1e-9
        assert ours.objective == pytest.approx(theirs.objective, rel=1e-12)
    np.testing.assert_array_equal(seen[True][-1][1].rotation, results[True].rotation)
    np.testing.assert_array_equal(seen[True][-1][1].translation, results[True].translation)


def test_the_compiled_loop_reports_a_cost_that_is_not_finite():
    """Source points 1e160 from the mixture (spread over 1e150): their squared offsets overflow, the cost is not
    finite, and the compiled loop raises the numpy path's FitError."""
    rng = np.random.default_rng(6)
    means = rng.normal(size=(4, 3))
    mixture = FittedMixture.from_fitted("m", _mixture(means, np.repeat(0.1 * np.eye(3)[None], 4, axis=0),
                                                      np.full(4, 0.25)))
    points = 1e160 + 1e150 * rng.normal(size=(20, 3))
    for compiled in (True, False):
        with pytest.raises(FitError, match="p2d registration: the cost or its derivatives are not finite at "
                                           "Gauss-Newton iteration 0"), np.errstate(over="ignore", invalid="ignore"):
            reg.register_p2d(points, mixture, solver="gauss-newton", compiled=compiled)


def test_quaternion_rotation_and_jacobian_equal_the_numpy_ones():
    """Quaternions of any length; a zero one gives NaNs (the numpy function raises), which BFGS's cost check turns
    into its error."""
    rng = np.random.default_rng(4)
    for quaternion in rng.normal(size=(5, 4)) * rng.uniform(0.2, 5.0, size=(5, 1)):
        for ours, theirs in zip(kernels.quaternion_rotation_and_jacobian(quaternion),
                                rotation_and_jacobian(quaternion)):
            np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-15 * np.abs(theirs).max() + 1e-16)
    assert np.isnan(kernels.quaternion_rotation_and_jacobian(np.zeros(4))[0]).all()


def test_bfgs_cost_and_gradient_equal_the_numpy_reference(bunny_mixture):
    """BFGS's cost over ``(t', q)`` (quaternions of any length) and its gradient, compiled against numpy."""
    vertices, mixture = bunny_mixture
    centre = vertices.mean(axis=0)
    compiled, reference = (p2d.p2d_params_cost(vertices, centre, mixture, compiled=c) for c in (True, False))
    rng = np.random.default_rng(3)
    for spin in (0.0, 0.05, 0.2):
        quaternion = rng.uniform(0.5, 2.0) * np.r_[1.0, spin * rng.normal(size=3)]
        params = np.concatenate([0.003 * rng.normal(size=3), quaternion])
        cost, gradient = compiled(params, with_grad=True)
        expected_cost, expected = reference(params, with_grad=True)
        assert cost == pytest.approx(expected_cost, rel=1e-13)
        assert compiled(params, with_grad=False) == cost
        np.testing.assert_allclose(gradient, expected, rtol=0, atol=1e-11 * np.abs(expected).max())


@pytest.mark.slow
def test_bfgs_poses_equal_the_numpy_path(bunny_mixture):
    """The paper's BFGS on the compiled and the numpy costs ends on the same optimum: the two costs differ at
    rounding, which moves where BFGS stops (its gtol) by at most 5e-9 rad in 40 such trials, far below any error the
    registrations report (0.1-1°)."""
    vertices, mixture = bunny_mixture
    diagonal = float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))
    for trial in reg.random_trials(8, np.random.default_rng(2), diagonal, vertices.mean(axis=0)):
        ours, theirs = (reg.register_p2d(trial.apply(vertices), mixture, compiled=c) for c in (True, False))
        assert np.radians(reg.rotation_distance_deg(ours.rotation, theirs.rotation)) < 1e-7
        assert np.abs(ours.translation - theirs.translation).max() < 1e-7 * diagonal


def test_loading_the_kernels_leaves_nothing_for_a_registration_to_load():
    """What the sweep's job server calls before forking its jobs (dgmm.registration.p2d.load_p2d_kernels) loads every
    kernel specialisation that P2D's solvers then run on a fitted scikit-learn mixture: a fresh process, so that no
    other test has loaded them first."""
    program = """
import numpy as np
from sklearn.mixture import GaussianMixture
from dgmm.compiled import registration as kernels
from dgmm.errors import FitError
from dgmm.registration.p2d import load_p2d_kernels
from dgmm.registration import register_p2d, register_p2d_coarse_to_fine
load_p2d_kernels()
names = [name for name in dir(kernels) if hasattr(getattr(kernels, name), "signatures")]
loaded = {name: list(getattr(kernels, name).signatures) for name in names}
points = np.random.default_rng(0).normal(size=(200, 3))
mixture = GaussianMixture(5, random_state=0).fit(points)
for solver in ("bfgs", "gauss-newton"):
    register_p2d(points[::-1] + 0.01, mixture, solver=solver)
register_p2d_coarse_to_fine(points + 0.01, mixture, scales=[0.25, 0.0])
print(sorted(name for name in names if loaded[name]))
print([name for name in names if list(getattr(kernels, name).signatures) != loaded[name]])
"""
    run = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    loaded, added = run.stdout.splitlines()
    assert loaded == str(["p2d_gauss_newton", "p2d_negative_mean_log_likelihood", "p2d_params_gradient",
                          "p2d_pose_buffers", "quaternion_rotation_and_jacobian"])
    assert added == "[]"


def test_vectorised_exponentials_are_within_an_ulp_of_math_exp():
    """Gauss-Newton's exponentials (``_exp_in_place``, Cody-Waite reduction and a Taylor polynomial) on 200,000
    values over [-708, 0], with 0, -708 and the reduction's halfway points ±ln 2 / 2: each within one ulp of
    ``math.exp``'s value, and most equal to it."""
    rng = np.random.default_rng(4)
    half = np.log(2.0) / 2
    values = np.concatenate([rng.uniform(-708.0, 0.0, 200_000), rng.uniform(-1.0, 0.0, 1000),
                             [0.0, -708.0, -half, -3 * half, -1e-300]])
    expected = np.array([math.exp(x) for x in values])
    ours = values.copy()
    kernels._exp_in_place(ours, np.empty_like(ours))
    assert np.all(np.abs(ours - expected) <= np.spacing(expected))
    assert np.mean(ours == expected) > 0.5
