"""The odometry's EM start compiled (dgmm.compiled.em_start) against the numpy steps it replaced, pick for pick:
k-means++'s loop of numpy products, and the Lloyd pass's product of the points with a column of ones against the
lifted centres and its argmin."""
import numpy as np
import pytest

from dgmm.compiled.em_start import _first_at_least, cluster_scatters, cluster_sums, nearest_centres
from dgmm.odometry import CAMERAS, pixel_primitives, read_sequence
from dgmm.odometry.em_start import kmeans_plusplus
from dgmm.variants import VARIANTS
from tests.test_odometry_metrics import FR1_XYZ, needs_fr1


def numpy_labels(points, centres):
    """The numpy Lloyd pass: ``[x, 1] @ [-2c, |c|²]`` and its argmin (the first centre at a tie)."""
    lifted = np.hstack([points, np.ones((len(points), 1))])
    return (lifted @ np.vstack([-2.0 * centres.T, np.sum(centres ** 2, axis=1)])).argmin(axis=1)


def compiled_labels(points, centres):
    lifted_centres = np.vstack([-2.0 * centres.T, np.sum(centres ** 2, axis=1)])
    return nearest_centres(np.ascontiguousarray(points.T), lifted_centres)


def lloyd_labels(points, centres, labels_of, passes=4):
    """The labels of every pass of Lloyd's iterations (unweighted) from ``centres``."""
    centres, passes_labels = centres.copy(), []
    for _ in range(passes):
        labels = labels_of(points, centres)
        passes_labels.append(labels)
        mass = np.bincount(labels, minlength=len(centres))
        present = mass > 0
        sums = np.stack([np.bincount(labels, points[:, d], minlength=len(centres)) for d in range(3)], 1)
        centres[present] = sums[present] / mass[present, None]
    return passes_labels


def test_labels_are_the_numpy_passes_at_ties_too():
    """Random points, and points on a grid with centres repeated and placed half-way between grid points: every
    value ties with another's and the first centre must win."""
    rng = np.random.default_rng(0)
    points = rng.normal(size=(5000, 3))
    centres = points[rng.choice(5000, 100, replace=False)]
    np.testing.assert_array_equal(compiled_labels(points, centres), numpy_labels(points, centres))
    grid = np.stack(np.meshgrid(*[np.arange(8.0)] * 3), axis=-1).reshape(-1, 3)
    tied = np.concatenate([grid[::5] + 0.5, grid[::7]])
    tied = np.concatenate([tied, tied[::3]])  # repeated centres
    labels = compiled_labels(grid, tied)
    np.testing.assert_array_equal(labels, numpy_labels(grid, tied))
    assert len(np.unique(labels)) < len(tied)  # the repeats never win


@needs_fr1
@pytest.mark.parametrize("frame", [0, 400, 797])
def test_lloyd_passes_on_fr1_frames_label_as_numpy(frame):
    """Four Lloyd passes from 100 centres drawn among an fr1/xyz frame's primitives: the same labels in every pass."""
    points = pixel_primitives(read_sequence(FR1_XYZ).depth(frame), CAMERAS["ros"]).means
    centres = points[np.random.default_rng(frame).choice(len(points), 100, replace=False)]
    for compiled, numpy in zip(lloyd_labels(points, centres, compiled_labels),
                               lloyd_labels(points, centres, numpy_labels), strict=True):
        np.testing.assert_array_equal(compiled, numpy)


def numpy_kmeans_plusplus(points, weights, n_clusters, rng, n_trials=None):
    """The numpy k-means++ that :func:`dgmm.odometry.em_start.kmeans_plusplus` compiled, as it was."""
    n_trials = 2 + int(np.log(n_clusters)) if n_trials is None else n_trials
    points = points - points.mean(axis=0)
    norms = np.einsum("ij,ij->i", points, points)
    chosen = [rng.choice(len(points), p=weights / weights.sum())]
    closest = np.maximum(norms + norms[chosen[0]] - 2.0 * points @ points[chosen[0]], 0.0)
    for _ in range(1, n_clusters):
        cumulative = np.cumsum(weights * closest)
        candidates = np.minimum(np.searchsorted(cumulative, rng.random(n_trials) * cumulative[-1]), len(points) - 1)
        reach = norms[candidates, None] - 2.0 * points[candidates] @ points.T
        reach += norms
        np.minimum(closest, reach, out=reach)
        best = int(np.argmin(reach @ weights))
        chosen.append(int(candidates[best]))
        closest = np.maximum(reach[best], 0.0)
    return chosen


def test_seeds_are_the_numpy_loops_with_repeated_points():
    """Points on a coarse grid, each repeated (candidates drawn twice, potentials tied to rounding), and points at
    random, 20 generators each: the same seeds, and the generators left in the same state."""
    rng = np.random.default_rng(2)
    grid = np.stack(np.meshgrid(*[np.arange(6.0)] * 3), axis=-1).reshape(-1, 3)
    for points in (np.concatenate([grid, grid, grid[::2]]), rng.normal(size=(1024, 3))):
        weights = rng.uniform(0.1, 2.0, len(points))
        for seed in range(20):
            compiled_rng, numpy_rng = np.random.default_rng(seed), np.random.default_rng(seed)
            assert (kmeans_plusplus(points, weights, 100, compiled_rng)
                    == numpy_kmeans_plusplus(points, weights, 100, numpy_rng))
            assert compiled_rng.random() == numpy_rng.random()


@needs_fr1
@pytest.mark.parametrize("variant", ["textbook", "authors"])
@pytest.mark.parametrize("size", ["area", "unit"])
def test_seeds_on_fr1_samples_are_the_numpy_loops(variant, size):
    """The odometry's seeds (1,024 primitives drawn from an fr1/xyz frame, their M-step weights) of 10 frames."""
    sequence = read_sequence(FR1_XYZ)
    for frame in range(0, 798, 80):
        prims = pixel_primitives(sequence.depth(frame), CAMERAS["ros"], size=size)
        weights = VARIANTS[variant](prims.weights)[1]
        sample = np.random.default_rng(frame).choice(len(prims.means), 1024, replace=False)
        assert (kmeans_plusplus(prims.means[sample], weights[sample], 100, np.random.default_rng(frame))
                == numpy_kmeans_plusplus(prims.means[sample], weights[sample], 100, np.random.default_rng(frame)))


def test_cluster_sums_are_numpys_bincounts():
    """Weights and weighted sums per cluster, bit for bit those of ``np.bincount`` (empty clusters 0)."""
    rng = np.random.default_rng(3)
    labels = rng.integers(0, 40, 5000)
    labels[labels == 7] = 8  # an empty cluster
    weights, values = rng.uniform(0.1, 2.0, 5000), rng.normal(size=(5000, 6))
    mass, sums = cluster_sums(labels, weights, values, 41)
    np.testing.assert_array_equal(mass, np.bincount(labels, weights, minlength=41))
    for m in range(6):
        np.testing.assert_array_equal(sums[:, m], np.bincount(labels, weights * values[:, m], minlength=41))


def test_cluster_scatters_are_the_numpy_rows_bincounted():
    """Each cluster's ``Σ w ((x - c)(x - c)ᵀ + C)`` entries, bit for bit the bincounts of numpy's rows
    ``(x - c)_a (x - c)_b + C_ab`` as the numpy start summed them."""
    rng = np.random.default_rng(4)
    points, labels = rng.normal(size=(3000, 3)), rng.integers(0, 30, 3000)
    centres, weights = rng.normal(size=(30, 3)), rng.uniform(0.1, 2.0, 3000)
    factors = rng.normal(size=(3000, 3, 3))
    covariances = factors @ factors.transpose(0, 2, 1)
    rows, cols = np.array([0, 1, 2, 0, 0, 1]), np.array([0, 1, 2, 1, 2, 2])
    offsets = points - centres[labels]
    moments = offsets[:, rows] * offsets[:, cols] + covariances[:, rows, cols]
    expected = np.stack([np.bincount(labels, weights * moments[:, m], minlength=30) for m in range(6)], 1)
    np.testing.assert_array_equal(cluster_scatters(labels, weights, points, centres, covariances), expected)


def test_a_draw_lands_where_numpy_searchsorted_puts_it_ties_included():
    """k-means++'s draw of a candidate (``_first_at_least``) is ``np.searchsorted``'s left side, on cumulative
    potentials with flat runs (repeated points add 0) and on draws that equal an entry, at its ends and past them."""
    cumulative = np.cumsum([0.0, 0.0, 1.0, 0.0, 0.0, 2.5, 0.0, 3.0, 0.0])
    for value in [-1.0, 0.0, 0.5, 1.0, 2.0, 3.5, 4.0, 6.5, 7.0, 1e9, *np.unique(cumulative)]:
        assert _first_at_least(cumulative, value) == np.searchsorted(cumulative, value, side="left"), value
