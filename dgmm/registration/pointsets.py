"""Point-set registration baselines: Kabsch and the authors' both-ways point-to-point ICP (CPD: :mod:`.cpd`)."""
from __future__ import annotations

import time

import numpy as np

from dgmm.errors import InputError
from dgmm.registration.checks import as_array, as_points
from dgmm.registration.neighbours import TrackedNeighbours
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
    return _kabsch(source.T, target.T, w / w.sum())


def _kabsch(source, target, weights):
    """:func:`kabsch` of coordinate-major ``(3, n)`` points (ICP keeps its points so: its sums then run along
    rows), ``weights`` summing to one."""
    source_mean, target_mean = source @ weights, target @ weights
    cross = (source - source_mean[:, None]) @ ((target - target_mean[:, None]) * weights).T
    u, _, vt = np.linalg.svd(cross)
    rotation = vt.T @ np.diag([1.0, 1.0, np.sign(np.linalg.det(vt.T @ u.T))]) @ u.T
    return rotation, target_mean - rotation @ source_mean


def register_icp(source, target, max_iter=50_000, tol=1e-9, callback=None):
    """Point-to-point ICP with nearest neighbours both ways, as the authors ran it.

    Every iteration pools source→target and target→source nearest-neighbour pairs (the target→source pairs
    weighted ``n_source / n_target`` so both directions count equally), takes the closed-form Kabsch step on
    them, and stops when the weighted mean matching distance changes by less than ``tol``. The neighbours are exact
    (:class:`~dgmm.registration.neighbours.TrackedNeighbours`: a k-d tree per side, built once, re-queried only
    where the previous neighbours cannot be proven still nearest).

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
    # The moved point nearest to a target point p is the source point nearest to Rᵀ(p − t), at the same distance:
    # both sides' points stay fixed, and the queries move a little per step.
    forward, back = TrackedNeighbours(target), TrackedNeighbours(source)
    n_source, n_target = len(source), len(target)
    back_weight = n_source / n_target
    weights = np.concatenate([np.ones(n_source), np.full(n_target, back_weight)])
    weights /= weights.sum()
    # Points coordinate-major (3, n) from here on. The pooled pairs (moved, matched target) then (matched moved,
    # target), refilled in place every iteration.
    moved, target = source.T.copy(), target.T.copy()
    pooled_source, pooled_target = np.empty((3, n_source + n_target)), np.empty((3, n_source + n_target))
    pooled_target[:, n_source:] = target
    rotation, translation = np.eye(3), np.zeros(3)
    previous = np.inf
    converged = False
    iteration = 0
    while iteration < max_iter:
        forward_dist, forward_idx = forward.query(moved.T)
        back_dist, back_idx = back.query((rotation.T @ (target - translation[:, None])).T)
        error = (forward_dist.sum() + back_weight * back_dist.sum()) / (2 * n_source)
        if abs(previous - error) < tol:
            converged = True
            break
        previous = error
        pooled_source[:, :n_source] = moved
        np.take(moved, back_idx, axis=1, out=pooled_source[:, n_source:])
        np.take(target, forward_idx, axis=1, out=pooled_target[:, :n_source])
        step_rotation, step_translation = _kabsch(pooled_source, pooled_target, weights)
        moved = step_rotation @ moved + step_translation[:, None]
        rotation, translation = step_rotation @ rotation, step_rotation @ translation + step_translation
        iteration += 1
        if callback is not None:
            callback(iteration, Registration(rotation, translation, iteration, time.perf_counter() - start,
                                             float(error), False, "icp"))
    return Registration(rotation, translation, iteration, time.perf_counter() - start, float(error), converged,
                        "icp")

