"""D2D registration of two frames' mixtures restricted to what both cameras see (the views' overlap).

Under fast rotation a frame loses and gains a tenth of its view per frame. Each frame's mixture tiles its own view,
so on a plane that runs out of the image (a wall, the floor) the tiles of two frames end in different places, and
D2D slides one tiling along the plane to match the other: translation errors of 5-15 cm with the rotation right
(the synthetic room under rotation-only motion, ``benchmarks/odometry_rotation_room.py``; noise-free renderings
fail alike, the same frames fitted on their common field of view do not). :func:`register_d2d_overlap` registers
the whole mixtures, then keeps of each mixture the components whose mean the other camera sees at that pose, and
registers those from it, for a few rounds.
"""
from __future__ import annotations

import numpy as np

from dgmm.registration import Registration, register_d2d


def seen_by(means, rotation, translation, intrinsics):
    """Which points, moved by ``(rotation, translation)`` into a camera, that camera sees (in front, in its image).

    Parameters
    ----------
    means : ndarray of shape (n, 3)
    rotation : ndarray of shape (3, 3)
    translation : ndarray of shape (3,)
    intrinsics : dgmm.odometry.pixels.Intrinsics

    Returns
    -------
    seen : ndarray of bool, shape (n,)
        Projection ``u`` in ``[-0.5, width - 0.5)`` and ``v`` in ``[-0.5, height - 0.5)``, depth positive.
    """
    points = means @ rotation.T + translation
    depth = points[:, 2]
    front = depth > 0
    safe = np.where(front, depth, 1.0)
    u = intrinsics.fx * points[:, 0] / safe + intrinsics.cx
    v = intrinsics.fy * points[:, 1] / safe + intrinsics.cy
    return front & (u >= -0.5) & (u < intrinsics.width - 0.5) & (v >= -0.5) & (v < intrinsics.height - 0.5)


class _Components:
    """The fitted arrays of ``mixture`` (what D2D reads) restricted to the components ``keep``."""

    def __init__(self, mixture, keep):
        weights = np.asarray(mixture.weights_)[keep]
        self.weights_ = weights / weights.sum()
        self.means_ = np.asarray(mixture.means_)[keep]
        self.covariances_ = np.asarray(mixture.covariances_)[keep]
        self.precisions_cholesky_ = np.asarray(mixture.precisions_cholesky_)[keep]


def register_d2d_overlap(fixed, moving, intrinsics, rounds=2, solver="gauss-newton"):
    """D2D of two frames' mixtures (camera coordinates), then ``rounds`` times on the components the other sees.

    Round 0 registers the whole mixtures from the identity. Each further round keeps the fixed mixture's
    components whose mean the moving camera sees at the current pose and the moving mixture's whose mean the
    fixed camera sees (:func:`seen_by`; weights renormalised) and registers them from that pose. A round that
    would leave either mixture without a component stops the rounds.

    Parameters
    ----------
    fixed, moving : fitted Gaussian mixture
        As for :func:`dgmm.registration.register_d2d`, in their cameras' coordinates.
    intrinsics : dgmm.odometry.pixels.Intrinsics
        Both frames' camera.
    rounds : int
        Rounds on the overlap after the first registration; 0 is :func:`~dgmm.registration.register_d2d`.
    solver : {"bfgs", "gauss-newton"}

    Returns
    -------
    Registration
        The last round's pose and cost (on the components it kept), ``iterations`` and ``seconds`` summed over
        the rounds.
    """
    registration = register_d2d(fixed, moving, solver=solver)
    iterations, seconds = registration.iterations, registration.seconds
    for _ in range(rounds):
        rotation, translation = registration.rotation, registration.translation
        # x_fixed = R x_moving + t: the fixed camera sees moving means moved by (R, t), and conversely.
        keep_fixed = seen_by(np.asarray(fixed.means_), rotation.T, -rotation.T @ translation, intrinsics)
        keep_moving = seen_by(np.asarray(moving.means_), rotation, translation, intrinsics)
        if not keep_fixed.any() or not keep_moving.any():
            break
        registration = register_d2d(_Components(fixed, keep_fixed), _Components(moving, keep_moving), rotation,
                                    translation, solver=solver)
        iterations, seconds = iterations + registration.iterations, seconds + registration.seconds
    return Registration(registration.rotation, registration.translation, iterations, seconds,
                        registration.objective, registration.converged, registration.method)
