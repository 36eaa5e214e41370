"""The per-frame model of each odometry method and how two frames' models are registered (paper §V).

Methods: ``"gmm-pixels"`` fits a K-component GMM to per-pixel rectangle primitives (:mod:`dgmm.odometry.pixels`)
and registers with the determinant-free D2D cost; ``"gmm-points"`` does the same with the plain back-projected
points; ``"icp"`` keeps 2,500 points drawn at random from each frame's back-projection for point-to-point ICP.

EM start (``warm_iter``): the paper's protocol fits every frame from a k-means start (``max_iter`` iterations);
with ``warm_iter`` set, every frame after the first starts from the previous frame's mixture (its starved
components restarted on the data) and runs ``warm_iter`` iterations, several times cheaper since the camera moves
little between frames, at a cost in drift (fr1/xyz, first 100 frames: ATE 0.037 m at 5 iterations against the
protocol's 0.018 m).
"""
from __future__ import annotations

import numpy as np

from dgmm.mixture import GaussianMixture
from dgmm.odometry.pixels import backproject, pixel_primitives
from dgmm.primitives import Primitives
from dgmm.registration import register_d2d, register_icp

STARVED_WEIGHT = 0.1
"""Warm start: a component of the previous frame's mixture whose weight is below ``STARVED_WEIGHT / K`` restarts."""


def _warm_start(mixture, prims, rng):
    """The previous frame's mixture as this frame's EM start, every starved component (weight below
    ``STARVED_WEIGHT / K``) restarted at a primitive drawn by size, with the live components' median covariance
    and weight ``1 / K``.

    Without the restart a component that loses its primitives (the scene leaves the view, or its neighbours win
    them) keeps a weight near 0 and the ``reg_covar`` covariance for good: on fr1/xyz the effective number of
    components ``1 / Σ π²`` falls from 79 to 7 within 55 frames and D2D loses its grip.
    """
    k = len(mixture.weights_)
    weights, means, covariances = mixture.weights_.copy(), mixture.means_.copy(), mixture.covariances_.copy()
    starved = weights < STARVED_WEIGHT / k
    if starved.any():
        picks = rng.choice(len(prims), size=int(starved.sum()), p=prims.weights / prims.weights.sum())
        means[starved] = prims.means[picks]
        covariances[starved] = np.median(covariances[~starved], axis=0)
        weights[starved] = 1.0 / k
        weights /= weights.sum()
    return weights, means, np.linalg.inv(covariances)


def _fit_mixture(prims, rng, previous, options):
    """The frame's K-component GMM: from a k-means start seeded by ``rng``, or from ``previous`` (warm start).

    ``previous`` is the previous frame's mixture or ``None`` (see :func:`_warm_start`).
    """
    common = dict(variant=options["variant"], random_state=rng)
    if previous is None or options["warm_iter"] is None:
        return GaussianMixture(options["n_components"], max_iter=options["max_iter"], **common).fit(prims)
    weights, means, precisions = _warm_start(previous, prims, rng)
    return GaussianMixture(options["n_components"], max_iter=options["warm_iter"], weights_init=weights,
                           means_init=means, precisions_init=precisions, **common).fit(prims)


def _prepare_pixels(depth, intrinsics, rng, previous, options):
    return _fit_mixture(pixel_primitives(depth, intrinsics, size=options["size"]), rng, previous, options)


def _prepare_points(depth, intrinsics, rng, previous, options):
    return _fit_mixture(Primitives.from_points(backproject(depth, intrinsics)), rng, previous, options)


def _prepare_icp(depth, intrinsics, rng, previous, options):
    points = backproject(depth, intrinsics)
    return points[rng.choice(len(points), size=min(options["n_icp_points"], len(points)), replace=False)]


def _register_icp(fixed, moving):
    return register_icp(moving, fixed)


# method -> (prepare(depth, intrinsics, rng, previous model, options) -> frame model,
#            register(fixed, moving) -> Registration)
METHODS = {
    "gmm-pixels": (_prepare_pixels, register_d2d),
    "gmm-points": (_prepare_points, register_d2d),
    "icp": (_prepare_icp, _register_icp),
}


MIXTURE_METHODS = ("gmm-pixels", "gmm-points")
"""The methods that fit a GMM per frame, and so run with an EM ``variant``."""


def odometry_runs(methods, variants):
    """The (method, variant) pairs of a sweep, named as its jobs' folders.

    Parameters
    ----------
    methods : sequence of str
        Keys of ``METHODS``.
    variants : sequence of str
        EM variants of the mixture methods (ICP has none).

    Returns
    -------
    runs : dict of str to (str, str)
        ``"gmm-pixels-textbook" -> ("gmm-pixels", "textbook")`` …, ``"icp" -> ("icp", "")``, in the given order.
    """
    return {f"{method}-{variant}" if variant else method: (method, variant)
            for method in methods for variant in (variants if method in MIXTURE_METHODS else [""])}
