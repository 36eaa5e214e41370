"""Rigid Coherent Point Drift (Myronenko & Song 2010, Fig. 2) exactly as pycpd's ``RigidRegistration`` runs it.

The paper's CPD baseline is pycpd's rigid model at 150 iterations. This module runs the same algorithm, operation
for operation: pycpd's initial variance, its outlier weight ``w``, its E-step then M-step (transform, moved points,
variance), its objective ``q`` and its stopping rule ``|q - q_previous| <= tol``, its variance floor, and its scale
(fitted, then dropped: the rigid part is the Kabsch fit of the source to the moved source, as the authors read it).
Only the E-step's memory traffic differs: pycpd builds an ``(n_source, n_target, 3)`` difference array and tiles
the column sums every iteration; here scipy's ``cdist`` writes the squared distances into one reused
``(n_source, n_target)`` buffer, summing in pycpd's order, and the column sums are broadcast. Every floating point
operation is pycpd's, so the poses agree with pycpd's to the last bit on the same inputs (tests/test_cpd.py checks
them to 1e-9 on seeded problems, some stopping by tolerance; the sweep's 250 Fig 6 trials come out byte-identical),
in a fraction of its time (benchmarks/cpd_speed.py).

Points are rows, as everywhere in :mod:`dgmm.registration`: the source (pycpd's ``Y``, the moving mixture's
centroids) has shape ``(n_source, 3)``, the target (pycpd's ``X``) ``(n_target, 3)``.
"""
from __future__ import annotations

import time

import numpy as np
from scipy.spatial.distance import cdist

from dgmm.errors import InputError
from dgmm.registration.checks import as_points
from dgmm.registration.pointsets import kabsch
from dgmm.registration.pose import Registration


def initial_variance(source, target):
    """pycpd's starting ``sigma²``: the mean squared coordinate difference over all source-target pairs.

    Summed over the full ``(n_source, n_target, 3)`` array as pycpd does (once per registration), so that the
    value is pycpd's to the last bit.
    """
    squared = (target[None, :, :] - source[:, None, :]) ** 2
    return np.sum(squared) / (squared.shape[2] * len(source) * len(target))


def squared_distances(moved, target, out):
    """``out[m, n] = |target[n] - moved[m]|²``, shape (n_source, n_target), written in place.

    scipy's ``cdist`` sums the squared coordinate differences over x, y, z in that order in one C loop: pycpd's
    ``np.sum(diff ** 2, axis=2)`` to the bit, without its (n_source, n_target, 3) array.
    """
    return cdist(moved, target, "sqeuclidean", out=out)


def _e_step(moved, target, sigma2, w, posterior):
    """Posterior of every (moved source point, target point) pair, in place in ``posterior`` (n_source, n_target).

    Returns ``(posterior, Pt1, P1, Np)``: the posterior, its column sums (n_target,), row sums (n_source,) and
    total, as pycpd's ``expectation``.
    """
    n_source, n_target = posterior.shape
    dims = moved.shape[1]
    uniform = (2 * np.pi * sigma2) ** (dims / 2)  # the outlier term, zero for pycpd's default w = 0
    uniform = uniform * w / (1 - w)
    uniform = uniform * n_source / n_target
    squared_distances(moved, target, posterior)
    np.divide(posterior, -(2 * sigma2), out=posterior)  # = -d² / (2 sigma²) to the bit: rounding is sign-symmetric
    np.exp(posterior, out=posterior)
    denominator = np.sum(posterior, axis=0)
    denominator[denominator == 0] = np.finfo(float).eps
    denominator += uniform
    np.divide(posterior, denominator, out=posterior)
    column_sums = np.sum(posterior, axis=0)
    row_sums = np.sum(posterior, axis=1)
    return posterior, column_sums, row_sums, np.sum(row_sums)


def _m_step(source, target, posterior, row_sums, total):
    """pycpd's ``update_transform``: the scaled rigid transform ``y -> s y R + t`` (rows) of Fig. 2.

    Returns ``(rotation, scale, translation, A, target_centred, YPY)``; ``rotation`` is pycpd's ``R``, which acts
    on rows (``moved = s * source @ R + t``).
    """
    target_mean = np.divide(np.sum(np.dot(posterior, target), axis=0), total)
    source_mean = np.divide(np.sum(np.dot(posterior.T, source), axis=0), total)
    target_centred = target - target_mean
    source_centred = source - source_mean
    ypy = np.dot(row_sums, np.sum(source_centred * source_centred, axis=1))
    a = np.dot(np.dot(target_centred.T, posterior.T), source_centred)
    u, _, v = np.linalg.svd(a, full_matrices=True)
    c = np.ones(a.shape[0])
    c[-1] = np.linalg.det(np.dot(u, v))
    rotation = np.dot(np.dot(u, np.diag(c)), v).T  # Fig. 2 / Lemma 1
    scale = np.trace(np.dot(a.T, rotation.T)) / ypy
    translation = target_mean - scale * np.dot(rotation.T, source_mean)
    return rotation, scale, translation, a, target_centred, ypy


def _objective_and_variance(a, rotation, scale, ypy, target_centred, column_sums, total, sigma2):
    """pycpd's ``update_variance``: the objective ``q`` at the old ``sigma²`` and the new ``sigma²``."""
    dims = a.shape[0]
    tr_ar = np.trace(np.dot(a, rotation))
    xpx = np.dot(column_sums, np.sum(target_centred * target_centred, axis=1))
    q = (xpx - 2 * scale * tr_ar + scale * scale * ypy) / (2 * sigma2) + dims * total / 2 * np.log(sigma2)
    return q, (xpx - scale * tr_ar) / (total * dims)


def register_cpd(source, target, max_iter=150, tol=1e-9, w=0.0, callback=None):
    """Rigid Coherent Point Drift moving ``source`` onto ``target``, as pycpd's ``RigidRegistration``.

    Parameters
    ----------
    source : array-like of shape (n_source, 3)
        The moving points (the GMM centroids; pycpd's ``Y``).
    target : array-like of shape (n_target, 3)
        The data points (pycpd's ``X``).
    max_iter : int, default=150
        EM iterations at most (the paper's 150).
    tol : float, default=1e-9
        Stop once the objective changes by at most ``tol`` between iterations (pycpd's ``tolerance``; also the
        variance floor's scale: a non-positive ``sigma²`` becomes ``tol / 10``, as in pycpd).
    w : float, default=0.0
        Weight of the uniform outlier component, in [0, 1) (pycpd's ``w``; the paper ran pycpd's default 0).
    callback : callable, optional
        ``callback(iteration, registration)`` after every EM iteration with the current rigid part.

    Returns
    -------
    Registration
        The rigid part: the Kabsch fit of ``source`` to its final scaled-rigid image, as the authors read pycpd's
        result. ``objective`` is pycpd's final ``q``; ``converged`` says the tolerance stopped it.
    """
    source, target = as_points("source", source), as_points("target", target)
    if int(max_iter) < 1 or not tol >= 0:
        raise InputError(f"max_iter must be >= 1 and tol >= 0, got {max_iter} and {tol}")
    if not 0 <= w < 1:
        raise InputError(f"w must be in [0, 1), got {w}")
    start = time.perf_counter()
    sigma2 = initial_variance(source, target)
    rotation, scale, translation = np.eye(3), 1, np.zeros(3)
    moved = scale * np.dot(source, rotation) + translation
    posterior = np.empty((len(source), len(target)))
    q, change, iteration = np.inf, np.inf, 0
    while iteration < max_iter and change > tol:
        posterior, column_sums, row_sums, total = _e_step(moved, target, sigma2, w, posterior)
        rotation, scale, translation, a, target_centred, ypy = _m_step(source, target, posterior, row_sums, total)
        moved = scale * np.dot(source, rotation) + translation
        previous = q
        q, sigma2 = _objective_and_variance(a, rotation, scale, ypy, target_centred, column_sums, total, sigma2)
        change = np.abs(q - previous)
        if sigma2 <= 0:
            sigma2 = tol / 10
        iteration += 1
        if callback is not None:
            callback(iteration, Registration(*kabsch(source, moved), iteration, time.perf_counter() - start,
                                             float(q), False, "cpd"))
    return Registration(*kabsch(source, moved), iteration, time.perf_counter() - start, float(q),
                        bool(change <= tol), "cpd")
