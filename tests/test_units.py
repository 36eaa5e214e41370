"""Units do not matter: fitting ``s · X`` (with ``reg_covar · s²``) gives the mixture of ``X`` scaled by ``s``.

The reference is the fit of ``X`` itself, at unit scale, mapped by the closed-form change of variables
(means × s, covariances × s², precision Choleskys / s, weights unchanged, bound and log-likelihoods − 3 log s);
the data are normalised to an RMS radius near 1 first, so ``s`` is the data's own scale. ``tol=0`` runs the same
25 iterations at every scale: with ``tol > 0`` a bound change sitting at ``tol`` can stop one fit an iteration
before the other (as a one-ulp change of the input can), leaving them 1e-10 apart.
"""
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from dgmm import GaussianMixture, InputError, Primitives

REG = 1e-6
RTOL = 1e-9
scales = st.floats(-150.0, 150.0).map(lambda exponent: 10.0**exponent)


def clustered_points(seed, n=400):
    """Three anisotropic clusters, RMS radius about their centre 1 (rounded)."""
    rng = np.random.default_rng(seed)
    centres = rng.normal(scale=3.0, size=(3, 3))
    points = centres[rng.integers(3, size=n)] + rng.normal(size=(n, 3)) * rng.uniform(0.2, 1.0, size=3)
    points -= points.mean(axis=0)
    return points / np.sqrt((points**2).sum(axis=1).mean())


def triangles(seed, n=300):
    """Random triangles about the clustered points, sides about a tenth of the radius, as vertices and faces."""
    rng = np.random.default_rng(seed)
    corners = clustered_points(seed, n)[:, None, :] + rng.normal(scale=0.1, size=(n, 3, 3))
    return corners.reshape(-1, 3), np.arange(3 * n).reshape(n, 3)


def assert_scaled(fit, reference, scale, queries):
    """``fit`` is ``reference`` with lengths multiplied by ``scale``, to RTOL of each quantity's size."""
    np.testing.assert_allclose(fit.weights_, reference.weights_, rtol=0, atol=RTOL)
    np.testing.assert_allclose(fit.means_ / scale, reference.means_, rtol=0, atol=RTOL)
    np.testing.assert_allclose(fit.covariances_ / scale**2, reference.covariances_, rtol=0,
                               atol=RTOL * np.abs(reference.covariances_).max())
    np.testing.assert_allclose(fit.precisions_cholesky_ * scale, reference.precisions_cholesky_, rtol=0,
                               atol=RTOL * np.abs(reference.precisions_cholesky_).max())
    shift = 3.0 * np.log(scale)  # log-densities in units scaled by s lose log s³
    tolerance = RTOL * max(1.0, abs(reference.lower_bound_))
    assert fit.lower_bound_ + shift == pytest.approx(reference.lower_bound_, abs=tolerance)
    assert fit.score_primitives(queries(scale)) + shift == pytest.approx(
        reference.score_primitives(queries(1.0)), abs=tolerance)


@pytest.mark.slow
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scale=scales, seed=st.integers(0, 2**16), init=st.sampled_from(["kmeans", "random"]))
def test_point_fits_scale_with_the_data(scale, seed, init):
    points = clustered_points(seed)
    fit = lambda s: GaussianMixture(3, init=init, tol=0.0, reg_covar=REG * s**2, random_state=seed).fit(points * s)
    assert_scaled(fit(scale), fit(1.0), scale, lambda s: points[::7] * s)


@pytest.mark.slow
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scale=scales, seed=st.integers(0, 2**16), variant=st.sampled_from(["textbook", "authors"]))
def test_triangle_fits_scale_with_the_data(scale, seed, variant):
    vertices, faces = triangles(seed)
    mesh = lambda s: Primitives.from_mesh(vertices * s, faces)
    fit = lambda s: GaussianMixture(3, variant=variant, tol=0.0, reg_covar=REG * s**2, random_state=seed).fit(mesh(s))
    assert_scaled(fit(scale), fit(1.0), scale, mesh)


def test_coordinates_whose_squares_overflow_are_an_input_error():
    """1e200 is refused, not fitted: its covariances (1e400 in squared units) are not float64 numbers."""
    with pytest.raises(InputError, match="rescale the input"):
        GaussianMixture(2).fit(clustered_points(0) * 1e200)
    with pytest.raises(InputError, match="rescale the input"):
        GaussianMixture(2).fit(clustered_points(0) * 1e-200)
