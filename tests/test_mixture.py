"""GaussianMixture against independent references: Monte Carlo, quadrature, scikit-learn, the paper."""
import copy
import warnings

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import logsumexp
from scipy.stats import multivariate_normal
from sklearn.base import clone
from sklearn.mixture import GaussianMixture as SklearnGaussianMixture

import dgmm.mixture
from dgmm import FitError, GaussianMixture, InputError, Primitives
from tests.test_primitives import uniform_in_triangle


def test_expected_log_density_over_a_triangle_equals_monte_carlo():
    rng = np.random.default_rng(3)
    triangle = np.array([[0.1, 0.2, 0.0], [0.9, -0.3, 0.4], [0.2, 0.8, -0.5]])
    mean = np.array([0.3, 0.1, 0.2])
    covariance = np.array([[0.5, 0.1, 0.0], [0.1, 0.3, -0.05], [0.0, -0.05, 0.2]])
    gmm = GaussianMixture.from_parameters([1.0], [mean], [covariance])
    closed_form = gmm.score_primitives(Primitives.from_mesh(triangle, [[0, 1, 2]]))

    log_density = multivariate_normal(mean, covariance).logpdf(uniform_in_triangle(triangle, 1_000_000, rng))
    standard_error = log_density.std() / np.sqrt(len(log_density))
    assert abs(closed_form - log_density.mean()) < 5 * standard_error


def component_log_densities(model, points):
    """``log lambda_i + log N(x; mu_i, Sigma_i)`` of each point under each component, from scipy, (n, K)."""
    return np.stack([np.log(w) + multivariate_normal(mean, cov).logpdf(points)
                     for w, mean, cov in zip(model.weights_, model.means_, model.covariances_)], axis=-1)


def triangle_terms(model, vertices, faces):
    """Per-triangle ``log rho`` of the textbook E-step, from scipy and the triangles' vertex formula, (P, K)."""
    triangles = vertices[faces]
    centroids = triangles.mean(axis=1)
    offsets = triangles - centroids[:, None]
    covariances = np.einsum("pvi,pvj->pij", offsets, offsets) / 12  # (A Aᵀ + B Bᵀ + C Cᵀ − 3 m mᵀ) / 12
    traces = np.einsum("kij,pji->pk", np.linalg.inv(model.covariances_), covariances)
    return component_log_densities(model, centroids) - 0.5 * traces


def jensen_gap_upper_bound(model, vertices, faces):
    """An upper bound of (surface average of log g) − (triangle bound of eq. 11), from closed forms.

    Each ``log N_i`` is concave, so below its tangent plane ``l_i`` at the centroid; ``logsumexp`` of planes is
    convex in x, so its mean over a triangle is at most its mean over the vertices. Hence
    ``E_x[log g] <= mean_v logsumexp_i l_i(v)``, and the gap is at most that minus the bound.
    """
    triangles = vertices[faces]
    centroids = triangles.mean(axis=1)
    at_centroid = component_log_densities(model, centroids)
    gradients = -np.einsum("kij,pkj->pki", np.linalg.inv(model.covariances_), centroids[:, None] - model.means_)
    planes = at_centroid[:, None, :] + np.einsum("pki,pvi->pvk", gradients, triangles - centroids[:, None])
    areas = 0.5 * np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]),
                                 axis=1)
    upper = logsumexp(planes, axis=2).mean(axis=1) - logsumexp(triangle_terms(model, vertices, faces), axis=1)
    return float(areas @ upper / areas.sum())


def test_mesh_bound_is_the_closed_form_and_below_the_surface_average_log_likelihood(bunny_res4):
    """The triangle bound equals eq. 11 computed here with scipy (log-weights, centroid densities, trace terms,
    area weights: 1e-10), and lies below the surface average of log g(x) (Monte Carlo, Jensen) by at most the
    tangent-plane bound (0.82 nats here; the gap is 0.13). Dropping or doubling the trace term moves the bound by
    0.13, dropping the log-weights by up to log 20 = 3.0."""
    gmm = GaussianMixture(20, random_state=0).fit(bunny_res4.vertices)
    vertices, faces = np.asarray(bunny_res4.vertices), np.asarray(bunny_res4.faces)
    bound = gmm.score_primitives(bunny_res4)
    areas = bunny_res4.area_faces
    expected = areas @ logsumexp(triangle_terms(gmm, vertices, faces), axis=1) / areas.sum()
    assert bound == pytest.approx(expected, rel=1e-10)

    log_likelihood = gmm.score_samples(trimesh.sample.sample_surface(bunny_res4, 200_000, seed=4)[0])
    standard_error = log_likelihood.std() / np.sqrt(len(log_likelihood))
    gap = log_likelihood.mean() - bound
    assert -5 * standard_error <= gap <= jensen_gap_upper_bound(gmm, vertices, faces) + 5 * standard_error


def area_weighted_surface_moments(mesh):
    """Surface mean and covariance by the edge-midpoint rule, exact for quadratics over a triangle."""
    tri = mesh.triangles
    midpoints = (tri + np.roll(tri, -1, axis=1)) / 2  # (n_faces, 3, 3)
    areas = mesh.area_faces
    total = areas.sum()
    mean = np.einsum("f,fvi->i", areas, midpoints) / 3 / total
    second = np.einsum("f,fvi,fvj->ij", areas, midpoints, midpoints) / 3 / total
    return mean, second - np.outer(mean, mean)


def test_one_component_fit_is_the_surface_moments_and_resampling_invariant(bunny_res4):
    mean, covariance = area_weighted_surface_moments(bunny_res4)
    finer = bunny_res4.subdivide()  # every triangle split into four
    assert len(finer.faces) == 4 * len(bunny_res4.faces)
    for mesh in (bunny_res4, finer):
        gmm = GaussianMixture(1, reg_covar=0.0, max_iter=3).fit(mesh)
        np.testing.assert_allclose(gmm.means_[0], mean, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(gmm.covariances_[0], covariance, rtol=1e-10, atol=1e-12 * np.abs(covariance).max())
    coarse = GaussianMixture(1, reg_covar=0.0).fit(bunny_res4).score_primitives(bunny_res4)
    assert GaussianMixture(1, reg_covar=0.0).fit(finer).score_primitives(finer) == pytest.approx(coarse, rel=1e-12)


@pytest.mark.parametrize("n_components", [1, 7, pytest.param(30, marks=pytest.mark.slow)])
def test_points_agree_with_scikit_learn_from_the_same_start(bunny_res4, n_components):
    points = trimesh.sample.sample_surface(bunny_res4, 3000, seed=5)[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # scikit-learn warns that 1 and 25 iterations do not converge
        start = SklearnGaussianMixture(n_components, init_params="random", max_iter=1, random_state=0).fit(points)
        init = dict(weights_init=start.weights_, means_init=start.means_, precisions_init=start.precisions_)
        reference = SklearnGaussianMixture(n_components, max_iter=25, tol=0, **init).fit(points)
    ours = GaussianMixture(n_components, max_iter=25, tol=0, **init).fit(points)

    for name in ("weights_", "means_", "covariances_", "precisions_cholesky_"):
        expected = getattr(reference, name)
        np.testing.assert_allclose(getattr(ours, name), expected, rtol=1e-8, atol=1e-8 * np.abs(expected).max())
    # scikit-learn's bound at iteration t is that of the parameters before its t-th M-step.
    np.testing.assert_allclose(ours.history_[:-1], reference.lower_bounds_[1:], rtol=0, atol=1e-10)
    assert ours.lower_bound_ == pytest.approx(reference.score(points), abs=1e-10)
    np.testing.assert_allclose(ours.score_samples(points), reference.score_samples(points), rtol=0, atol=1e-9)
    assert ours.n_iter_ == 25 and not ours.converged_


def test_tol_none_runs_every_iteration_without_the_final_e_step_as_scikit_learn_bounds(bunny_res4, monkeypatch):
    """``tol=None``: the parameters after 3 iterations are scikit-learn's from the same start; the E-step after the
    last M-step is not run (3 E-steps, not 4), so ``lower_bound_`` is the bound before that M-step, which is
    what scikit-learn's ``lower_bound_`` is."""
    points = trimesh.sample.sample_surface(bunny_res4, 3000, seed=5)[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # scikit-learn warns that 1 and 3 iterations do not converge
        start = SklearnGaussianMixture(7, init_params="random", max_iter=1, random_state=0).fit(points)
        init = dict(weights_init=start.weights_, means_init=start.means_, precisions_init=start.precisions_)
        reference = SklearnGaussianMixture(7, max_iter=3, tol=0, **init).fit(points)
    e_steps = []
    e_step = dgmm.mixture._e_step
    monkeypatch.setattr(dgmm.mixture, "_e_step", lambda *args: e_steps.append(1) or e_step(*args))
    ours = GaussianMixture(7, max_iter=3, tol=None, **init).fit(points)

    assert len(e_steps) == 3
    for name in ("weights_", "means_", "covariances_", "precisions_cholesky_"):
        expected = getattr(reference, name)
        np.testing.assert_allclose(getattr(ours, name), expected, rtol=1e-8, atol=1e-8 * np.abs(expected).max())
    np.testing.assert_allclose(ours.history_, reference.lower_bounds_[1:], rtol=0, atol=1e-10)
    assert ours.lower_bound_ == pytest.approx(reference.lower_bound_, abs=1e-10)
    assert ours.n_iter_ == 3 and not ours.converged_


def test_scores_of_many_points_do_not_depend_on_the_blocks(bunny_res4):
    """Scoring streams over cache-sized blocks of rows (655 at K=200): every point's log-likelihood must be
    scikit-learn's under the same parameters, and the same bits however the points are split."""
    gmm = GaussianMixture(200, max_iter=5, random_state=0).fit(bunny_res4)
    points = trimesh.sample.sample_surface(bunny_res4, 3000, seed=6)[0]
    reference = SklearnGaussianMixture(200, covariance_type="full")
    reference.weights_, reference.means_ = gmm.weights_, gmm.means_
    reference.covariances_, reference.precisions_cholesky_ = gmm.covariances_, gmm.precisions_cholesky_
    scores = gmm.score_samples(points)
    np.testing.assert_allclose(scores, reference.score_samples(points), rtol=0, atol=1e-9)
    split = np.concatenate([gmm.score_samples(points[:1000]), gmm.score_samples(points[1000:])])
    assert np.array_equal(scores, split)
    prepared = Primitives.from_points(points)  # an evaluation set built once for many mixtures: the same bits
    assert np.array_equal(gmm.score_samples(prepared), scores) and gmm.score(prepared) == gmm.score(points)
    with pytest.raises(InputError, match="score_samples takes points"):
        gmm.score(Primitives.from_mesh(bunny_res4))


def random_mesh(seed, n_faces):
    rng = np.random.default_rng(seed)
    vertices = rng.normal(size=(n_faces + 2, 3)) * rng.uniform(0.2, 3.0, size=3)
    faces = np.array([rng.choice(len(vertices), 3, replace=False) for _ in range(n_faces)])
    return vertices, faces


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_faces=st.integers(12, 80), n_components=st.integers(1, 4),
       init=st.sampled_from(["kmeans", "random"]))
def test_em_never_decreases_its_bound(seed, n_faces, n_components, init):
    """EM's bound must rise at every iteration (up to rounding). Triangles thickened by ``r I`` (Gaussian
    primitives) keep every covariance full rank without ``reg_covar``, which would make the M-step inexact."""
    vertices, faces = random_mesh(seed, n_faces)
    prims = Primitives.from_mesh(vertices, faces)
    thick = Primitives(prims.means, prims.covariances + 1e-3 * np.eye(3), prims.weights)
    gmm = GaussianMixture(n_components, init=init, reg_covar=0.0, max_iter=15, tol=0, random_state=seed).fit(thick)
    bounds = gmm.history_
    assert len(bounds) == 15
    assert np.all(np.diff(bounds) >= -1e-12 * np.maximum(1.0, np.abs(bounds[1:])))


@pytest.mark.parametrize("init", ["kmeans", "random"])
def test_random_state_makes_fits_bit_identical(bunny_res4, init):
    fits = [GaussianMixture(10, init=init, random_state=seed).fit(bunny_res4) for seed in (7, 7, 8)]
    for name in ("weights_", "means_", "covariances_"):
        assert np.array_equal(getattr(fits[0], name), getattr(fits[1], name))
        assert not np.array_equal(getattr(fits[0], name), getattr(fits[2], name))
    assert fits[0].history_ == fits[1].history_


def test_authors_variant_equals_textbook_where_sizes_are_equal():
    """The authors' E-step scale alpha/min(alpha) is 1 and their unweighted M-step is the area-weighted one
    when every triangle has the same area, and for points; so both variants must then give the same fit."""
    grid = trimesh.creation.box().subdivide().subdivide()  # a cube of equal right triangles
    assert np.allclose(grid.area_faces, grid.area_faces[0])
    for data in (grid, grid.vertices):
        textbook = GaussianMixture(6, random_state=0).fit(data)
        authors = GaussianMixture(6, random_state=0, variant="authors").fit(data)
        np.testing.assert_allclose(authors.means_, textbook.means_, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(authors.history_, textbook.history_, rtol=1e-10)


def authors_em(centroids, triangle_covariances, areas, weights, means, covariances, n_iter, reg_covar):
    """The authors' EM (leonidk/direct_gmm's modified scikit-learn 0.20), written from their description:
    each triangle's Mahalanobis-plus-trace term is multiplied by ``area / min(area)`` in the E-step; the M-step
    counts every triangle once (responsibility-weighted centroids, weights ``N_k / n``) and keeps the triangles'
    covariances. Plain loops over components, scipy for the Gaussian. Returns (weights, means, covariances,
    bounds), a bound (mean of log-sum-exp over triangles) after each iteration."""
    scale = areas / areas.min()
    bounds = []
    for _ in range(n_iter):
        log_rho = np.empty((len(centroids), len(weights)))
        for k, (weight, mean, covariance) in enumerate(zip(weights, means, covariances)):
            precision = np.linalg.inv(covariance)
            offsets = centroids - mean
            quadratic = np.einsum("pi,ij,pj->p", offsets, precision, offsets)
            trace = np.einsum("ij,pji->p", precision, triangle_covariances)
            log_det = np.linalg.slogdet(covariance)[1]
            log_rho[:, k] = np.log(weight) - 0.5 * (3 * np.log(2 * np.pi) + log_det + scale * (quadratic + trace))
        resp = np.exp(log_rho - logsumexp(log_rho, axis=1, keepdims=True))
        counts = resp.sum(axis=0) + 10 * np.finfo(float).eps
        weights = counts / len(centroids)
        means = resp.T @ centroids / counts[:, None]
        covariances = np.stack([
            (resp[:, k, None, None] * (np.einsum("pi,pj->pij", centroids - means[k], centroids - means[k])
                                       + triangle_covariances)).sum(axis=0) / counts[k] + reg_covar * np.eye(3)
            for k in range(len(weights))])
        bounds.append(logsumexp(log_rho, axis=1).mean())
    return weights, means, covariances, bounds


def test_authors_variant_equals_an_independent_implementation_on_unequal_triangles(bunny_res4):
    """bunny_res4's areas differ by a factor above 20, so the E-step scale matters. From the same start (random
    parameters given to both), 8 iterations agree to rounding. Tried wrong implementations move the component
    weights by: E-step scale over the mean area (the authors' earlier code) 70%, an area-weighted M-step 9%,
    textbook EM 45%, an unscaled E-step 49%; the tolerances (1e-9 relative) fail all of them."""
    triangles = bunny_res4.vertices[bunny_res4.faces]
    centroids, areas = triangles.mean(axis=1), bunny_res4.area_faces
    assert areas.max() / areas.min() > 20
    offsets = triangles - centroids[:, None]
    triangle_covariances = np.einsum("pvi,pvj->pij", offsets, offsets) / 12  # paper: (AAᵀ + BBᵀ + CCᵀ − 3mmᵀ) / 12
    rng = np.random.default_rng(11)
    k, n_iter, reg_covar = 6, 8, 1e-6
    start_weights = rng.dirichlet(np.ones(k))
    start_means = centroids[rng.choice(len(centroids), k, replace=False)]
    start_covariances = np.tile(np.cov(centroids.T), (k, 1, 1))
    init = dict(weights_init=start_weights, means_init=start_means,
                precisions_init=np.linalg.inv(start_covariances))
    ours = GaussianMixture(k, variant="authors", max_iter=n_iter, tol=0, reg_covar=reg_covar, **init).fit(bunny_res4)
    weights, means, covariances, bounds = authors_em(centroids, triangle_covariances, areas, start_weights,
                                                     start_means, start_covariances, n_iter, reg_covar)
    size = np.abs(centroids).max()
    np.testing.assert_allclose(ours.weights_, weights, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(ours.means_, means, rtol=0, atol=1e-9 * size)
    np.testing.assert_allclose(ours.covariances_, covariances, rtol=0, atol=1e-9 * np.abs(covariances).max())
    # Our bound after iteration t is that of the parameters of M-step t: the reference's next E-step.
    np.testing.assert_allclose(ours.history_[:-1], bounds[1:], rtol=1e-10)


def test_exact_mesh_fit_beats_vertex_fit_on_bunny_res4(bunny_res4):
    """Paper Fig 3 / Table 1: K=100, kmeans, 25 iterations; about 8.2 (mesh) vs 7.6 (vertices) nats."""
    evaluation = trimesh.sample.sample_surface(bunny_res4, 50_000, seed=6)[0]
    exact = GaussianMixture(100, random_state=0).fit(bunny_res4).score(evaluation)
    vertices = GaussianMixture(100, random_state=0).fit(bunny_res4.vertices).score(evaluation)
    assert exact > vertices
    assert exact == pytest.approx(8.2, abs=0.3)
    assert vertices == pytest.approx(7.6, abs=0.3)


def test_estimator_conventions(bunny_res4):
    gmm = GaussianMixture(5, random_state=1, max_iter=200, tol=1e-4)
    twin = clone(gmm)
    assert twin.get_params() == gmm.get_params()
    gmm.fit(bunny_res4.vertices)
    assert gmm.converged_ and gmm.n_iter_ < 200 and gmm.history_[-1] == gmm.lower_bound_
    labels = gmm.predict(bunny_res4.vertices)
    assert labels.shape == (len(bunny_res4.vertices),) and set(labels) <= set(range(5))
    assert gmm.predict(bunny_res4).shape == (len(bunny_res4.faces),)
    samples, components = gmm.sample(20_000)
    assert samples.shape == (20_000, 3)
    # Samples follow the mixture: their component frequencies match the weights within sampling error.
    frequencies = np.bincount(components, minlength=5) / 20_000
    assert np.all(np.abs(frequencies - gmm.weights_) < 5 * np.sqrt(gmm.weights_ / 20_000))


def test_each_component_s_samples_have_its_mean_and_covariance(bunny_res4):
    """Per component, sample mean and covariance within 5 standard errors (entry (i, j) of a sample covariance
    of n normal draws has variance (Σii Σjj + Σij²) / n). Tried: a transposed Cholesky factor (covariance Lᵀ L)
    misses by 44 standard errors, samples drawn with other components' factors than their labels by 121."""
    gmm = GaussianMixture(5, random_state=1).fit(bunny_res4)
    samples, components = gmm.sample(50_000)
    for k, (mean, covariance) in enumerate(zip(gmm.means_, gmm.covariances_)):
        own = samples[components == k]
        n = len(own)
        mean_error = np.abs(own.mean(axis=0) - mean) / np.sqrt(np.diag(covariance) / n)
        variance = np.diag(covariance)
        covariance_se = np.sqrt((np.outer(variance, variance) + covariance**2) / n)
        covariance_error = np.abs(np.cov(own.T) - covariance) / covariance_se
        assert mean_error.max() < 5 and covariance_error.max() < 5, (k, mean_error.max(), covariance_error.max())


def test_predict_proba_and_primitive_bounds_equal_scipy(bunny_res4):
    """Responsibilities and per-primitive bounds of points and triangles against scipy's densities and the
    triangles' vertex formula (independent of the moment table): 1e-9. Scoring without the triangles' trace term
    (tried) misses in 45% of the responsibilities."""
    gmm = GaussianMixture(6, random_state=2).fit(bunny_res4)
    vertices, faces = np.asarray(bunny_res4.vertices), np.asarray(bunny_res4.faces)
    for data, log_rho in ((vertices, component_log_densities(gmm, vertices)),
                          (bunny_res4, triangle_terms(gmm, vertices, faces))):
        log_norm = logsumexp(log_rho, axis=1)
        np.testing.assert_allclose(gmm.predict_proba(data), np.exp(log_rho - log_norm[:, None]), rtol=0, atol=1e-9)
        np.testing.assert_allclose(gmm.primitive_bounds(data), log_norm, rtol=1e-10)
        np.testing.assert_array_equal(gmm.predict(data), log_rho.argmax(axis=1))


def test_predict_proba_over_several_blocks_equals_scipy(bunny_res4):
    """5,000 points at K=150 are scored in several blocks of ``_SCORE_BLOCK_BYTES`` (873 rows each): every block's
    responsibilities must be its own points' (a mix-up of blocks fails; tried), against scipy's densities."""
    points = trimesh.sample.sample_surface(bunny_res4, 5000, seed=4)[0]
    gmm = GaussianMixture(150, max_iter=3, random_state=0).fit(points)
    assert len(points) > 5 * dgmm.mixture._SCORE_BLOCK_BYTES // (8 * 150)
    log_rho = component_log_densities(gmm, points)
    expected = np.exp(log_rho - logsumexp(log_rho, axis=1)[:, None])
    np.testing.assert_allclose(gmm.predict_proba(points), expected, rtol=0, atol=1e-9)


def test_saved_model_loads_back_bit_identical(bunny_res4, tmp_path):
    """save_model / load_model: the same parameters to the bit, the same scores, the stored description."""
    from dgmm.model_io import load_model, save_model

    gmm = GaussianMixture(7, random_state=3).fit(bunny_res4)
    save_model(tmp_path / "m.npz", gmm, {"K": 7, "input": "bunny_res4"})
    loaded, params = load_model(tmp_path / "m.npz")
    assert params == {"K": 7, "input": "bunny_res4"}
    for name in ("weights_", "means_", "covariances_"):
        assert np.array_equal(getattr(loaded, name), getattr(gmm, name)), name
    np.testing.assert_allclose(loaded.precisions_cholesky_, gmm.precisions_cholesky_, rtol=1e-12)
    points = trimesh.sample.sample_surface(bunny_res4, 1000, seed=1)[0]
    np.testing.assert_allclose(loaded.score_samples(points), gmm.score_samples(points), rtol=0, atol=1e-10)
    assert loaded.score_primitives(bunny_res4) == pytest.approx(gmm.score_primitives(bunny_res4), abs=1e-10)


@pytest.mark.parametrize("covariance_type", ["full", "tied", "diag", "spherical"])
@pytest.mark.parametrize("d", [1, 2, 8])
def test_a_saved_model_of_any_type_and_dimension_scores_as_scikit_learns(tmp_path, covariance_type, d):
    """A model file keeps the covariance type and dimension: loaded, it scores as scikit-learn's GaussianMixture
    holding the same parameters (an independent density), and a file claiming another type is one line."""
    from sklearn.mixture import GaussianMixture as SklearnGaussianMixture
    from sklearn.mixture._gaussian_mixture import _compute_precision_cholesky

    from dgmm.errors import DataError
    from dgmm.model_io import load_model, save_model

    points = np.random.default_rng(d).normal(size=(300, d)) * np.arange(1, d + 1)
    gmm = GaussianMixture(3, covariance_type=covariance_type, random_state=0).fit(points)
    save_model(tmp_path / "m.npz", gmm)
    loaded, _ = load_model(tmp_path / "m.npz")
    reference = SklearnGaussianMixture(3, covariance_type=covariance_type)
    reference.weights_, reference.means_, reference.covariances_ = gmm.weights_, gmm.means_, gmm.covariances_
    reference.precisions_cholesky_ = _compute_precision_cholesky(gmm.covariances_, covariance_type)
    assert loaded.covariance_type == covariance_type
    np.testing.assert_allclose(loaded.score_samples(points), reference.score_samples(points), rtol=0, atol=1e-10)
    with np.load(tmp_path / "m.npz") as archive:
        arrays = dict(archive)
    np.savez(tmp_path / "bad.npz", **{**arrays, "covariance_type": np.array("banded")})
    with pytest.raises(DataError, match=r"bad.npz: covariance_type must be one of full, tied, diag, spherical"):
        load_model(tmp_path / "bad.npz")


def test_callback_sees_every_iteration(bunny_res4):
    seen = []
    GaussianMixture(4, max_iter=6, tol=0, random_state=0,
                    callback=lambda it, model: seen.append((it, copy.deepcopy(model.means_)))).fit(bunny_res4)
    assert [it for it, _ in seen] == list(range(1, 7))
    assert not np.array_equal(seen[0][1], seen[-1][1])


@pytest.mark.parametrize(
    "params, data, message",
    [
        (dict(n_components=0), None, "n_components=0"),
        (dict(n_components=500), None, "larger than the 453 primitives"),
        (dict(init="kmeans++"), None, "init='kmeans\\+\\+'"),
        (dict(tol=-1.0), None, "tol=-1.0"),
        (dict(tol="none"), None, "tol='none'"),
        (dict(reg_covar=float("nan")), None, "reg_covar=nan"),
        (dict(variant="paper"), None, "variant='paper'"),
        (dict(screen=0.5), None, "screen=0.5"),
        (dict(n_components=2, means_init=np.zeros((3, 3))), None, "means_init must have shape"),
        (dict(n_components=2, weights_init=[0.9, 0.9]), None, "sum to 1"),
        (dict(n_components=2, precisions_init=-np.stack([np.eye(3)] * 2)), None, "positive definite"),
        (dict(), np.full((5, 3), np.nan), "NaN"),
        (dict(), np.zeros(5), "Expected 2D array.*Reshape your data"),
        (dict(), np.zeros((5, 0)), "0 feature"),
    ],
)
def test_bad_input_is_one_line_error(bunny_res4, params, data, message):
    data = bunny_res4.vertices if data is None else data
    with pytest.raises(InputError, match=message) as info:
        GaussianMixture(**params).fit(data)
    assert "\n" not in str(info.value)


def test_singular_covariance_is_a_fit_error():
    points = np.repeat(np.eye(3), 4, axis=0)  # three distinct points, three components collapse on them
    with pytest.raises(FitError, match="reg_covar"):
        GaussianMixture(3, reg_covar=0.0, random_state=0).fit(points)


def test_unfitted_model_says_so():
    from sklearn.exceptions import NotFittedError

    for method in ("score", "score_samples", "predict", "predict_proba", "primitive_bounds"):
        with pytest.raises(InputError, match="not fitted") as info:
            getattr(GaussianMixture(2), method)(np.zeros((3, 3)))
        assert isinstance(info.value, NotFittedError)
