"""The odometry's per-frame EM start (dgmm.odometry.em_start): k-means++ seeding against its defining
probabilities and its greedy choice, computed here by brute force over every pair of points."""
import numpy as np
import pytest

from dgmm.odometry.em_start import kmeans_plusplus

POINTS = np.array([[0.0, 0, 0], [1.0, 0, 0], [0, 2.0, 0], [0, 0, 3.0], [1.0, 1.0, 1.0]])
WEIGHTS = np.array([1.0, 3.0, 4.0, 0.3, 1.5])
SQUARED = np.sum((POINTS[:, None] - POINTS[None]) ** 2, axis=2)


def test_one_trial_seeds_by_weight_then_by_weight_times_squared_distance():
    """With one candidate per seed, k-means++ draws the first seed with probability ∝ w and the second ∝ w·D²:
    the joint frequencies of 20,000 draws of two seeds match those probabilities within 4.5 standard errors."""
    first = WEIGHTS / WEIGHTS.sum()
    second = WEIGHTS * SQUARED / (SQUARED @ WEIGHTS)[:, None]
    expected = first[:, None] * second
    n = 20_000
    counts = np.zeros((5, 5))
    rng = np.random.default_rng(0)
    for _ in range(n):
        a, b = kmeans_plusplus(POINTS, WEIGHTS, 2, rng, n_trials=1)
        counts[a, b] += 1
    standard_error = np.sqrt(expected * (1 - expected) / n)
    assert np.all(np.abs(counts / n - expected) <= 4.5 * standard_error + 1e-12)


@pytest.mark.parametrize("first", range(5))
def test_many_trials_keep_the_candidate_that_leaves_the_least_potential(first):
    """With 300 candidates every point at positive distance is drawn (each has probability ≥ 1% here), so the
    second seed is the point that minimises the potential Σ w·min(D²) left given the first, for any seed."""
    potential = np.array([WEIGHTS @ np.minimum(SQUARED[first], SQUARED[b]) for b in range(5)])
    best = int(np.argmin(potential))
    for seed in range(3):
        rng = np.random.default_rng(seed)
        chosen = [-1]
        while chosen[0] != first:  # draw again until the first seed is the one under test
            chosen = kmeans_plusplus(POINTS, WEIGHTS, 2, rng, n_trials=300)
        assert chosen == [first, best]


def test_seeds_are_distinct_points_and_reproducible():
    rng = np.random.default_rng(1)
    points = rng.normal(size=(1024, 3))
    weights = rng.uniform(0.1, 2.0, 1024)
    chosen = kmeans_plusplus(points, weights, 100, np.random.default_rng(5))
    assert len(set(chosen)) == 100
    assert chosen == kmeans_plusplus(points, weights, 100, np.random.default_rng(5))
