"""Rotations: quaternions (scalar-first ``(w, x, y, z)``), matrices, rotation vectors, Euler angles, distances.

Every function accepts one rotation or a stack of them (rows are items). The pose optimisers' derivatives live here
too: the rotation of an unnormalised quaternion with its Jacobian (BFGS), and the exponential map of the left
perturbation ``R -> exp([w]x) R`` (Gauss-Newton).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from dgmm.errors import InputError
from dgmm.registration.checks import as_array


def quaternion_to_matrix(quaternions):
    """Rotation matrices of unit quaternions.

    Parameters
    ----------
    quaternions : array-like of shape (4,) or (n_rotations, 4)
        Scalar-first ``(w, x, y, z)``; normalised here, so any non-zero quaternion is accepted.

    Returns
    -------
    rotations : ndarray of shape (3, 3) or (n_rotations, 3, 3)
    """
    q = np.asarray(quaternions, dtype=np.float64)
    if q.shape[-1:] != (4,) or q.ndim > 2 or not np.all(np.isfinite(q)):
        raise InputError(f"quaternions must be finite with shape (4,) or (n, 4), got {q.shape}")
    norms = np.linalg.norm(q, axis=-1, keepdims=True)
    if np.any(norms == 0):
        raise InputError("quaternions must be non-zero")
    w, x, y, z = np.moveaxis(q / norms, -1, 0)
    rows = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    return np.moveaxis(np.array(rows), (0, 1), (-2, -1))


def matrix_to_quaternion(rotations):
    """Unit quaternions ``(w, x, y, z)`` with ``w >= 0`` of rotation matrices.

    Parameters
    ----------
    rotations : array-like of shape (3, 3) or (n_rotations, 3, 3)

    Returns
    -------
    quaternions : ndarray of shape (4,) or (n_rotations, 4)
    """
    return Rotation.from_matrix(_as_rotations("rotations", rotations)).as_quat(canonical=True, scalar_first=True)


def rotvec_to_matrix(rotvecs):
    """Rotation matrices of rotation vectors ``theta * axis`` (radians).

    Parameters
    ----------
    rotvecs : array-like of shape (3,) or (n_rotations, 3)

    Returns
    -------
    rotations : ndarray of shape (3, 3) or (n_rotations, 3, 3)
    """
    return Rotation.from_rotvec(_as_vectors("rotvecs", rotvecs)).as_matrix()


def matrix_to_rotvec(rotations):
    """Rotation vectors ``theta * axis`` (radians, ``theta`` in [0, pi]) of rotation matrices.

    Parameters
    ----------
    rotations : array-like of shape (3, 3) or (n_rotations, 3, 3)

    Returns
    -------
    rotvecs : ndarray of shape (3,) or (n_rotations, 3)
    """
    return Rotation.from_matrix(_as_rotations("rotations", rotations)).as_rotvec()


def euler_to_matrix(angles_deg):
    """Rotation ``Rz(c) Ry(b) Rx(a)`` of static-axis Euler angles ``(a, b, c)`` in degrees.

    This is transforms3d's default ``"sxyz"`` (scipy's ``"xyz"``), the convention of the authors' trials.

    Parameters
    ----------
    angles_deg : array-like of shape (3,) or (n_rotations, 3)

    Returns
    -------
    rotations : ndarray of shape (3, 3) or (n_rotations, 3, 3)
    """
    return Rotation.from_euler("xyz", _as_vectors("angles_deg", angles_deg), degrees=True).as_matrix()


def _as_vectors(name, vectors):
    """Return ``vectors`` as finite float64 of shape (3,) or (n, 3), or raise."""
    values = np.asarray(vectors, dtype=np.float64)
    if values.shape[-1:] != (3,) or values.ndim > 2 or not np.all(np.isfinite(values)):
        raise InputError(f"{name} must be finite with shape (3,) or (n, 3), got {values.shape}")
    return values


def _as_rotations(name, rotations):
    """Return ``rotations`` as finite float64 of shape (3, 3) or (n, 3, 3), or raise."""
    values = np.asarray(rotations, dtype=np.float64)
    if values.shape[-2:] != (3, 3) or values.ndim > 3 or not np.all(np.isfinite(values)):
        raise InputError(f"{name} must be finite with shape (3, 3) or (n, 3, 3), got {values.shape}")
    return values


def rotation_distance_deg(rotation_a, rotation_b):
    """Geodesic distance between rotations: the angle of ``R_aᵀ R_b``, in degrees.

    Parameters
    ----------
    rotation_a, rotation_b : array-like of shape (3, 3)

    Returns
    -------
    angle : float
        In [0, 180].
    """
    relative = as_array("rotation_a", rotation_a, (3, 3)).T @ as_array("rotation_b", rotation_b, (3, 3))
    return float(np.degrees(Rotation.from_matrix(relative).magnitude()))


def rotation_and_jacobian(quaternion):
    """Rotation of a normalised quaternion and its derivative with respect to the unnormalised one.

    Parameters
    ----------
    quaternion : ndarray of shape (4,)
        ``(w, x, y, z)``, any non-zero length.

    Returns
    -------
    rotation : ndarray of shape (3, 3)
        ``R(q / |q|)``.
    jacobian : ndarray of shape (4, 3, 3)
        ``d R(q / |q|) / d q_j``: the derivative of ``R`` at the unit quaternion ``u``, chained through the
        normalisation ``d u / d q = (I - u uᵀ) / |q|``.
    """
    norm = np.linalg.norm(quaternion)
    if norm == 0:
        raise InputError("quaternion must be non-zero")
    u = quaternion / norm
    w, x, y, z = u
    unit_jacobian = 2.0 * np.array([
        [[0, -z, y], [z, 0, -x], [-y, x, 0]],
        [[0, y, z], [y, -2 * x, -w], [z, w, -2 * x]],
        [[-2 * y, x, w], [x, 0, z], [-w, z, -2 * y]],
        [[-2 * z, -w, x], [w, -2 * z, y], [x, y, 0]],
    ])
    projection = (np.eye(4) - np.outer(u, u)) / norm
    return quaternion_to_matrix(u), np.einsum("ij,jab->iab", projection, unit_jacobian)



def exp_rotation(rotvec):
    """Rotation matrix ``exp([w]x)`` of one rotation vector ``w`` of shape (3,) (Rodrigues' formula)."""
    x, y, z = rotvec
    theta2 = x * x + y * y + z * z
    if theta2 < 1e-16:
        a, b = 1.0, 0.5
    else:
        theta = np.sqrt(theta2)
        a, b = np.sin(theta) / theta, (1.0 - np.cos(theta)) / theta2
    # I + a K + b K², with K² = w wᵀ - |w|² I
    return np.array([[1.0 - b * (y * y + z * z), b * x * y - a * z, b * x * z + a * y],
                     [b * x * y + a * z, 1.0 - b * (x * x + z * z), b * y * z - a * x],
                     [b * x * z - a * y, b * y * z + a * x, 1.0 - b * (x * x + y * y)]])


LEVI_CIVITA = np.zeros((3, 3, 3))
"""The permutation symbol ``ε_abc``: ``(u x v)_a = ε_abc u_b v_c``."""
LEVI_CIVITA[[0, 1, 2], [1, 2, 0], [2, 0, 1]], LEVI_CIVITA[[0, 1, 2], [2, 0, 1], [1, 2, 0]] = 1.0, -1.0
