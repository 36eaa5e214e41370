"""D2D registration of two frames' mixtures restricted to what both cameras see (the views' overlap).

Under fast rotation a frame loses and gains a tenth of its view per frame. Each frame's mixture tiles its own view,
so on a plane that runs out of the image (a wall, the floor) the tiles of two frames end in different places, and
D2D slides one tiling along the plane to match the other: translation errors of 5-15 cm with the rotation right
(the synthetic room under rotation-only motion, ``benchmarks/studies/odometry_rotation_room.py``; noise-free renderings
fail alike, the same frames fitted on their common field of view do not). :func:`register_d2d_overlap` registers,
round by round, the components of each mixture whose mean the other camera sees at the pose found so far.
A coarse-to-fine schedule (both mixtures widened, then narrowed, as :mod:`dgmm.registration.coarse_to_fine` does for
P2D) finds the right basin where the first registration of the whole mixtures does not; widened without the overlap,
the same schedule only adds a bias (wide components match the views' whole extents). Whole components still keep
the tiles that straddle the other view's edge: :func:`register_d2d_common_view` then refits both frames on the
primitives the other camera sees and registers them from that pose; with two refits every frame of the room is
within 2.1 cm (three spins, both EMs), at about five times the fast schedule's CPU per frame.
"""
from __future__ import annotations

import numpy as np

from dgmm.errors import InputError
from dgmm.primitives import Primitives
from dgmm.registration import Registration, register_d2d
from dgmm.registration.coarse_to_fine import WidenedMixture, _check_scales


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
    u, v, front = intrinsics.project(means @ rotation.T + translation)
    return front & (u >= -0.5) & (u < intrinsics.width - 0.5) & (v >= -0.5) & (v < intrinsics.height - 0.5)


def centroid_and_radius(mixture):
    """The weighted centroid of a mixture's means, shape (3,), and their weighted RMS distance to it."""
    weights, means = np.asarray(mixture.weights_), np.asarray(mixture.means_)
    centroid = weights @ means / weights.sum()
    return centroid, float(np.sqrt(weights @ np.sum((means - centroid) ** 2, axis=1) / weights.sum()))


class _Components:
    """The fitted arrays of ``mixture`` (what D2D reads) restricted to the components ``keep``."""

    def __init__(self, mixture, keep):
        weights = np.asarray(mixture.weights_)[keep]
        self.weights_ = weights / weights.sum()
        self.means_ = np.asarray(mixture.means_)[keep]
        self.covariances_ = np.asarray(mixture.covariances_)[keep]
        self.precisions_cholesky_ = np.asarray(mixture.precisions_cholesky_)[keep]


def register_d2d_overlap(fixed, moving, intrinsics, rounds=3, scales=(0.0,), solver="gauss-newton", options=None):
    """D2D of two frames' mixtures (camera coordinates) on the components the other camera sees, round by round.

    Every round keeps the fixed mixture's components whose mean the moving camera sees at the current pose and
    the moving mixture's whose mean the fixed camera sees (:func:`seen_by`; weights renormalised) and registers
    them from that pose; the first round starts from the identity, where each camera sees (nearly) all of its own
    mixture. With ``scales`` the rounds run at each scale in turn on the kept components widened by
    ``(scale * radius)^2 I`` (``radius`` the moving mixture's weighted RMS radius about its weighted centroid), a
    coarse-to-fine schedule that ends on the mixtures themselves (or widened, for what registers them next). A
    round that would leave either mixture without a component ends the registration.

    Parameters
    ----------
    fixed, moving : fitted Gaussian mixture
        As for :func:`dgmm.registration.register_d2d`, in their cameras' coordinates.
    intrinsics : dgmm.odometry.pixels.Intrinsics
        Both frames' camera.
    rounds : int
        Rounds at each scale (at least 1).
    scales : sequence of float, default=(0.0,)
        Widening in RMS radii of the moving mixture, non-increasing; ending with 0 registers the mixtures
        themselves last, ending above 0 leaves that to what follows (the odometry's cut rounds).
    solver : {"bfgs", "gauss-newton"}
    options : dict, optional
        The solver's, for every round (:func:`dgmm.registration.register_d2d`).

    Returns
    -------
    Registration
        The last round's pose and cost (on the components it kept), ``iterations`` and ``seconds`` summed over
        the rounds.
    """
    if int(rounds) < 1:
        raise InputError(f"rounds must be at least 1, got {rounds!r}")
    scales = _check_scales(scales, end_at_zero=False)
    means = np.asarray(moving.means_)
    _, radius = centroid_and_radius(moving)
    rotation, translation, iterations, seconds, registration = np.eye(3), np.zeros(3), 0, 0.0, None
    for scale in scales:
        for _ in range(int(rounds)):
            # x_fixed = R x_moving + t: the fixed camera sees moving means moved by (R, t), and conversely.
            keep_fixed = seen_by(np.asarray(fixed.means_), rotation.T, -rotation.T @ translation, intrinsics)
            keep_moving = seen_by(means, rotation, translation, intrinsics)
            if not keep_fixed.any() or not keep_moving.any():
                break
            pair = _Components(fixed, keep_fixed), _Components(moving, keep_moving)
            if scale > 0:
                pair = tuple(WidenedMixture(mixture, (scale * radius) ** 2) for mixture in pair)
            registration = register_d2d(*pair, rotation, translation, options=options, solver=solver)
            rotation, translation = registration.rotation, registration.translation
            iterations, seconds = iterations + registration.iterations, seconds + registration.seconds
    if registration is None:
        raise InputError("register_d2d_overlap: neither camera sees a component of the other's mixture")
    return Registration(rotation, translation, iterations, seconds, registration.objective, registration.converged,
                        registration.method)


def register_d2d_common_view(fixed, moving, fit, intrinsics, refits=1, rounds=2, scales=(0.0,),
                             solver="gauss-newton"):
    """:func:`register_d2d_overlap`, then ``refits`` times both frames refitted on the primitives the other camera
    sees at the pose found so far and registered from it.

    Keeping whole components still keeps the tiles that straddle the other view's edge; refitting on the common
    view's primitives ends both tilings where the common view ends (on the synthetic room, the same frames refitted
    on the view common under the true motion register within 1.3 cm). A common view cut at a pose some
    centimetres off is itself a little off, so a second refit can still move the pose.

    Parameters
    ----------
    fixed, moving : (fitted Gaussian mixture, Primitives)
        Each frame's mixture and the primitives it was fitted to, in its camera's coordinates.
    fit : callable
        ``fit(primitives, frame)`` -> the mixture of ``primitives``, ``frame`` 0 (fixed) or 1 (moving).
    intrinsics : dgmm.odometry.pixels.Intrinsics
    refits : int
        Refits of both frames.
    rounds, scales, solver
        Of :func:`register_d2d_overlap`.

    Returns
    -------
    Registration
        The last registration's pose and cost (a refit is skipped, and the refits end, where either common view
        has fewer primitives than its mixture has components); ``iterations`` and ``seconds`` summed over the
        registrations (the refits' time is not in ``seconds``).
    """
    registration = register_d2d_overlap(fixed[0], moving[0], intrinsics, rounds, scales, solver)
    iterations, seconds = registration.iterations, registration.seconds
    for _ in range(int(refits)):
        rotation, translation = registration.rotation, registration.translation
        # x_fixed = R x_moving + t: the moving camera sees fixed primitives moved by (Rᵀ, -Rᵀ t), and conversely.
        views = ((fixed, rotation.T, -rotation.T @ translation), (moving, rotation, translation))
        keeps = [seen_by(prims.means, turn, shift, intrinsics) for (_, prims), turn, shift in views]
        if any(keep.sum() < len(mixture.weights_) for keep, (mixture, _) in zip(keeps, (fixed, moving))):
            break
        refitted = [fit(Primitives(prims.means[keep], prims.covariances[keep], prims.weights[keep]), frame)
                    for frame, (keep, (_, prims)) in enumerate(zip(keeps, (fixed, moving)))]
        registration = register_d2d(*refitted, rotation, translation, solver=solver)
        iterations, seconds = iterations + registration.iterations, seconds + registration.seconds
    return Registration(registration.rotation, registration.translation, iterations, seconds,
                        registration.objective, registration.converged, registration.method)
