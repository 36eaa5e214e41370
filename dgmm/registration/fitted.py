"""A fitted Gaussian mixture as the registration costs use it: checked once, with its pose-independent caches.

A mixture is any object with scikit-learn's fitted attributes ``weights_ (n_components,)``, ``means_
(n_components, 3)``, ``covariances_ (n_components, 3, 3)`` and ``precisions_cholesky_ (n_components, 3, 3)``
(upper-triangular ``U`` with precision ``U Uᵀ``), e.g. ``dgmm.GaussianMixture`` or
``sklearn.mixture.GaussianMixture(covariance_type="full")``.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from dgmm.errors import InputError
from dgmm.registration.checks import as_array

_LOG_2PI = np.log(2.0 * np.pi)
EXP_FLOOR = -700.0
"""Exponents are clipped here before ``np.exp``: numpy's exp is ~20x slower on very negative inputs, and a term of
``e^-700 ~ 1e-304`` beside a largest term of 1 changes no sum of fewer than 1e288 terms."""
_UPPER = (np.array([0, 1, 2, 0, 0, 1]), np.array([0, 1, 2, 1, 2, 2]))
"""Row and column of the 6 distinct entries of a symmetric 3x3 matrix: xx, yy, zz, xy, xz, yz."""
FULL_INDEX = np.array([[0, 3, 4], [3, 1, 5], [4, 5, 2]])
"""Index into those 6 entries of each entry of the full 3x3 matrix."""


def quadratic_features(offsets):
    """Monomials of the offsets up to degree 2: ``(x², y², z², xy, xz, yz, x, y, z, 1)``.

    Parameters
    ----------
    offsets : ndarray of shape (n_points, 3)

    Returns
    -------
    features : ndarray of shape (n_points, 10)
        ``features @ FittedMixture.log_density_table`` is every point's log-density under every component.
    """
    features = np.empty((len(offsets), 10))
    rows, cols = _UPPER
    np.multiply(offsets[:, rows], offsets[:, cols], out=features[:, :6])
    features[:, 6:9] = offsets
    features[:, 9] = 1.0
    return features


@dataclass(frozen=True)
class FittedMixture:
    """The fitted arrays of a Gaussian mixture, checked once.

    Attributes
    ----------
    weights : ndarray of shape (n_components,)
    means : ndarray of shape (n_components, 3)
    covariances : ndarray of shape (n_components, 3, 3)
    precisions_cholesky : ndarray of shape (n_components, 3, 3)
        Upper-triangular ``U`` with precision ``U Uᵀ`` (scikit-learn's convention).
    """

    weights: np.ndarray
    means: np.ndarray
    covariances: np.ndarray
    precisions_cholesky: np.ndarray

    @classmethod
    def from_fitted(cls, name, mixture):
        """Read and check the fitted attributes of ``mixture`` (or return it if already a FittedMixture)."""
        if isinstance(mixture, cls):
            return mixture
        arrays = {}
        for attribute, shape in (("weights_", (None,)), ("means_", (None, 3)),
                                 ("covariances_", (None, 3, 3)), ("precisions_cholesky_", (None, 3, 3))):
            if not hasattr(mixture, attribute):
                raise InputError(f"{name} has no fitted attribute {attribute} (fit it, with full covariances)")
            arrays[attribute] = as_array(f"{name}.{attribute}", getattr(mixture, attribute), shape)
        n_components = len(arrays["weights_"])
        if any(len(values) != n_components for values in arrays.values()):
            raise InputError(f"{name} attributes disagree on n_components: "
                             + ", ".join(f"{key} {values.shape}" for key, values in arrays.items()))
        if np.any(arrays["weights_"] <= 0):
            raise InputError(f"{name}.weights_ must be positive")
        return cls(arrays["weights_"], arrays["means_"], arrays["covariances_"], arrays["precisions_cholesky_"])

    @property
    def centroid(self):
        """Weighted mean of the component means, shape (3,)."""
        return self.weights @ self.means / self.weights.sum()

    @cached_property
    def precisions(self):
        """``U Uᵀ``, shape (n_components, 3, 3)."""
        return self.precisions_cholesky @ self.precisions_cholesky.transpose(0, 2, 1)

    @cached_property
    def log_normalisers(self):
        """``log π_k - 1.5 log 2π + log det U_k``: log-density of component k at its mean plus log weight, (n_components,)."""
        return (np.log(self.weights) - 1.5 * _LOG_2PI
                + np.log(np.diagonal(self.precisions_cholesky, axis1=1, axis2=2)).sum(axis=1))

    @cached_property
    def origin(self):
        """Where offsets are measured from (the centroid), so that the expanded quadratics stay well scaled."""
        return self.centroid

    @cached_property
    def log_density_table(self):
        """Coefficients of ``log π_k N(y | μ_k, Σ_k)`` on :func:`quadratic_features` of ``y - origin``, (10, n_components).

        ``-½ (d - m)ᵀ P (d - m) = -½ dᵀ P d + dᵀ P m - ½ mᵀ P m`` with ``d = y - origin``, ``m = μ - origin``.
        """
        p = self.precisions
        m = self.means - self.origin
        pm = np.einsum("kab,kb->ka", p, m)
        rows, cols = _UPPER
        quadratic = -p[:, rows, cols] * np.where(rows == cols, 0.5, 1.0)
        constant = self.log_normalisers - 0.5 * np.einsum("ka,ka->k", m, pm)
        return np.column_stack([quadratic, pm, constant]).T.copy()

    @cached_property
    def moment_table(self):
        """``[P_k (9 entries), P_k m_k (3)]`` per component, (n_components, 12): responsibilities times it give
        every point's gradient ``Σ_k r_k P_k (d - m_k)`` and Gauss-Newton weight ``Σ_k r_k P_k``."""
        p = self.precisions
        return np.column_stack([p.reshape(-1, 9), np.einsum("kab,kb->ka", p, self.means - self.origin)])

    @cached_property
    def precision_means(self):
        """``P_k (μ_k - origin)``, the moment table's last three columns, contiguous, (n_components, 3)."""
        return np.ascontiguousarray(self.moment_table[:, 9:])

    @cached_property
    def gradient_outer_table(self):
        """Coefficients of ``g gᵀ`` (6 distinct entries), ``g = P_k (d - m_k)``, on :func:`quadratic_features` of
        ``d``, shape (n_components, 60): responsibilities times it, contracted with the features, give each
        point's ``Σ_k r_k g_k g_kᵀ`` (the spread term of the exact Hessian of ``-log p``)."""
        p = self.precisions
        pm = np.einsum("kab,kb->ka", p, self.means - self.origin)
        rows, cols = _UPPER
        p_a, p_b = p[:, rows], p[:, cols]  # rows a and b of P_k for each entry (a, b) of g gᵀ, (n_components, 6, 3)
        outer = p_a[:, :, :, None] * p_b[:, :, None, :]
        quadratic = (outer + outer.swapaxes(2, 3))[:, :, rows, cols] * np.where(rows == cols, 0.5, 1.0)
        linear = -(pm[:, cols, None] * p_a + pm[:, rows, None] * p_b)
        constant = pm[:, rows] * pm[:, cols]
        return np.concatenate([quadratic, linear, constant[:, :, None]], axis=2).reshape(len(p), 60)
