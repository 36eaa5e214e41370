"""Point-set registration baselines: Kabsch and the authors' both-ways point-to-point ICP (CPD: :mod:`.cpd`)."""
from __future__ import annotations

import time

import numpy as np
from scipy.spatial import cKDTree

from dgmm.errors import InputError
from dgmm.registration.checks import as_array, as_points
from dgmm.registration.pose import Registration


def kabsch(source, target, weights=None):
    """Least-squares rigid transform between corresponding points (Kabsch/Umeyama, no scale).

    Parameters
    ----------
    source, target : array-like of shape (n_points, 3)
        Row ``n`` of ``source`` corresponds to row ``n`` of ``target``.
    weights : array-like of shape (n_points,), optional
        Non-negative pair weights, not all zero; equal when omitted.

    Returns
    -------
    rotation : ndarray of shape (3, 3)
    translation : ndarray of shape (3,)
        Minimisers of ``Σ w_n |R s_n + t - t_n|²``.
    """
    source, target = as_points("source", source), as_points("target", target)
    if len(source) != len(target):
        raise InputError(f"source and target must have as many rows, got {len(source)} and {len(target)}")
    w = np.ones(len(source)) if weights is None else as_array("weights", weights, (len(source),))
    if np.any(w < 0) or w.sum() <= 0:
        raise InputError("weights must be non-negative and not all zero")
    w = w / w.sum()
    source_mean, target_mean = w @ source, w @ target
    cross = (source - source_mean).T @ ((target - target_mean) * w[:, None])
    u, _, vt = np.linalg.svd(cross)
    rotation = vt.T @ np.diag([1.0, 1.0, np.sign(np.linalg.det(vt.T @ u.T))]) @ u.T
    return rotation, target_mean - rotation @ source_mean


def register_icp(source, target, max_iter=50_000, tol=1e-9, callback=None):
    """Point-to-point ICP with nearest neighbours both ways, as the authors ran it.

    Every iteration pools source→target and target→source nearest-neighbour pairs (the target→source pairs
    weighted ``n_source / n_target`` so both directions count equally), takes the closed-form Kabsch step on
    them, and stops when the weighted mean matching distance changes by less than ``tol``.

    Parameters
    ----------
    source : array-like of shape (n_source, 3)
        Points moved onto the target.
    target : array-like of shape (n_target, 3)
    max_iter : int, default=50000
    tol : float, default=1e-9
    callback : callable, optional
        ``callback(iteration, registration)`` after every step with the current pose.

    Returns
    -------
    Registration
        ``objective`` is the last mean matching distance (of the pose before the final step).
    """
    source, target = as_points("source", source), as_points("target", target)
    if int(max_iter) < 1 or not tol >= 0:
        raise InputError(f"max_iter must be >= 1 and tol >= 0, got {max_iter} and {tol}")
    start = time.perf_counter()
    target_tree = cKDTree(target)
    back_weight = len(source) / len(target)
    weights = np.concatenate([np.ones(len(source)), np.full(len(target), back_weight)])
    rotation, translation = np.eye(3), np.zeros(3)
    moved = source
    previous = np.inf
    converged = False
    iteration = 0
    while iteration < max_iter:
        forward_dist, forward_idx = target_tree.query(moved)
        back_dist, back_idx = cKDTree(moved).query(target)
        error = (forward_dist.sum() + back_weight * back_dist.sum()) / (2 * len(source))
        if abs(previous - error) < tol:
            converged = True
            break
        previous = error
        step_rotation, step_translation = kabsch(np.vstack([moved, moved[back_idx]]),
                                                 np.vstack([target[forward_idx], target]), weights)
        moved = moved @ step_rotation.T + step_translation
        rotation, translation = step_rotation @ rotation, step_rotation @ translation + step_translation
        iteration += 1
        if callback is not None:
            callback(iteration, Registration(rotation, translation, iteration, time.perf_counter() - start,
                                             float(error), False, "icp"))
    return Registration(rotation, translation, iteration, time.perf_counter() - start, float(error), converged,
                        "icp")

