"""Covariance ellipsoids: the principal axes and half-sizes both recording formats draw a mixture's components
with."""
import numpy as np
from scipy.spatial.transform import Rotation

from dgmm.errors import InputError

DEFAULT_N_SIGMA = 2.0
"""Ellipsoids are drawn at this many standard deviations along each principal axis."""


def covariance_ellipsoids(covariances, n_sigma=DEFAULT_N_SIGMA):
    """Principal axes of covariance ellipsoids as proper rotations and half-sizes.

    ``covariances[i] = rotations[i] @ diag((half_sizes[i] / n_sigma) ** 2) @ rotations[i].T``.

    Parameters
    ----------
    covariances : array-like of shape (n_components, 3, 3)
        Symmetric positive semi-definite matrices.
    n_sigma : float, default=2.0
        Number of standard deviations the half-sizes span.

    Returns
    -------
    rotations : ndarray of shape (n_components, 3, 3)
        Columns are the principal axes (eigenvectors, ascending eigenvalue); determinant +1.
    half_sizes : ndarray of shape (n_components, 3)
        ``n_sigma * sqrt(eigenvalue)`` along each column of ``rotations``.
    quaternions : ndarray of shape (n_components, 4)
        ``rotations`` as unit quaternions in (x, y, z, w) order, the order of Foxglove and rerun.
    """
    covariances = np.asarray(covariances, dtype=np.float64)
    if covariances.ndim != 3 or covariances.shape[1:] != (3, 3):
        raise InputError(f"covariances must have shape (n_components, 3, 3), got {covariances.shape}")
    eigenvalues, rotations = np.linalg.eigh(covariances)
    # eigh may return a reflection; flipping one axis keeps the same ellipsoid and makes it a rotation.
    rotations[:, :, 2] *= np.sign(np.linalg.det(rotations))[:, None]
    half_sizes = n_sigma * np.sqrt(np.clip(eigenvalues, 0.0, None))
    quaternions = Rotation.from_matrix(rotations).as_quat()
    return rotations, half_sizes, quaternions
