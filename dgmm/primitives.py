"""Geometric primitives as the moments EM needs: a mean, a covariance and a size each.

A primitive ``p`` enters Gaussian-mixture EM only through its size ``alpha_p`` (area of a triangle, 1 for a
point), its mean ``mu_p`` and its covariance ``Sigma_p``, the second central moment of the uniform
distribution over it (paper §III and "Generalization to other primitives"). Arrays are rows of items:
``means (n_prims, d)``, ``covariances (n_prims, d, d)``, ``weights (n_prims,)``, in any dimension ``d >= 1``
(triangles: ``d >= 2``; the paper's data, pixel rectangles and registration are 3-D).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dgmm.errors import InputError

MAX_COORDINATE = 1e152
"""Largest coordinate magnitude accepted: EM, scores and triangle moments square coordinates, and float64 stops
at 1.8e308 (so ``dgmm.GaussianMixture().fit(points * 1e200)`` is an InputError, not a mixture of NaN)."""


def _check_finite(name, array):
    if not np.all(np.isfinite(array)):
        raise InputError(f"{name} contains NaN or infinite values")


def _as_points(name, array):
    """Return ``array`` as a float64 array of shape (n, d) with n, d >= 1, or raise InputError naming it."""
    if np.iscomplexobj(array):
        raise InputError(f"{name} is complex: complex data not supported")
    try:
        points = np.asarray(array, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} is not a numeric array: {exc}") from None
    if points.ndim != 2 or points.shape[1] == 0:
        raise InputError(f"{name} must have shape (n, d) with d >= 1, got {points.shape}")
    if len(points) == 0:
        raise InputError(f"{name} is empty")
    _check_finite(name, points)
    peak = np.abs(points).max()
    if peak > MAX_COORDINATE:
        raise InputError(f"{name} has coordinates up to {peak:.3g}, beyond the {MAX_COORDINATE:.0e} that squared "
                         f"units allow in float64: rescale the input (for example to metres)")
    return points


def triangle_moments(triangles):
    """Centroid, area and covariance of the uniform distribution over each triangle.

    Parameters
    ----------
    triangles : ndarray of shape (n_triangles, 3, d)
        Vertices ``A, B, C`` of each triangle, one per row, in any dimension ``d >= 2``.

    Returns
    -------
    centroids : ndarray of shape (n_triangles, d)
    areas : ndarray of shape (n_triangles,)
        ``|e1 ∧ e2| / 2`` of the edges ``e1 = B − A``, ``e2 = C − A`` (in 3-D the norm of their cross product; in
        any dimension ``|e1 ∧ e2|² = Σ_{i<j} (e1_i e2_j − e1_j e2_i)²``, Lagrange's identity).
    covariances : ndarray of shape (n_triangles, d, d)
        ``(A Aᵀ + B Bᵀ + C Cᵀ − 3 m mᵀ) / 12`` with ``m`` the centroid (paper eq. 10, ``cov(△)``): the triangle's
        affine map of the standard simplex, so the formula holds in any dimension.
    """
    centroids = triangles.mean(axis=1)
    edges = triangles[:, 1:] - triangles[:, :1]
    # Each triangle's edges scaled by a power of two near their length (exact), so that the squares in the norm
    # neither underflow (edges of 1e-160) nor overflow, then the area scaled back (exact again).
    _, exponents = np.frexp(np.abs(edges).max(axis=(1, 2)))
    edges = np.ldexp(edges, -exponents[:, None, None])
    if triangles.shape[2] == 3:
        wedge = np.linalg.norm(np.cross(edges[:, 0], edges[:, 1]), axis=1)
    else:  # the bivector e1 ∧ e2 as the antisymmetric matrix e1 e2ᵀ − e2 e1ᵀ, whose entries hold each pair twice
        outer = edges[:, 0, :, None] * edges[:, 1, None, :]
        wedge = np.sqrt(0.5 * np.sum((outer - np.swapaxes(outer, 1, 2)) ** 2, axis=(1, 2)))
    areas = np.ldexp(0.5 * wedge, 2 * exponents)
    # Centre on the centroid first: the same formula, without cancellation between large terms.
    local = triangles - centroids[:, None, :]
    covariances = np.einsum("tvi,tvj->tij", local, local) / 12.0
    return centroids, areas, covariances


def _mesh_moments(vertices, faces, chunk=1 << 16):
    """:func:`triangle_moments` of every face, ``chunk`` faces at a time (so that its (n, 3, 3) temporaries
    exist for one chunk only: a mesh of millions of triangles needs no more than its moments)."""
    n, d = len(faces), vertices.shape[1]
    centroids, areas, covariances = np.empty((n, d)), np.empty(n), np.empty((n, d, d))
    for start in range(0, n, chunk):
        rows = slice(start, start + chunk)
        centroids[rows], areas[rows], covariances[rows] = triangle_moments(vertices[faces[rows]])
    return centroids, areas, covariances


@dataclass(frozen=True)
class Primitives:
    """An immutable set of primitives given by their moments.

    Attributes
    ----------
    means : ndarray of shape (n_prims, d)
        Any dimension ``d >= 1``.
    covariances : ndarray of shape (n_prims, d, d)
        Zero for points.
    weights : ndarray of shape (n_prims,)
        Size of each primitive (area, or 1 for a point); non-negative, not all zero.
    """

    means: np.ndarray
    covariances: np.ndarray
    weights: np.ndarray

    def __post_init__(self):
        means = _as_points("primitive means", self.means)
        n, d = means.shape
        covariances = np.asarray(self.covariances, dtype=np.float64)
        weights = np.asarray(self.weights, dtype=np.float64)
        if covariances.shape != (n, d, d):
            raise InputError(f"primitive covariances must have shape ({n}, {d}, {d}), got {covariances.shape}")
        if weights.shape != (n,):
            raise InputError(f"primitive weights must have shape ({n},), got {weights.shape}")
        _check_finite("primitive covariances", covariances)
        _check_finite("primitive weights", weights)
        if np.any(weights < 0):
            raise InputError("primitive weights must be non-negative")
        if not np.any(weights > 0):
            raise InputError("primitive weights are all zero")
        for name, value in (("means", means), ("covariances", covariances), ("weights", weights)):
            value = value.copy()
            value.flags.writeable = False
            object.__setattr__(self, name, value)

    def __len__(self):
        return len(self.weights)

    @property
    def dimension(self):
        """The dimension ``d`` of the space the primitives lie in."""
        return self.means.shape[1]

    @property
    def second_moments(self):
        """E[x xᵀ] = μ μᵀ + Σ of each primitive, shape (n_prims, d, d)."""
        return self.covariances + self.means[:, :, None] * self.means[:, None, :]

    @classmethod
    def from_points(cls, points, weights=None):
        """Points as primitives: zero covariance, size 1 (or the given weights)."""
        points = _as_points("points", points)
        weights = np.ones(len(points)) if weights is None else weights
        return cls(points, np.zeros((len(points), points.shape[1], points.shape[1])), weights)

    @classmethod
    def from_gaussians(cls, means, covariances, weights):
        """Gaussians (for example another mixture's components) as primitives."""
        return cls(means, covariances, weights)

    @classmethod
    def from_mesh(cls, mesh_or_vertices, faces=None):
        """Triangles of a mesh with their exact moments; zero-area faces are dropped.

        Parameters
        ----------
        mesh_or_vertices : trimesh.Trimesh or array-like of shape (n_vertices, d), d >= 2
        faces : array-like of shape (n_faces, 3), optional
            Vertex indices; required when vertices are given.
        """
        if faces is None:
            if not hasattr(mesh_or_vertices, "faces"):
                raise InputError("from_mesh needs a trimesh.Trimesh, or vertices and faces")
            vertices, faces = mesh_or_vertices.vertices, mesh_or_vertices.faces
        else:
            vertices = mesh_or_vertices
        vertices = _as_points("mesh vertices", vertices)
        if vertices.shape[1] < 2:
            raise InputError(f"mesh vertices must have shape (n, d) with d >= 2 for triangles, got {vertices.shape}")
        faces = np.asarray(faces)
        if faces.ndim != 2 or faces.shape[1] != 3:
            raise InputError(f"mesh faces must be triangles of shape (n, 3), got {faces.shape}")
        if len(faces) == 0:
            raise InputError("mesh has no faces")
        if not np.issubdtype(faces.dtype, np.integer):
            raise InputError(f"mesh faces must be integer vertex indices, got {faces.dtype}")
        if faces.min() < 0 or faces.max() >= len(vertices):
            raise InputError(f"mesh faces index vertices outside 0..{len(vertices) - 1}")
        centroids, areas, covariances = _mesh_moments(vertices, faces)
        keep = areas > 0
        if not np.any(keep):
            raise InputError("mesh has no face of positive area")
        if not np.all(keep):
            centroids, areas, covariances = centroids[keep], areas[keep], covariances[keep]
        return cls(centroids, covariances, areas)

    def without_covariances(self):
        """The paper's area × centroid approximation (eq. 5): same means and sizes, zero covariance."""
        return Primitives(self.means, np.zeros_like(self.covariances), self.weights)

    def transformed(self, rotation, translation):
        """Primitives moved by ``x ↦ R x + t``: means rotate and shift, covariances become R Σ Rᵀ."""
        rotation = np.asarray(rotation, dtype=np.float64)
        translation = np.asarray(translation, dtype=np.float64)
        d = self.dimension
        if rotation.shape != (d, d) or translation.shape != (d,):
            raise InputError(f"transformed needs a ({d}, {d}) rotation and a ({d},) translation")
        means = self.means @ rotation.T + translation
        covariances = rotation @ self.covariances @ rotation.T
        return Primitives(means, covariances, self.weights)

    @staticmethod
    def concat(*parts):
        """One set holding every primitive of ``parts`` (sizes kept as they are)."""
        if not parts:
            raise InputError("concat needs at least one Primitives")
        return Primitives(
            np.concatenate([p.means for p in parts]),
            np.concatenate([p.covariances for p in parts]),
            np.concatenate([p.weights for p in parts]),
        )


def as_primitives(data):
    """Primitives from an (n, d) array (points), a ``Primitives`` or a ``trimesh.Trimesh`` (triangles)."""
    if isinstance(data, Primitives):
        return data
    if hasattr(data, "faces") and hasattr(data, "vertices"):
        return Primitives.from_mesh(data)
    return Primitives.from_points(data)
