"""The authors' random rigid trials (leonidk/direct_gmm) and the errors of a registration that undoes one.

Euler angles uniform in ±15° per axis and a translation uniform in ±0.05 per axis for the bunny (bounding-box
diagonal 0.24077), scaled by the model's diagonal; the trial rotates about a centre (the source centroid). Errors
compare the estimate with the inverse of the trial: the rotation error is the geodesic angle of
``R_est R_trial`` and the translation error is how far the trial followed by the estimate moves the centre, in
percent of the bounding-box diagonal.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dgmm.errors import InputError
from dgmm.registration.checks import as_array, as_points
from dgmm.registration.rotations import euler_to_matrix, rotation_distance_deg

BUNNY_DIAGONAL = 0.24077
"""Bounding-box diagonal of the Stanford bunny, the unit of the authors' trial translations."""


@dataclass(frozen=True)
class RigidTrial:
    """A rigid motion about a centre: ``x -> rotation @ (x - centre) + centre + translation``.

    Attributes
    ----------
    rotation : ndarray of shape (3, 3)
    translation : ndarray of shape (3,)
    centre : ndarray of shape (3,)
    """

    rotation: np.ndarray
    translation: np.ndarray
    centre: np.ndarray

    def apply(self, points):
        """Move ``points`` of shape (n_points, 3) by the trial; returns shape (n_points, 3)."""
        return (as_points("points", points) - self.centre) @ self.rotation.T + self.centre + self.translation


def random_trials(n_trials, seed, diagonal, centre, max_angle_deg=15.0, max_translation=0.05):
    """Random rigid trials of the authors' registration experiment.

    Each trial draws three static-axis Euler angles (``euler_to_matrix``) uniformly in
    ``±max_angle_deg``, then a translation uniformly in ``±max_translation * diagonal / BUNNY_DIAGONAL`` per
    axis, from one ``np.random.default_rng(seed)``.

    Parameters
    ----------
    n_trials : int
    seed : int or numpy.random.Generator
    diagonal : float
        Bounding-box diagonal of the model; the bunny's 0.24077 gives the authors' ±0.05.
    centre : array-like of shape (3,)
        Centre of rotation, normally the centroid of the source points.
    max_angle_deg, max_translation : float

    Returns
    -------
    trials : list of RigidTrial
    """
    if not (np.isfinite(diagonal) and diagonal > 0):
        raise InputError(f"diagonal must be a positive number, got {diagonal}")
    if int(n_trials) < 0:
        raise InputError(f"n_trials must be non-negative, got {n_trials}")
    centre = as_array("centre", centre, (3,))
    rng = np.random.default_rng(seed)
    half_width = max_translation * diagonal / BUNNY_DIAGONAL
    trials = []
    for _ in range(int(n_trials)):
        rotation = euler_to_matrix(rng.uniform(-max_angle_deg, max_angle_deg, size=3))
        trials.append(RigidTrial(rotation, rng.uniform(-half_width, half_width, size=3), centre))
    return trials


def registration_errors(result, trial, diagonal):
    """Errors of a registration that should undo a trial.

    Parameters
    ----------
    result : Registration
        Estimated transform from the trial-moved source back onto the model.
    trial : RigidTrial
    diagonal : float
        Bounding-box diagonal of the model.

    Returns
    -------
    rotation_deg : float
        Geodesic angle of ``R_est R_trial`` (zero when the estimate undoes the trial's rotation).
    translation_pct : float
        ``|T_est(T_trial(c)) - c|`` for the trial's centre ``c``, in percent of ``diagonal`` (the authors'
        ``|t_est - t_trial|`` when both rotate about ``c``).
    """
    if not (np.isfinite(diagonal) and diagonal > 0):
        raise InputError(f"diagonal must be a positive number, got {diagonal}")
    rotation_deg = rotation_distance_deg(result.rotation.T, trial.rotation)
    moved_centre = result.rotation @ (trial.centre + trial.translation) + result.translation
    return rotation_deg, float(100.0 * np.linalg.norm(moved_centre - trial.centre) / diagonal)

