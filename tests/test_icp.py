"""ICP and its nearest-neighbour tracking against brute force: full distance matrices, argmin, and a Kabsch step by
np.linalg.svd written here."""
import numpy as np
import pytest
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from dgmm.registration import register_icp
from dgmm.registration.neighbours import TrackedNeighbours


def _brute_force_icp(source, target, tol):
    """Both-ways point-to-point ICP from its definition: every pair by a distance-matrix argmin, then the weighted
    Kabsch step; stops when the mean matching distance changes by less than ``tol``. Returns (R, t, iterations)."""
    n_source, n_target = len(source), len(target)
    back_weight = n_source / n_target
    weights = np.concatenate([np.ones(n_source), np.full(n_target, back_weight)]) / (2 * n_source)
    rotation, translation, previous = np.eye(3), np.zeros(3), np.inf
    for iteration in range(10_000):
        moved = source @ rotation.T + translation
        distances = np.linalg.norm(moved[:, None, :] - target[None, :, :], axis=2)
        forward, back = distances.argmin(axis=1), distances.argmin(axis=0)
        error = (distances[np.arange(n_source), forward].sum()
                 + back_weight * distances[back, np.arange(n_target)].sum()) / (2 * n_source)
        if abs(previous - error) < tol:
            return rotation, translation, iteration
        previous = error
        paired_from = np.concatenate([moved, moved[back]])
        paired_to = np.concatenate([target[forward], target])
        from_mean, to_mean = weights @ paired_from, weights @ paired_to
        u, _, vt = np.linalg.svd((weights[:, None] * (paired_from - from_mean)).T @ (paired_to - to_mean))
        reflection = np.diag([1.0, 1.0, np.linalg.det(vt.T @ u.T)])
        step = vt.T @ reflection @ u.T
        rotation, translation = step @ rotation, step @ translation + to_mean - step @ from_mean
    raise AssertionError("brute-force ICP did not stop")


@pytest.mark.parametrize("seed, n_source, n_target, angle_deg", [(0, 150, 150, 10.0), (1, 120, 200, 20.0),
                                                                  (2, 220, 90, 30.0)])
def test_icp_matches_brute_force_icp(seed, n_source, n_target, angle_deg):
    # Two different samples of one curved surface, the source moved by a known rigid motion: ICP iterates many
    # times, its matches change from step to step and both directions' pairs matter (n_source != n_target).
    rng = np.random.default_rng(seed)

    def surface(n):
        xy = rng.uniform(-1, 1, size=(n, 2))
        return np.column_stack([xy, 0.3 * np.sin(2 * xy[:, 0]) * np.cos(3 * xy[:, 1])]) + [2.0, -1.0, 3.0]

    motion = Rotation.from_rotvec(np.radians(angle_deg) * Rotation.random(rng=rng).as_rotvec() / np.pi)
    target = surface(n_target)
    source = motion.apply(surface(n_source)) + rng.normal(scale=0.1, size=3)
    rotation, translation, iterations = _brute_force_icp(source, target, tol=1e-9)
    result = register_icp(source, target, tol=1e-9)
    assert iterations > 5 and result.iterations == iterations and result.converged
    np.testing.assert_allclose(result.rotation, rotation, atol=1e-9)
    np.testing.assert_allclose(result.translation, translation, atol=1e-9)


def test_tracked_neighbours_match_brute_force_along_a_random_walk():
    # Queries that creep (the candidates prove the answer), jump (re-anchoring) and sit still, in turn.
    rng = np.random.default_rng(3)
    points = rng.uniform(-1, 1, size=(300, 3))
    queries = rng.uniform(-1.2, 1.2, size=(200, 3))
    tracked = TrackedNeighbours(points)
    for step in range(30):
        queries = queries + rng.normal(scale=(0.003, 0.3, 0.0)[step % 3], size=queries.shape)
        distances, indices = tracked.query(queries)
        table = np.linalg.norm(queries[:, None, :] - points[None, :, :], axis=2)
        np.testing.assert_array_equal(indices, table.argmin(axis=1))
        np.testing.assert_allclose(distances, table.min(axis=1), rtol=0, atol=1e-14)


def test_tracked_neighbours_break_exact_ties_as_the_tree_does():
    # Integer grid points and queries on half-integers: most queries are equally near two to eight points.
    grid = np.stack(np.meshgrid(*[np.arange(6.0)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    rng = np.random.default_rng(4)
    queries = rng.integers(0, 11, size=(150, 3)) / 2.0
    tracked, tree = TrackedNeighbours(grid), cKDTree(grid)
    for shift in (0.0, 0.0, 0.5, 0.5, -1.0):  # repeated calls, then whole-step moves that keep the ties
        queries = queries + shift
        np.testing.assert_array_equal(tracked.query(queries)[1], tree.query(queries)[1])
