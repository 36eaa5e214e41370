"""The Gaussian log-density as a linear map of quadratic features, the one form EM and the registration costs use.

``log π + log N(x; μ, Λ⁻¹) = −½ xᵀΛx + μᵀΛx − ½ μᵀΛμ + log π − d/2 log 2π + ½ log det Λ`` is the product of the
quadratic features of ``x`` (:func:`quadratic_features`: ``x xᵀ``, ``x``, 1) with the component's coefficients
(:func:`log_density_coefficients`), so that every (point, component) pair of a mixture is one matrix product. With a
primitive's second moment ``E_p[x xᵀ] = μ_p μ_pᵀ + Σ_p`` in place of ``x xᵀ`` the same product is its expected
log-density (EM's E-step, :mod:`dgmm.mixture`).

A symmetric d×d matrix is packed as its ``d(d+1)/2`` distinct entries, the diagonal first, then the off-diagonals row
by row (3-D: xx, yy, zz, xy, xz, yz; :class:`Layout`). Features hold the off-diagonals doubled, so that ``<Λ, x xᵀ>``
is the packed ``Λ`` dotted with them. Columns, 11 in 3-D: the packed second moment, ``x``, a one, and a constant
column that carries each component's log-normaliser.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

SCREEN = 50.0
"""Nats below a row's largest term beyond which terms are left out: ``e^-50 ≈ 2e-22``, so even 10⁵ of them add under
``2e-17`` to a sum of at least 1, below half its last place (``1.1e-16``). EM's screened E-step (``GaussianMixture(
screen=SCREEN)``, every odometry frame's fit), the P2D kernels, D2D's derivatives and scoring
leave out the same pairs."""

_LOG_2PI = np.log(2.0 * np.pi)


@dataclass(frozen=True)
class Layout:
    """Columns of the quadratic features and log-density coefficients in dimension ``d``.

    ``rows, cols``: the packed entries of a symmetric d×d matrix (module docstring); ``n_second = d(d+1)/2`` columns
    of them, then ``d`` of ``x`` (``mean``), a one (``one``): ``n_quadratic`` columns of features; the coefficients'
    log-normaliser makes ``n_columns = n_quadratic + 1``. ``full``: the index into the packed entries of each entry
    of the d×d matrix.
    """

    d: int
    rows: np.ndarray
    cols: np.ndarray
    full: np.ndarray

    @property
    def n_second(self):
        return len(self.rows)

    @property
    def mean(self):
        return slice(self.n_second, self.n_second + self.d)

    @property
    def one(self):
        return self.n_second + self.d

    @property
    def n_quadratic(self):
        return self.n_second + self.d + 1

    @property
    def n_columns(self):
        return self.n_second + self.d + 2


@functools.lru_cache(maxsize=None)
def layout(d):
    """The :class:`Layout` of dimension ``d``."""
    upper_rows, upper_cols = np.triu_indices(d, 1)
    diagonal = np.arange(d)
    rows, cols = np.concatenate([diagonal, upper_rows]), np.concatenate([diagonal, upper_cols])
    full = np.empty((d, d), dtype=np.intp)
    full[rows, cols] = full[cols, rows] = np.arange(len(rows))
    return Layout(d, rows, cols, full)


def unpack(packed):
    """Symmetric matrices ``(..., d, d)`` from their packed entries ``(..., d(d+1)/2)`` (off-diagonals not
    doubled)."""
    d = int(round((np.sqrt(8 * packed.shape[-1] + 1) - 1) / 2))
    return packed[..., layout(d).full]


def quadratic_features(points, out=None):
    """Features ``(n, n_quadratic)`` of ``points`` ``(n, d)``: ``x xᵀ`` packed (off-diagonals doubled), ``x``, 1
    (3-D: ``x², y², z², 2xy, 2xz, 2yz, x, y, z, 1``); written into ``out`` when given.

    ``features @ log_density_coefficients(...)[:, :n_quadratic]ᵀ`` is every point's log-density under every
    component but the log-normalisers.
    """
    shape = layout(points.shape[1])
    features = np.empty((len(points), shape.n_quadratic)) if out is None else out
    np.multiply(points[:, shape.rows], points[:, shape.cols], out=features[:, :shape.n_second])
    features[:, shape.d:shape.n_second] *= 2.0
    features[:, shape.mean] = points
    features[:, shape.one] = 1.0
    return features


def log_density_coefficients(weights, means, precisions_cholesky, unit=1.0):
    """Coefficients ``(n_components, n_columns)`` of ``log π_k N(x; μ_k, Λ_k⁻¹)`` on the quadratic features.

    ``−½ Λ_k`` packed, ``Λ_k μ_k``, ``−½ μ_kᵀ Λ_k μ_k`` on the one, and on the last column the log-normaliser
    ``log π_k − d/2 log 2π + log det U_k`` (``−inf`` for a weight of 0).

    Parameters
    ----------
    weights : ndarray of shape (n_components,)
    means : ndarray of shape (n_components, d)
    precisions_cholesky : ndarray of shape (n_components, d, d)
        ``U`` with ``Λ = U Uᵀ``.
    unit : float, default=1.0
        Means and ``U`` are in coordinates divided by ``unit`` (``U`` times it); the log-determinant is taken of the
        precision in undivided units, so that the density is theirs.
    """
    shape = layout(means.shape[1])
    precisions = precisions_cholesky @ np.swapaxes(precisions_cholesky, 1, 2)
    precision_means = np.einsum("kij,kj->ki", precisions, means)
    log_det = np.log(np.diagonal(precisions_cholesky, axis1=1, axis2=2) / unit).sum(axis=1)
    coefficients = np.empty((len(weights), shape.n_columns))
    coefficients[:, :shape.n_second] = -0.5 * precisions[:, shape.rows, shape.cols]
    coefficients[:, shape.mean] = precision_means
    coefficients[:, shape.one] = -0.5 * np.einsum("ki,ki->k", means, precision_means)
    with np.errstate(divide="ignore"):
        coefficients[:, -1] = np.log(weights) - (0.5 * shape.d) * _LOG_2PI + log_det
    return coefficients
