"""Trajectory error metrics of TUM's benchmark (Sturm et al. 2012): ATE after a rigid alignment, and RPE.

Both equal evo's (``evo_ape`` / ``evo_rpe``, translation parts, no scale) on the same TUM files and settings.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dgmm.errors import InputError
from dgmm.registration import kabsch
from dgmm.odometry.tum import MAX_TIME_DIFFERENCE, associate

@dataclass(frozen=True)
class TrajectoryError:
    """Absolute trajectory error after a rigid alignment (TUM's ATE, no scale).

    Attributes
    ----------
    rmse : float
        Root mean square of ``errors``, metres.
    errors : ndarray of shape (n_pairs,)
        Distance of each aligned estimated position to its ground-truth position.
    rotation : ndarray of shape (3, 3)
    translation : ndarray of shape (3,)
        The alignment ``x -> R x + t`` applied to the estimated positions.
    timestamps : ndarray of shape (n_pairs,)
        Estimated-trajectory timestamps that found a ground-truth partner.
    """

    rmse: float
    errors: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray
    timestamps: np.ndarray


def absolute_trajectory_error(estimate, reference, max_difference=MAX_TIME_DIFFERENCE):
    """ATE RMSE of an estimated trajectory against ground truth (Sturm et al. 2012, eq. 7 and 8).

    Estimated poses are paired with the nearest ground-truth timestamp within ``max_difference``; the estimated
    positions are rigidly aligned to their partners by the closed-form least-squares fit (Horn/Umeyama without
    scale, ``dgmm.registration.kabsch``), and the RMSE of the remaining position differences is returned.

    Parameters
    ----------
    estimate, reference : Trajectory
    max_difference : float

    Returns
    -------
    TrajectoryError

    Raises
    ------
    InputError
        Fewer than 3 pairs (the alignment is not determined).
    """
    first, second = associate(estimate.timestamps, reference.timestamps, max_difference)
    if len(first) < 3:
        raise InputError(f"only {len(first)} estimated poses have a ground-truth pose within {max_difference} s")
    est, ref = estimate.translations[first], reference.translations[second]
    rotation, translation = kabsch(est, ref)
    errors = np.linalg.norm(est @ rotation.T + translation - ref, axis=1)
    return TrajectoryError(float(np.sqrt(np.mean(errors ** 2))), errors, rotation, translation,
                           estimate.timestamps[first])


RPE_WINDOW_SECONDS = 1.0
"""TUM's RPE window for odometry: drift per second."""


@dataclass(frozen=True)
class RelativePoseError:
    """Relative pose error of odometry over windows of about one second (Sturm et al. 2012, eq. 1–3).

    Attributes
    ----------
    translation_rmse : float
        RMSE of the translation of ``E_i = (Q_i⁻¹ Q_{i+Δ})⁻¹ (P_i⁻¹ P_{i+Δ})``, metres per window (m/s for 1 s).
    rotation_rmse_deg : float
        RMSE of the rotation angle of ``E_i``, degrees per window.
    delta : int
        Window in associated frames, ``round(window / median frame interval)``.
    n_pairs : int
        Windows compared: every associated frame ``i`` with ``i + delta`` in the run.
    """

    translation_rmse: float
    rotation_rmse_deg: float
    delta: int
    n_pairs: int


def _relative(rotations, translations, first, second):
    """Rotations and translations of ``T_first⁻¹ T_second`` for index arrays ``first``, ``second``."""
    r_first_t = np.transpose(rotations[first], (0, 2, 1))
    rotation = r_first_t @ rotations[second]
    translation = np.einsum("nij,nj->ni", r_first_t, translations[second] - translations[first])
    return rotation, translation


def frame_motions(trajectory):
    """Every frame's motion to the next, ``T_k⁻¹ T_{k+1}`` (what frame-to-frame odometry estimates).

    Parameters
    ----------
    trajectory : dgmm.odometry.Trajectory

    Returns
    -------
    rotations : ndarray of shape (n_frames - 1, 3, 3)
    translations : ndarray of shape (n_frames - 1, 3)
        In frame ``k``'s camera coordinates.
    """
    n = len(trajectory)
    return _relative(np.asarray(trajectory.rotations), np.asarray(trajectory.translations), np.arange(n - 1),
                     np.arange(1, n))


def relative_pose_error(estimate, reference, window=RPE_WINDOW_SECONDS, max_difference=MAX_TIME_DIFFERENCE):
    """RPE of an estimated trajectory against ground truth, over windows of ``window`` seconds.

    Estimated poses are paired with the nearest ground-truth timestamp within ``max_difference`` (as for the
    ATE); the window is ``delta = round(window / median interval)`` of the paired frames and every pair
    ``(i, i + delta)`` is compared. This is ``evo_rpe tum REF EST --delta DELTA --delta_unit f --all_pairs`` after
    evo's association with the same ``max_difference`` (evo has no time unit for the window).

    Parameters
    ----------
    estimate, reference : Trajectory
    window : float
        Seconds.
    max_difference : float

    Returns
    -------
    RelativePoseError

    Raises
    ------
    InputError
        The paired frames span less than one window.
    """
    first, second = associate(estimate.timestamps, reference.timestamps, max_difference)
    stamps = estimate.timestamps[first]
    delta = max(1, int(round(window / np.median(np.diff(stamps))))) if len(stamps) > 1 else 1
    if len(first) <= delta:
        raise InputError(f"only {len(first)} estimated poses have a ground-truth pose within {max_difference} s: "
                         f"RPE needs more than one {window} s window ({delta} frames)")
    i, j = np.arange(len(first) - delta), np.arange(delta, len(first))
    q_rot, q_trans = _relative(reference.rotations[second], reference.translations[second], i, j)
    p_rot, p_trans = _relative(estimate.rotations[first], estimate.translations[first], i, j)
    # E = Q_rel⁻¹ P_rel: rotation Q_rᵀ P_r, translation Q_rᵀ (p_t − q_t)
    q_rot_t = np.transpose(q_rot, (0, 2, 1))
    error_rotation = q_rot_t @ p_rot
    error_translation = np.einsum("nij,nj->ni", q_rot_t, p_trans - q_trans)
    skew = error_rotation - np.transpose(error_rotation, (0, 2, 1))  # 2 sin(θ) [axis]×
    sine = np.linalg.norm(skew[:, [2, 0, 1], [1, 2, 0]], axis=1) / 2.0
    angles = np.degrees(np.arctan2(sine, (np.trace(error_rotation, axis1=1, axis2=2) - 1.0) / 2.0))
    return RelativePoseError(float(np.sqrt(np.mean(np.sum(error_translation ** 2, axis=1)))),
                             float(np.sqrt(np.mean(angles ** 2))), delta, len(i))


def drift_metrics(estimate, reference, max_difference=MAX_TIME_DIFFERENCE):
    """The odometry table's columns: ATE RMSE and the one-second RPE of ``estimate`` against ``reference``.

    Parameters
    ----------
    estimate : Trajectory
    reference : Trajectory or None
        None: a sequence without ground truth, every entry None.
    max_difference : float

    Returns
    -------
    metrics : dict
        ``ate_rmse_m``, ``rpe_translation_m_s``, ``rpe_rotation_deg_s``; the RPE entries are None when the paired
        frames span less than one window.
    """
    if reference is None:
        return {"ate_rmse_m": None, "rpe_translation_m_s": None, "rpe_rotation_deg_s": None}
    ate = absolute_trajectory_error(estimate, reference, max_difference)
    try:
        rpe = relative_pose_error(estimate, reference, max_difference=max_difference)
    except InputError:
        return {"ate_rmse_m": ate.rmse, "rpe_translation_m_s": None, "rpe_rotation_deg_s": None}
    return {"ate_rmse_m": ate.rmse, "rpe_translation_m_s": rpe.translation_rmse,
            "rpe_rotation_deg_s": rpe.rotation_rmse_deg}
