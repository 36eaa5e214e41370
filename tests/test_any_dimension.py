"""GaussianMixture in any dimension against independent references: scikit-learn step for step on points,
Monte Carlo and closed forms for triangles and Gaussian primitives."""
import warnings

import numpy as np
import pytest
from scipy.stats import multivariate_normal
from sklearn.mixture import GaussianMixture as SklearnGaussianMixture

from dgmm import GaussianMixture, InputError, Primitives
from tests.test_primitives import uniform_in_triangle

PARAMETERS = ("weights_", "means_", "covariances_", "precisions_cholesky_")


def clustered_points(d, n, n_clusters, seed):
    """``n`` points in ``d`` dimensions around ``n_clusters`` centres with random full covariances."""
    rng = np.random.default_rng(seed)
    centres = rng.normal(scale=4.0, size=(n_clusters, d))
    mixing = rng.normal(size=(n_clusters, d, d)) / np.sqrt(d) + np.eye(d)
    labels = rng.integers(n_clusters, size=n)
    return centres[labels] + np.einsum("nij,nj->ni", mixing[labels], rng.normal(size=(n, d)))


@pytest.mark.parametrize("covariance_type", ["full", "tied", "diag", "spherical"])
@pytest.mark.parametrize("d", [1, 2, 3, 8, 32])
@pytest.mark.parametrize("max_iter", [1, 2, 3])
def test_points_equal_scikit_learn_step_for_step(d, max_iter, covariance_type):
    """From scikit-learn's starting parameters, ``max_iter`` EM iterations give scikit-learn's parameters and bounds
    to 1e-10 of their scale, for each covariance type."""
    points = clustered_points(d, 1500, 3, seed=d)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # scikit-learn warns that a few iterations do not converge
        start = SklearnGaussianMixture(4, covariance_type=covariance_type, init_params="random", max_iter=1,
                                       random_state=0).fit(points)
        init = dict(weights_init=start.weights_, means_init=start.means_, precisions_init=start.precisions_)
        reference = SklearnGaussianMixture(4, covariance_type=covariance_type, max_iter=max_iter, tol=0,
                                           **init).fit(points)
    ours = GaussianMixture(4, covariance_type=covariance_type, max_iter=max_iter, tol=None, **init).fit(points)

    assert ours.n_features_in_ == d
    for name in PARAMETERS[:3]:
        expected = getattr(reference, name)
        np.testing.assert_allclose(getattr(ours, name), expected, rtol=0, atol=1e-10 * np.abs(expected).max(),
                                   err_msg=name)
    # each precision to 1e-9 of itself: the moment form's variance (E[x²] − μ²) loses the digits of E[x²] / σ², and the
    # tightest component (d=32, spherical: σ² = 3.5e-5 among coordinates of size 4, a ratio of 5e5) keeps 10 of 16
    np.testing.assert_allclose(ours.precisions_cholesky_, reference.precisions_cholesky_, rtol=1e-9,
                               atol=1e-10 * np.abs(reference.precisions_cholesky_).max(),
                               err_msg="precisions_cholesky_")
    np.testing.assert_allclose(ours.history_, reference.lower_bounds_[1:], rtol=0, atol=1e-10)
    assert ours.lower_bound_ == pytest.approx(reference.lower_bound_, abs=1e-10)
    # relative: a log-likelihood of -64 moves by 1e-9 when a variance moves by 2e-11 of itself (d=32, spherical)
    np.testing.assert_allclose(ours.score_samples(points), reference.score_samples(points), rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(ours.predict_proba(points), reference.predict_proba(points), rtol=0, atol=1e-10)


@pytest.mark.parametrize("d", [2, 4])
def test_triangle_moments_equal_monte_carlo(d):
    """A triangle's area is the Gram determinant's, its second moment ``E[x xᵀ]`` the Monte Carlo one, and its
    E-step term ``E_x[log N(x)]`` under a Gaussian the Monte Carlo mean of scipy's log-density."""
    rng = np.random.default_rng(d)
    triangle = rng.normal(size=(3, d)) + 0.5
    prims = Primitives.from_mesh(triangle, [[0, 1, 2]])
    edges = triangle[1:] - triangle[0]
    assert prims.weights[0] == pytest.approx(0.5 * np.sqrt(np.linalg.det(edges @ edges.T)), rel=1e-12)

    samples = uniform_in_triangle(triangle, 400_000, rng)
    outer = samples[:, :, None] * samples[:, None, :]
    standard_error = outer.std(axis=0) / np.sqrt(len(samples))
    assert np.all(np.abs(prims.second_moments[0] - outer.mean(axis=0)) < 5 * standard_error + 1e-12)

    mean = rng.normal(size=d)
    factor = rng.normal(size=(d, d))
    covariance = factor @ factor.T + np.eye(d)
    gmm = GaussianMixture.from_parameters([1.0], [mean], [covariance])
    log_density = multivariate_normal(mean, covariance).logpdf(samples)
    assert abs(gmm.score_primitives(prims) - log_density.mean()) < 5 * log_density.std() / np.sqrt(len(samples))


@pytest.mark.parametrize("covariance_type", ["full", "tied", "diag", "spherical"])
def test_triangles_covariance_types_equal_monte_carlo(covariance_type):
    """One component fitted to triangles in 4-D: the covariance of the surface (Monte Carlo: points uniform over it,
    triangles picked by area) in the type's form, its full matrix (full, tied: pooled over one component), its
    diagonal or its mean variance; and its E-step term against scipy's log-density of that covariance."""
    rng = np.random.default_rng(5)
    d = 4
    vertices = rng.normal(size=(12, d))
    faces = np.array([[0, 1, 2], [3, 4, 5], [6, 7, 8], [9, 10, 11]])
    prims = Primitives.from_mesh(vertices, faces)
    gmm = GaussianMixture(1, covariance_type=covariance_type, max_iter=1, tol=None, reg_covar=0.0).fit(prims)

    n = 400_000
    picked = rng.choice(len(faces), size=n, p=prims.weights / prims.weights.sum())
    samples = np.empty((n, d))
    for t, face in enumerate(faces):
        samples[picked == t] = uniform_in_triangle(vertices[face], np.count_nonzero(picked == t), rng)
    centred = samples - samples.mean(axis=0)
    products = centred[:, :, None] * centred[:, None, :]
    covariance, error = products.mean(axis=0), 5 * products.std(axis=0) / np.sqrt(n)
    if covariance_type == "full":
        expected, error = covariance[None], error[None]
    elif covariance_type == "tied":
        expected = covariance
    elif covariance_type == "diag":
        expected, error = np.diag(covariance)[None], np.diag(error)[None]
    else:  # the mean of the variances: a mean over samples of the mean squared coordinate
        squares = np.einsum("ni,ni->n", centred, centred) / d
        expected, error = [squares.mean()], 5 * squares.std() / np.sqrt(n)
    assert np.all(np.abs(gmm.covariances_ - expected) < error)

    mean = gmm.means_[0]
    full = {"full": lambda c: c[0], "tied": lambda c: c, "diag": lambda c: np.diag(c[0]),
            "spherical": lambda c: c[0] * np.eye(d)}[covariance_type](gmm.covariances_)
    triangle = vertices[faces[0]]
    points = uniform_in_triangle(triangle, n, rng)
    log_density = multivariate_normal(mean, full).logpdf(points)
    bound = gmm.primitive_bounds(Primitives.from_mesh(triangle, [[0, 1, 2]]))[0]
    assert abs(bound - log_density.mean()) < 5 * log_density.std() / np.sqrt(n)


def test_one_component_fit_to_gaussians_is_their_moment_match():
    """One component fitted to Gaussian primitives in 5-D is their size-weighted mixture's mean and covariance
    (plus reg_covar), from the closed form ``Σ_p w_p (Σ_p + μ_p μ_pᵀ) / Σ_p w_p − μ μᵀ``."""
    rng = np.random.default_rng(1)
    d, n = 5, 40
    means = rng.normal(size=(n, d))
    factors = rng.normal(size=(n, d, d)) * 0.3
    covariances = factors @ np.swapaxes(factors, 1, 2)
    sizes = rng.uniform(0.5, 2.0, size=n)
    gmm = GaussianMixture(1, max_iter=2, reg_covar=1e-6).fit(Primitives.from_gaussians(means, covariances, sizes))

    mean = sizes @ means / sizes.sum()
    second = np.einsum("p,pij->ij", sizes, covariances + means[:, :, None] * means[:, None, :]) / sizes.sum()
    np.testing.assert_allclose(gmm.means_[0], mean, rtol=0, atol=1e-12)
    np.testing.assert_allclose(gmm.covariances_[0], second - np.outer(mean, mean) + 1e-6 * np.eye(d),
                               rtol=0, atol=1e-12)


def test_a_mixture_in_2d_fits_triangles_and_samples_its_dimension():
    rng = np.random.default_rng(2)
    vertices = rng.uniform(size=(30, 2))
    faces = np.array([rng.choice(30, 3, replace=False) for _ in range(40)])
    gmm = GaussianMixture(3, random_state=0).fit(Primitives.from_mesh(vertices, faces))
    assert gmm.means_.shape == (3, 2) and gmm.sample(10)[0].shape == (10, 2)
    with pytest.raises(InputError, match="X has 3 features, but GaussianMixture is expecting 2"):
        gmm.predict(np.zeros((4, 3)))


def test_triangles_need_two_dimensions():
    with pytest.raises(InputError, match="d >= 2 for triangles"):
        Primitives.from_mesh(np.zeros((3, 1)), [[0, 1, 2]])


def test_screened_fit_outside_3d_is_the_unscreened_one():
    """At ``screen=50`` terms are dropped only below e^-50 of a primitive's largest: in 2-D (numpy's screened
    exponentials, not the 3-D kernel) the fit is scikit-learn's unscreened one from the same start."""
    points = clustered_points(2, 1000, 4, seed=7)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        start = SklearnGaussianMixture(4, init_params="random", max_iter=1, random_state=0).fit(points)
        init = dict(weights_init=start.weights_, means_init=start.means_, precisions_init=start.precisions_)
        reference = SklearnGaussianMixture(4, max_iter=5, tol=0, **init).fit(points)
    ours = GaussianMixture(4, max_iter=5, tol=None, screen=50.0, memory_limit=20_000, **init).fit(points)
    for name in PARAMETERS:
        expected = getattr(reference, name)
        np.testing.assert_allclose(getattr(ours, name), expected, rtol=0, atol=1e-10 * np.abs(expected).max())
