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
from dgmm.gaussian import layout, log_density_coefficients
from dgmm.registration.checks import as_array

EXP_FLOOR = -700.0
"""Exponents are clipped here before ``np.exp``: numpy's exp is ~20x slower on very negative inputs, and a term of
``e^-700 ~ 1e-304`` beside a largest term of 1 changes no sum of fewer than 1e288 terms."""
_SHAPE = layout(3)


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
    def origin(self):
        """Where offsets are measured from (the centroid), so that the expanded quadratics stay well scaled."""
        return self.centroid

    @cached_property
    def _coefficients(self):
        """:func:`dgmm.gaussian.log_density_coefficients` of the components about :attr:`origin`, (n_components, 11)."""
        return log_density_coefficients(self.weights, self.means - self.origin, self.precisions_cholesky)

    @property
    def log_normalisers(self):
        """``log π_k - 1.5 log 2π + log det U_k``: log-density of component k at its mean plus log weight,
        (n_components,)."""
        return self._coefficients[:, -1]

    @cached_property
    def log_density_table(self):
        """Coefficients of ``log π_k N(y | μ_k, Σ_k)`` on :func:`dgmm.gaussian.quadratic_features` of ``y - origin``,
        (10, n_components): :attr:`_coefficients` with the one's and the log-normaliser's columns added."""
        coefficients = self._coefficients
        constant = coefficients[:, -1] + coefficients[:, _SHAPE.one]
        return np.column_stack([coefficients[:, :_SHAPE.one], constant]).T.copy()

    @cached_property
    def precision_means(self):
        """``P_k (μ_k - origin)``, contiguous, (n_components, 3)."""
        return np.ascontiguousarray(self._coefficients[:, _SHAPE.mean])

    @cached_property
    def moment_table(self):
        """``[P_k (9 entries), P_k m_k (3)]`` per component, (n_components, 12): responsibilities times it give
        every point's gradient ``Σ_k r_k P_k (d - m_k)`` and Gauss-Newton weight ``Σ_k r_k P_k``."""
        return np.column_stack([self.precisions.reshape(-1, 9), self.precision_means])

    @cached_property
    def gradient_outer_table(self):
        """Coefficients of ``g gᵀ`` (6 distinct entries), ``g = P_k (d - m_k)``, on
        :func:`dgmm.gaussian.quadratic_features` of ``d``, shape (n_components, 60): responsibilities times it,
        contracted with the features, give each point's ``Σ_k r_k g_k g_kᵀ`` (the spread term of the exact Hessian
        of ``-log p``)."""
        p, pm = self.precisions, self.precision_means
        rows, cols = _SHAPE.rows, _SHAPE.cols
        p_a, p_b = p[:, rows], p[:, cols]  # rows a and b of P_k for each entry (a, b) of g gᵀ, (n_components, 6, 3)
        outer = p_a[:, :, :, None] * p_b[:, :, None, :]
        quadratic = 0.5 * (outer + outer.swapaxes(2, 3))[:, :, rows, cols]  # the features' off-diagonals are doubled
        linear = -(pm[:, cols, None] * p_a + pm[:, rows, None] * p_b)
        constant = pm[:, rows] * pm[:, cols]
        return np.concatenate([quadratic, linear, constant[:, :, None]], axis=2).reshape(len(p), 60)
