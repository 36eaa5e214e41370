"""The result of a registration and the pose vector the BFGS solver works on.

A rigid transform ``(R, t)`` maps ``x -> R x + t``; on rows, ``points @ R.T + t``. The optimisers rotate about a
fixed centre ``c`` (the centroid of the source) so that rotation and translation are well decoupled:
``x -> R (x - c) + c + t'``. BFGS works on the 7-vector ``(t', q)`` with an unnormalised quaternion ``q``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dgmm.errors import FitError
from dgmm.registration.checks import as_array, as_points
from dgmm.registration.rotations import matrix_to_quaternion, quaternion_to_matrix

IDENTITY_PARAMS = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])
"""The pose vector ``(t', q)`` of the identity."""


@dataclass(frozen=True)
class Registration:
    """A rigid transform ``x -> rotation @ x + translation`` that moves a source onto a target.

    Attributes
    ----------
    rotation : ndarray of shape (3, 3)
    translation : ndarray of shape (3,)
    iterations : int
        Optimiser iterations (BFGS), ICP or CPD iterations.
    seconds : float
        Wall-clock time of the registration.
    objective : float
        Final value of the method's minimised cost: negative mean log-likelihood (P2D), the determinant-free
        D2D cost, mean matching distance (ICP), CPD's objective ``q`` (pycpd's).
    converged : bool
        Whether the method's own stopping test was met before its iteration cap.
    method : str
        ``"p2d"``, ``"d2d"``, ``"icp"`` or ``"cpd"``.
    """

    rotation: np.ndarray
    translation: np.ndarray
    iterations: int
    seconds: float
    objective: float
    converged: bool
    method: str

    def __post_init__(self):
        """A registration whose cost or pose is not finite is an error, not a pose."""
        if not (np.isfinite(self.objective) and np.all(np.isfinite(self.rotation))
                and np.all(np.isfinite(self.translation))):
            raise FitError(f"{self.method} registration reached a non-finite cost or pose (cost {self.objective}) "
                           f"after {self.iterations} iterations: check that source and target are in the same "
                           f"units and overlap")

    @property
    def quaternion(self):
        """Unit quaternion ``(w, x, y, z)`` with ``w >= 0`` of ``rotation``, shape (4,)."""
        return matrix_to_quaternion(self.rotation)

    def apply(self, points):
        """Move ``points`` of shape (n_points, 3) by this transform; returns shape (n_points, 3)."""
        return as_points("points", points) @ self.rotation.T + self.translation


def pose_from_params(params, centre):
    """Global ``(R, t)`` of the optimiser's ``(t', q)`` rotating about ``centre`` (both shape (3,))."""
    rotation = quaternion_to_matrix(params[3:])
    return rotation, params[:3] + centre - rotation @ centre


def pivot_pose(rotation, translation, centre):
    """The global pose ``(R, t)`` checked, as ``(R, t')`` rotating about ``centre``: ``x -> R (x - c) + c + t'``."""
    rotation = as_array("initial rotation", rotation, (3, 3))
    translation = as_array("initial translation", translation, (3,))
    return rotation, translation - centre + rotation @ centre


def params_from_pose(rotation, translation, centre):
    """The optimiser's 7-vector ``(t', q)`` of the global pose ``(R, t)`` rotating about ``centre``."""
    rotation, pivot = pivot_pose(rotation, translation, centre)
    return np.concatenate([pivot, matrix_to_quaternion(rotation)])

