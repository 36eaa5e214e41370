"""The odometry frame's compiled kernels (dgmm.compiled.visibility, .measured_cut) against their numpy
formulas, computed here by brute force."""
import numpy as np
import pytest

from dgmm.compiled.measured_cut import _floored
from dgmm.compiled.visibility import seen_on_grid

RNG = np.random.default_rng(3)


def test_seen_on_grid_is_the_rounded_projection_onto_a_measured_pixel():
    measured = RNG.random((12, 16)) < 0.7
    camera = np.array([50.0, 55.0, 31.5, 23.5])
    rotation = np.linalg.qr(RNG.normal(size=(3, 3)))[0]
    rotation *= np.linalg.det(rotation)
    translation = np.array([0.1, -0.2, 0.3])
    points = RNG.normal(size=(500, 3)) + [0, 0, 2.0]
    moved = points @ rotation.T + translation
    front = moved[:, 2] > 0
    z = np.where(front, moved[:, 2], 1.0)
    col = np.rint((camera[0] * moved[:, 0] / z + camera[2]) / 4)
    row = np.rint((camera[1] * moved[:, 1] / z + camera[3]) / 4)
    inside = front & (col >= 0) & (col < 16) & (row >= 0) & (row < 12)
    expected = np.zeros(len(points), dtype=bool)
    expected[inside] = measured[row[inside].astype(int), col[inside].astype(int)]
    assert 0 < expected.sum() < inside.sum() < len(points)
    np.testing.assert_array_equal(seen_on_grid(points, rotation, translation, camera, 4, measured), expected)


@pytest.mark.parametrize("values", [(-1e-4, 2e-3, 1e-2), (0.0, 1e-3, 1e-2), (1e-12, 1e-3, 1e-2)],
                         ids=["negative", "zero", "below the floor"])
def test_floored_lifts_small_eigenvalues_to_a_millionth_of_the_largest(values):
    vectors = np.linalg.qr(RNG.normal(size=(3, 3)))[0]
    covariance = (vectors * values) @ vectors.T
    expected = (vectors * np.maximum(values, 1e-6 * values[2])) @ vectors.T
    _floored(covariance)
    np.testing.assert_allclose(covariance, expected, rtol=0, atol=1e-15)


def test_floored_leaves_a_covariance_above_the_floor_as_it_is():
    vectors = np.linalg.qr(RNG.normal(size=(3, 3)))[0]
    covariance = (vectors * [1e-5, 1e-3, 1e-2]) @ vectors.T
    before = covariance.copy()
    _floored(covariance)
    np.testing.assert_array_equal(covariance, before)
