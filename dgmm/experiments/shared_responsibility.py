"""How much the triangle bound loses by sharing one responsibility across each triangle (Fig 2's gap).

The triangle expression (eq. 11) scores a triangle ``p`` by ``logsumexp_i(log lambda_i + E_{x~p}[log N_i(x)])``:
one responsibility ``eta_ip`` for the whole triangle. Dense points sampled on the surface instead score
``E_{x~p}[logsumexp_i(log lambda_i + log N_i(x))]``, a responsibility per point. By Jensen's inequality
(logsumexp is convex) the second is never lower; their difference is the price of the shared responsibility.
:func:`per_point_likelihoods` measures the second on the same triangles with a fixed quadrature, so that
``per-point − triangle`` is that price and ``all points − per-point`` is what remains of Fig 2's gap.
"""
import numpy as np

from dgmm.experiments.sweep import expected_log_likelihood
from dgmm.primitives import Primitives

PER_POINT_MEASURE = "triangle with per-point responsibilities"
"""The ``measure`` of this expression's row in ``fig2.csv``."""

SUBDIVISIONS = 8
"""Each triangle edge is cut into this many segments: 64 quadrature points per triangle (the bound moves by
0.001 nat from 8 to 32 segments in Fig 2's setting)."""


def triangle_points(vertices, faces, n=SUBDIVISIONS):
    """Centroids of the ``n²`` congruent sub-triangles of each face (midpoint-grid subdivision).

    Each point stands for ``1/n²`` of its face's area. Their mean is the face's centroid and their covariance is
    ``(1 − 1/n²)`` times the face's (the uniform distribution over it): the within-sub-triangle part is missing.

    Parameters
    ----------
    vertices : ndarray of shape (n_vertices, 3)
    faces : ndarray of shape (n_faces, 3)
    n : int

    Returns
    -------
    ndarray of shape (n_faces, n * n, 3)
    """
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    up = (i + j <= n - 1).ravel()
    down = (i + j <= n - 2).ravel()
    # Barycentric (u, v) of the upward sub-triangles' centroids, then the downward ones'.
    u = np.concatenate([(i.ravel()[up] + 1 / 3) / n, (i.ravel()[down] + 2 / 3) / n])
    v = np.concatenate([(j.ravel()[up] + 1 / 3) / n, (j.ravel()[down] + 2 / 3) / n])
    a, b, c = (np.asarray(vertices, dtype=np.float64)[np.asarray(faces)[:, k]] for k in range(3))
    return a[:, None] + u[None, :, None] * (b - a)[:, None] + v[None, :, None] * (c - a)[:, None]


def per_point_likelihoods(model, vertices, faces, n=SUBDIVISIONS):
    """Fig 2's two expressions of a mesh with a responsibility per point within each triangle.

    Returns
    -------
    bound : float
        Area-weighted mean over faces of the mean over their quadrature points of ``log p(x)``.
    expected : float
        The same of ``Σ_i eta_i(x) log rho_i(x)`` (the paper's plotted quantity).
    """
    corners = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)]
    areas = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    kept = areas > 0  # as in Primitives.from_mesh, zero-area faces are dropped
    points = triangle_points(vertices, np.asarray(faces)[kept], n)
    prims = Primitives.from_points(points.reshape(-1, 3), np.repeat(areas[kept], n * n))
    return model.score_primitives(prims), expected_log_likelihood(model, prims)
