"""Identities the paper states, each side computed independently: dgmm's code against the formula of the cited source.

- ``cgal_triangle_moment`` (§III): the triangle covariance of eq. 10, ``cov(△) = (A Aᵀ + B Bᵀ + C Cᵀ − 3 μ μᵀ) / 12``
  (:mod:`dgmm.primitives`), "is consistent with the standard formulation in CGAL": CGAL's
  ``linear_least_squares_fitting_3`` takes a triangle's second moment about the origin as ``2 area V M Vᵀ``, ``V``
  the matrix of its vertex columns and ``M`` :data:`CGAL_TRIANGLE_MOMENT`, "a 5x multiple of the one for 3D
  tetrahedrons" (:data:`CGAL_TETRAHEDRON_MOMENT`), and its covariance as that moment over the area less ``c cᵀ``;
- ``mean_update_exact_equals_approx`` (§III): from the same responsibilities, the exact M-step's means (eq. 9) are the
  area × centroid approximation's (eq. 5), and its covariances exceed the approximation's by the
  responsibility-weighted triangle covariance (eq. 10's ``cov(△)`` term);
- ``hierarchical_gmm_update`` (§V-A): the general M-step (eqs. 12-13) on a mixture's own components (means,
  covariances, sizes its weights) is the hierarchical-GMM M-step of Vasconcelos & Lippman (1998),
  ``μ = Σ h w μ_p / Σ h w``, ``Σ = Σ h w (Σ_p + (μ_p − μ)(μ_p − μ)ᵀ) / Σ h w``, ``π = Σ h w / Σ w``, for the same
  responsibilities ``h`` (their E-step raises each component's term to the power of its virtual samples ``N w_p``,
  ours to 1: the identity is the M-step's);
- ``points_equal_sklearn`` (§VII, "empirical equivalence with traditional techniques"): EM on points (zero
  covariance, unit size) is scikit-learn's ``GaussianMixture`` from the same start, iteration for iteration;
- ``triangle_bound_monte_carlo`` (§III, eq. 8): the triangle bound as printed, in the vertices ``A, B, C``, is the
  area-weighted integral ``Σ_j α_j Σ_i η_ij E_{x~△j}[log λ_i N(x; μ_i, Σ_i)]`` that it closes, here integrated by
  sampling each triangle uniformly;
- ``general_bound_monte_carlo`` (§V-A, eq. 11): the general bound on Gaussian primitives, read with
  ``tr(Σ_i⁻¹ Σ_p)`` where the printed bracket subtracts the matrix ``Σ_p``, is the same integral under each
  primitive's Gaussian; its detail gives the nearest literal reading, ``tr(Σ_p)``, beside it.

dgmm's M-step is not public: one EM iteration of :class:`dgmm.GaussianMixture` from given parameters
(``max_iter=1, tol=None``) is one E-step under them and one M-step. The reference sides take their responsibilities
from :func:`reference_responsibilities`, the textbook E-step ``log h_ip = log π_i + log N(μ_p; μ_i, Σ_i) −
tr(Σ_i⁻¹ Σ_p) / 2`` written with scipy's density. Where the exact and approximate M-steps must see the same
responsibilities, every component starts with the same covariance: the trace term is then the same for every
component and leaves the softmax unchanged.

A row (:data:`COLUMNS`) compares several quantities; ``max_error`` and ``scale`` are those of the quantity with the
largest relative difference (``scale`` the largest magnitude of its reference side), and ``detail`` lists every
quantity's. ``cases`` counts what was compared (triangles, or components). ``noise`` is 0 for an identity, which holds
to rounding, and the standard error of the Monte Carlo side for an integral, which holds within its noise.
"""
import warnings

import numpy as np
from scipy.stats import multivariate_normal
from sklearn.exceptions import ConvergenceWarning
from sklearn.mixture import GaussianMixture as SklearnGaussianMixture

from dgmm.mixture import GaussianMixture
from dgmm.primitives import Primitives

COLUMNS = ("identity", "cases", "max_error", "scale", "detail", "noise")
CGAL_TRIANGLE_MOMENT = np.array([[1 / 12, 1 / 24, 1 / 24],
                                 [1 / 24, 1 / 12, 1 / 24],
                                 [1 / 24, 1 / 24, 1 / 12]])
"""CGAL's canonical triangle moment (``assemble_covariance_matrix_3`` for ``Triangle_3``)."""
CGAL_TETRAHEDRON_MOMENT = np.array([[1 / 60, 1 / 120, 1 / 120],
                                    [1 / 120, 1 / 60, 1 / 120],
                                    [1 / 120, 1 / 120, 1 / 60]])
"""CGAL's canonical tetrahedron moment (``Tetrahedron_3``, on the edges from the first vertex, times 6 volume): the
upper 3x3 block of the 4x4 ``E[b bᵀ] / 6`` of a uniform point's barycentric coordinates in a tetrahedron."""


def _relative(error, scale):
    return error / scale if scale > 0 else (0.0 if error == 0 else np.inf)


def comparison_row(identity, cases, quantities):
    """A table row from ``quantities``: name -> (ours, reference), arrays of one shape (module docstring)."""
    found = {}
    for name, (ours, reference) in quantities.items():
        reference = np.asarray(reference, dtype=float)
        found[name] = (float(np.max(np.abs(np.asarray(ours, dtype=float) - reference))),
                       float(np.max(np.abs(reference))))
    worst = max(found, key=lambda name: _relative(*found[name]))
    return {"identity": identity, "cases": cases, "max_error": found[worst][0], "scale": found[worst][1],
            "detail": "; ".join(f"{name} {error:.1e} of {scale:.1e}" for name, (error, scale) in found.items()),
            "noise": 0.0}


# ---------------------------------------------------------------------------------------------------------
# References, each written from its source
# ---------------------------------------------------------------------------------------------------------

def triangle_areas(triangles):
    """Half the norm of the cross product of two edges, for (n, 3, 3) vertex rows."""
    return 0.5 * np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]), axis=1)


def cgal_moments(triangles, moment=CGAL_TRIANGLE_MOMENT):
    """CGAL's per-triangle quantities: area ``sqrt(squared_area)``, second moment about the origin
    ``2 area V M Vᵀ`` and covariance ``moment / area − c cᵀ`` (``c`` the centroid), for (n, 3, 3) vertex rows."""
    areas = triangle_areas(triangles)
    columns = np.swapaxes(triangles, 1, 2)  # V: the vertices as columns
    second = 2 * areas[:, None, None] * columns @ moment @ triangles
    centroids = triangles.mean(axis=1)
    return areas, second, second / areas[:, None, None] - centroids[:, :, None] * centroids[:, None, :]


def triangle_covariances(triangles):
    """Eq. 10's ``cov(△) = (A Aᵀ + B Bᵀ + C Cᵀ − 3 μ μᵀ) / 12`` of (n, 3, 3) vertex rows, as the paper writes it."""
    centroids = triangles.mean(axis=1)
    return (np.einsum("nvi,nvj->nij", triangles, triangles)
            - 3 * centroids[:, :, None] * centroids[:, None, :]) / 12


def _log_densities(points, weights, means, covariances):
    """``log λ_i + log N(x; μ_i, Σ_i)`` with scipy's density, shape (n_points, K) (scipy squeezes one point)."""
    return np.stack([np.log(weight) + np.atleast_1d(multivariate_normal.logpdf(points, mean, covariance))
                     for weight, mean, covariance in zip(weights, means, covariances)], axis=1)


def reference_responsibilities(weights, means, covariances, prim_means, prim_covariances):
    """Textbook E-step responsibilities ``h`` (n_prims, K) with scipy's log-density and the trace term."""
    traces = np.stack([np.einsum("ij,pji->p", np.linalg.inv(covariance), prim_covariances)
                       for covariance in covariances], axis=1)
    log_h = _log_densities(prim_means, weights, means, covariances) - 0.5 * traces
    log_h -= log_h.max(axis=1, keepdims=True)
    h = np.exp(log_h)
    return h / h.sum(axis=1, keepdims=True)


def weighted_update(h, sizes, prim_means, prim_covariances):
    """The M-step of Vasconcelos & Lippman's hierarchical GMM (eqs. 12-13 in the paper's notation): weights
    ``Σ_p h w / Σ w``, means and covariances ``Σ_p h w (Σ_p + (μ_p − μ)(μ_p − μ)ᵀ) / Σ_p h w``."""
    w = h * sizes[:, None]  # (n_prims, K)
    mass = w.sum(axis=0)
    means = w.T @ prim_means / mass[:, None]
    offsets = prim_means[:, None, :] - means[None]  # (n_prims, K, 3)
    covariances = (np.einsum("pk,pki,pkj->kij", w, offsets, offsets)
                   + np.einsum("pk,pij->kij", w, prim_covariances)) / mass[:, None, None]
    return mass / sizes.sum(), means, covariances


# ---------------------------------------------------------------------------------------------------------
# The identities
# ---------------------------------------------------------------------------------------------------------

def _mesh_triangles(vertices, faces):
    """The mesh as (n, 3, 3) vertex rows, faces of zero area left out as :meth:`Primitives.from_mesh` does."""
    triangles = np.asarray(vertices, dtype=float)[np.asarray(faces)]
    return triangles[triangle_areas(triangles) > 0]


def cgal_triangle_moment(vertices, faces, random_triangles, rng, moment=CGAL_TRIANGLE_MOMENT):
    """dgmm's triangle moments against CGAL's on a mesh's triangles and on ``random_triangles`` random ones.

    Compared per triangle: the covariance (dgmm's against CGAL's moment over the area less ``c cᵀ``), the
    area-weighted second moment about the origin (``area (Σ + μ μᵀ)`` against ``2 area V M Vᵀ``), and ``moment``
    against 5 times the tetrahedron's.
    """
    sets = {"mesh": _mesh_triangles(vertices, faces), "random": rng.uniform(-1.0, 1.0, (random_triangles, 3, 3))}
    quantities = {}
    for name, triangles in sets.items():
        ours = Primitives.from_mesh(triangles.reshape(-1, 3), np.arange(3 * len(triangles)).reshape(-1, 3))
        areas, second, covariances = cgal_moments(triangles, moment)
        quantities[f"{name} covariances"] = (ours.covariances, covariances)
        quantities[f"{name} second moments"] = (ours.weights[:, None, None] * ours.second_moments, second)
    quantities["moment matrix"] = (moment, 5 * CGAL_TETRAHEDRON_MOMENT)
    return comparison_row("cgal_triangle_moment", sum(map(len, sets.values())), quantities)


def cgal_five_times_tetrahedron(moment=CGAL_TRIANGLE_MOMENT):
    """CGAL's triangle moment matrix against 5 times the tetrahedron's, and against its value from
    the barycentric coordinates ``b`` of a uniform point on the triangle: ``E[b bᵀ] / 2 = (I + 1 1ᵀ) / 24``."""
    return comparison_row("cgal_five_times_tetrahedron", 1, {
        "5 x tetrahedron": (moment, 5 * CGAL_TETRAHEDRON_MOMENT),
        "barycentric": (moment, (np.eye(3) + np.ones((3, 3))) / 24)})


def _one_iteration(prims, weights, means, covariances):
    """dgmm's textbook EM iteration from the given parameters (its E-step, then its M-step; no floor)."""
    return GaussianMixture(len(weights), max_iter=1, tol=None, reg_covar=0.0, weights_init=weights, means_init=means,
                           precisions_init=np.linalg.inv(covariances)).fit(prims)


def _start(rng, means, n_components, spread):
    """Random weights, components at ``n_components`` of ``means`` and ``spread`` (K, 3, 3) covariances."""
    return (rng.dirichlet(np.ones(n_components)), means[rng.choice(len(means), n_components, replace=False)], spread)


def mean_update_exact_equals_approx(vertices, faces, n_components, rng):
    """One M-step on a mesh's exact triangles and on its area × centroid approximation from the same
    responsibilities (every component starts with one shared covariance), against the formulas (eqs. 5, 9, 10).

    The reference responsibilities are those of the centroids (zero covariance): under a shared covariance the
    triangles' trace term is the same for every component, so the exact E-step's responsibilities are the same.
    """
    triangles = _mesh_triangles(vertices, faces)
    exact = Primitives.from_mesh(vertices, faces)
    centroids, areas = triangles.mean(axis=1), triangle_areas(triangles)
    shared = np.cov(centroids.T) / n_components ** (2 / 3)  # about one component's share of the surface
    start = _start(rng, centroids, n_components, np.tile(shared, (n_components, 1, 1)))
    fits = {name: _one_iteration(prims, *start) for name, prims in (("exact", exact),
                                                                    ("approx", exact.without_covariances()))}
    no_extent = np.zeros((len(centroids), 3, 3))
    h = reference_responsibilities(*start, centroids, no_extent)
    _, means, _ = weighted_update(h, areas, centroids, no_extent)  # eq. 5's update: centroids weighted by area
    w = h * areas[:, None]
    term = np.einsum("pk,pij->kij", w, triangle_covariances(triangles)) / w.sum(axis=0)[:, None, None]
    return comparison_row("mean_update_exact_equals_approx", n_components, {
        "exact means": (fits["exact"].means_, means), "approx means": (fits["approx"].means_, means),
        "exact - approx covariances": (fits["exact"].covariances_ - fits["approx"].covariances_, term)})


def hierarchical_gmm_update(mixture, n_components, rng):
    """One M-step on the components of ``mixture`` (sizes its weights) against the hierarchical-GMM M-step."""
    child = Primitives.from_gaussians(mixture.means_, mixture.covariances_, mixture.weights_)
    spread = np.cov(child.means.T) / n_components ** (2 / 3)
    start = _start(rng, child.means, n_components, spread * rng.uniform(0.5, 2.0, n_components)[:, None, None])
    fitted = _one_iteration(child, *start)
    h = reference_responsibilities(*start, child.means, child.covariances)
    weights, means, covariances = weighted_update(h, child.weights, child.means, child.covariances)
    return comparison_row("hierarchical_gmm_update", n_components, {
        "weights": (fitted.weights_, weights), "means": (fitted.means_, means),
        "covariances": (fitted.covariances_, covariances)})


def sklearn_fit(points, start, n_iter, reg_covar):
    """scikit-learn's ``GaussianMixture`` (full covariances) from ``start``: exactly ``n_iter`` EM iterations."""
    weights, means, covariances = start
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)  # tol=0: it runs every iteration and says so
        return SklearnGaussianMixture(len(weights), max_iter=n_iter, tol=0, reg_covar=reg_covar, weights_init=weights,
                                      means_init=means, precisions_init=np.linalg.inv(covariances)).fit(points)


def points_equal_sklearn(points, n_components, n_iter, reg_covar, rng):
    """dgmm's EM on points against scikit-learn's, ``n_iter`` iterations from one random start: the final
    parameters and the mean log-likelihood of the points."""
    points = np.asarray(points, dtype=float)
    shared = np.cov(points.T) / n_components ** (2 / 3)
    start = _start(rng, points, n_components, np.tile(shared, (n_components, 1, 1)))
    reference = sklearn_fit(points, start, n_iter, reg_covar)
    ours = GaussianMixture(n_components, max_iter=n_iter, tol=0, reg_covar=reg_covar, weights_init=start[0],
                           means_init=start[1], precisions_init=np.linalg.inv(start[2])).fit(points)
    return comparison_row("points_equal_sklearn", n_components, {
        "means": (ours.means_, reference.means_), "mean log-likelihood": (ours.score(points), reference.score(points)),
        "covariances": (ours.covariances_, reference.covariances_), "weights": (ours.weights_, reference.weights_)})


def _monte_carlo_bound(samples, h, sizes, weights, means, covariances):
    """Size-weighted mean over primitives of ``Σ_i h_pi (log λ_i + log N(x; μ_i, Σ_i))`` averaged over each
    primitive's samples (n_prims, m, 3), and its standard error (the samples' spread within each primitive)."""
    n_prims, m, dim = samples.shape
    share = sizes / sizes.sum()
    values = np.einsum("pmk,pk->pm", _log_densities(samples.reshape(-1, dim), weights, means, covariances)
                       .reshape(n_prims, m, -1), h)
    return float(share @ values.mean(axis=1)), float(np.sqrt(share ** 2 @ values.var(axis=1, ddof=1) / m))


def _integral_row(identity, cases, closed, sampled, error, detail):
    """A row comparing a closed form with its Monte Carlo integral (``noise`` the integral's standard error)."""
    return {"identity": identity, "cases": cases, "max_error": abs(closed - sampled), "scale": abs(sampled),
            "detail": detail, "noise": error}


def _bracket(prim_means, weights, means, covariances):
    """The bound's bracket at each primitive's mean as the paper prints it, ``2 log λ_i − k log 2π − log det Σ_i −
    (μ_p − μ_i)ᵀ Σ_i⁻¹ (μ_p − μ_i)``, before its extent term (n_prims, K)."""
    offsets = prim_means[:, None, :] - means[None]
    quadratic = np.einsum("pki,kij,pkj->pk", offsets, np.linalg.inv(covariances), offsets)
    return (2 * np.log(weights) - means.shape[1] * np.log(2 * np.pi) - np.linalg.slogdet(covariances)[1]
            - quadratic)


def triangle_bound_monte_carlo(vertices, faces, mixture, samples, rng):
    """Eq. 8 as printed (per unit area) for ``mixture`` and its textbook responsibilities on a mesh's triangles,
    against ``samples`` uniform points a triangle."""
    triangles = _mesh_triangles(vertices, faces)
    centroids, areas = triangles.mean(axis=1), triangle_areas(triangles)
    weights, means, covariances = mixture.weights_, mixture.means_, mixture.covariances_
    h = reference_responsibilities(weights, means, covariances, centroids, triangle_covariances(triangles))
    precisions = np.linalg.inv(covariances)
    vertex_terms = (np.einsum("nvi,kij,nvj->nk", triangles, precisions, triangles)
                    - 3 * np.einsum("ni,kij,nj->nk", centroids, precisions, centroids))
    bracket = _bracket(centroids, weights, means, covariances) - vertex_terms / 12
    closed = float(0.5 * np.sum(h * areas[:, None] * bracket) / areas.sum())
    u = rng.random((len(triangles), samples, 2))
    u = np.where(u.sum(axis=2, keepdims=True) > 1, 1 - u, u)  # reflected into the triangle: uniform over it
    edges = triangles[:, 1:] - triangles[:, :1]  # (n, 2, 3)
    points = triangles[:, None, 0] + np.einsum("nmb,nbi->nmi", u, edges)
    sampled, error = _monte_carlo_bound(points, h, areas, weights, means, covariances)
    return _integral_row("triangle_bound_monte_carlo", len(triangles), closed, sampled, error,
                         f"eq. 8 {closed:.6f}, Monte Carlo {sampled:.6f} ± {error:.6f} nat ({samples} uniform points "
                         f"a triangle)")


def general_bound_monte_carlo(mixture, n_components, samples, rng):
    """Eq. 11 (per unit size) on the components of ``mixture`` as Gaussian primitives, read with ``tr(Σ_i⁻¹ Σ_p)``,
    against ``samples`` draws from each primitive; the detail adds the printed ``Σ_p`` read as ``tr(Σ_p)``."""
    child = Primitives.from_gaussians(mixture.means_, mixture.covariances_, mixture.weights_)
    spread = np.cov(child.means.T) / n_components ** (2 / 3)
    weights, means, covariances = _start(rng, child.means, n_components,
                                         spread * rng.uniform(0.5, 2.0, n_components)[:, None, None])
    h = reference_responsibilities(weights, means, covariances, child.means, child.covariances)
    common = _bracket(child.means, weights, means, covariances)

    def bound(extent):  # eq. 11 with the bracket's last term read as ``extent`` (n_prims, K)
        return float(0.5 * np.sum(h * child.weights[:, None] * (common - extent)) / child.weights.sum())

    closed = bound(np.einsum("kij,pji->pk", np.linalg.inv(covariances), child.covariances))
    printed = bound(np.trace(child.covariances, axis1=1, axis2=2)[:, None])
    draws = np.stack([rng.multivariate_normal(mean, covariance, samples)
                      for mean, covariance in zip(child.means, child.covariances)])
    sampled, error = _monte_carlo_bound(draws, h, child.weights, weights, means, covariances)
    return _integral_row("general_bound_monte_carlo", len(child.means), closed, sampled, error,
                         f"eq. 11 read with tr(Σᵢ⁻¹Σ_p) {closed:.6f}, as printed (−Σ_p read as −tr Σ_p) {printed:.6f}, "
                         f"Monte Carlo {sampled:.6f} ± {error:.6f} nat ({samples} draws a primitive)")


def identity_rows(vertices, faces, mixture, *, random_triangles, n_components, n_iter, reg_covar, samples, seed):
    """Every identity of the module docstring on one mesh and a mixture fitted to it.

    Parameters
    ----------
    vertices : ndarray of shape (n_vertices, 3)
    faces : ndarray of shape (n_faces, 3)
    mixture : GaussianMixture
        Fitted to the mesh: the hierarchical update's primitives.
    random_triangles : int
        Random triangles beside the mesh's in the CGAL comparison.
    n_components : int
        K of the M-steps and of the scikit-learn fit (of the mesh's vertices).
    n_iter : int
        EM iterations of the scikit-learn comparison.
    reg_covar : float
        Covariance floor of the scikit-learn comparison (both sides).
    samples : int
        Monte Carlo points a primitive of the two integrals.
    seed : int
        Seeds every random start and the random triangles.

    Returns
    -------
    list of dict
        With the keys of :data:`COLUMNS`.
    """
    rng = np.random.default_rng(seed)
    return [cgal_triangle_moment(vertices, faces, random_triangles, rng), cgal_five_times_tetrahedron(),
            mean_update_exact_equals_approx(vertices, faces, n_components, rng),
            hierarchical_gmm_update(mixture, n_components, rng),
            points_equal_sklearn(vertices, n_components, n_iter, reg_covar, rng),
            triangle_bound_monte_carlo(vertices, faces, mixture, samples, rng),
            general_bound_monte_carlo(mixture, n_components, samples, rng)]
