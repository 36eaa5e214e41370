"""The study's transcription of the authors' ICP (benchmarks/studies/icp_authors.py): it recovers a known rigid
motion, it ends where their loop as written (cdist + argmin, their update) ends, and on a bunny trial it lands where
ours does."""
import sys
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial.distance import cdist
from scipy.spatial.transform import Rotation

from dgmm.experiments.trials import bounding_diagonal, make_trials
from dgmm.registration import RigidTrial, register_icp, registration_errors

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks" / "studies"))
from icp_authors import register_icp_authors, their_bookkeeping  # noqa: E402


def _their_loop(source, target, max_iter=50_000, tol=1e-9):
    """registration_test.py's ICP loop (flag = True) as written there: the final moved points and the pose it books
    (``R``, ``icp_t``)."""
    source2, prev_err, R, icp_t = np.copy(source), 100000000, np.identity(3), np.zeros(3)
    for _ in range(max_iter):
        dist = cdist(source2, target)
        matched_pts = target[np.argmin(dist, 1)]
        source2mean, matchedptsmean = source2.mean(0), matched_pts.mean(0)
        source2centered = source2 - source2mean
        it = source2mean - matchedptsmean
        matched2 = source2[np.argmin(dist, 0)]
        it = (0.5 * it) + 0.5 * (matched2.mean(0) - target.mean(0))
        H = source2centered.T @ (matched_pts - matchedptsmean)
        H2 = (matched2 - matched2.mean(0)).T @ (target - target.mean(0))
        H = H + H2 * source2.shape[0] / target.shape[0]
        u, s, vt = np.linalg.svd(H)
        rotmat = vt.T @ np.diag([1, 1, np.linalg.det(vt.T @ u.T)]) @ u.T
        source2 = source2centered @ rotmat.T + source2mean - it
        err = np.linalg.norm(source2 - matched_pts, axis=1)
        if np.linalg.norm(err - prev_err) < tol:
            break
        prev_err = err
        icp_t += it
        R = R @ rotmat
    return source2, R, icp_t


def _surface(rng, n):
    xy = rng.uniform(-1, 1, size=(n, 2))
    return np.column_stack([xy, 0.3 * np.sin(2 * xy[:, 0]) * np.cos(3 * xy[:, 1])]) + [2.0, -1.0, 3.0]


def test_recovers_a_known_rigid_motion():
    rng = np.random.default_rng(0)
    target = _surface(rng, 300)
    motion = Rotation.from_euler("xyz", [8.0, -6.0, 10.0], degrees=True)
    source = motion.apply(target - target.mean(0)) + target.mean(0) + [0.05, -0.03, 0.04]
    result = register_icp_authors(source, target)
    assert result.converged and result.iterations > 3
    np.testing.assert_allclose(result.apply(source), target, atol=1e-8)
    np.testing.assert_allclose(result.rotation, motion.inv().as_matrix(), atol=1e-8)


def test_ends_where_their_loop_as_written_ends_and_books_its_errors():
    # Two different samples of one surface, of different sizes: the matches change from step to step and the
    # backward pairs' scaling matters.
    rng = np.random.default_rng(1)
    target, points = _surface(rng, 160), _surface(rng, 120)
    trial = RigidTrial(Rotation.from_rotvec([0.1, -0.2, 0.15]).as_matrix(), np.array([0.1, 0.0, -0.05]),
                       points.mean(0))
    source = trial.apply(points)
    steps = []
    result = register_icp_authors(source, target, callback=lambda i, step, shift: steps.append((step, shift)))
    assert result.converged and result.iterations == len(steps) > 5
    moved, R, icp_t = _their_loop(source, target)
    np.testing.assert_allclose(result.apply(source), moved, atol=1e-9)
    # Their script's errors: the quaternion dot product with the true rotation's (M, source = centred @ M + ...)
    # and |icp_t - t|.
    dot = abs(Rotation.from_matrix(R).as_quat() @ Rotation.from_matrix(trial.rotation.T).as_quat())
    diagonal = bounding_diagonal(points)
    expected = np.degrees(2 * np.arccos(min(dot, 1.0))), 100 * np.linalg.norm(icp_t - trial.translation) / diagonal
    np.testing.assert_allclose(their_bookkeeping(steps, trial, diagonal), expected, atol=1e-6)


def test_lands_near_ours_on_a_bunny_trial(bunny_res4):
    # The sweep's trial construction on a seeded surface sample of res4 (the sweep draws from a Poisson-disk one).
    dense = trimesh.sample.sample_surface(bunny_res4, 20_000, seed=0)[0]
    diagonal = bounding_diagonal(bunny_res4.vertices)
    (setup,) = make_trials(dense, len(bunny_res4.vertices), [0], root_seed=0, key="registration/bunny/res4",
                           diagonal=diagonal)
    ours = register_icp(setup.moved, setup.target)
    theirs = register_icp_authors(setup.moved, setup.target)
    assert ours.converged and theirs.converged
    errors = [registration_errors(result, setup.trial, diagonal) for result in (ours, theirs)]
    np.testing.assert_allclose(errors[1], errors[0], atol=0.05)  # degrees, % of the diagonal
    # Not the same point: the two steps and stops differ, so they stop on nearby poses.
    assert np.abs(theirs.apply(setup.moved) - ours.apply(setup.moved)).max() < 0.01 * diagonal
