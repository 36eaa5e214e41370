"""Frame-to-frame visual odometry with Gaussian mixtures on TUM RGB-D sequences (paper §V "Visual Odometry").

Files and poses follow ``dgmm.tum`` (camera → world, ``x_w = R x_c + t``), pixels ``dgmm.pixels``, the error
metrics ``dgmm.trajectory_metrics``. Odometry registers frame ``k+1`` (moving) onto frame ``k`` (fixed); the
transform returned maps camera ``k+1`` coordinates into camera ``k`` coordinates, i.e. the relative pose
``T_k⁻¹ T_{k+1}``, and the poses are composed from the identity at the first frame. Registration starts from the
identity, as in the paper.

Methods (paper §V): ``"gmm-pixels"`` fits a K=100 GMM (25 EM iterations) to per-pixel rectangle primitives and
registers with the determinant-free D2D cost; ``"gmm-points"`` does the same with the plain back-projected points;
``"icp"`` runs point-to-point ICP on 2,500 points drawn at random from each frame's back-projection.

EM start (``warm_iter``): the paper's protocol fits every frame from a k-means start (``max_iter`` iterations);
with ``warm_iter`` set, every frame after the first starts from the previous frame's mixture (its starved
components restarted on the data) and runs ``warm_iter`` iterations, several times cheaper since the camera moves
little between frames, at a cost in drift (fr1/xyz, first 100 frames: ATE 0.037 m at 5 iterations against the
protocol's 0.018 m).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from dgmm.errors import DataError, InputError
from dgmm.mixture import GaussianMixture
from dgmm.pixels import FR3, backproject, pixel_primitives
from dgmm.primitives import Primitives
from dgmm.registration import Registration, register_d2d, register_icp
from dgmm.tum import MAX_TIME_DIFFERENCE, Trajectory


# ---------------------------------------------------------------------------------------------- odometry
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


@dataclass(frozen=True)
class OdometryFrame:
    """What the odometry loop knows after a frame, handed to ``callback``.

    Attributes
    ----------
    index : int
        Frame index in the sequence.
    timestamp : float
    rotation : ndarray of shape (3, 3)
    translation : ndarray of shape (3,)
        The frame's estimated pose (camera → first camera).
    model : GaussianMixture or ndarray of shape (n_icp_points, 3)
        The frame's mixture, or its ICP points.
    prepare_seconds : float
        Time to build ``model`` (the GMM fit, or the sampling for ICP).
    registration : Registration or None
        This frame registered onto the previous one; None for the first frame.
    """

    index: int
    timestamp: float
    rotation: np.ndarray
    translation: np.ndarray
    model: object
    prepare_seconds: float
    registration: Registration | None


@dataclass(frozen=True)
class Odometry:
    """The result of ``run_odometry``.

    Attributes
    ----------
    method : str
    trajectory : Trajectory
        Estimated poses at the depth timestamps, the first one the identity.
    prepare_seconds : ndarray of shape (n_frames,)
        Per-frame model building time (GMM fit; point sampling for ICP).
    registration_seconds : ndarray of shape (n_frames - 1,)
        Per-frame registration time (``Registration.seconds``).
    registrations : tuple of Registration
        Frame ``k+1`` onto frame ``k``, ``n_frames - 1`` of them.
    cpu_seconds : ndarray of shape (n_frames,)
        Per-frame CPU time of this process (``time.process_time``) for the model and its registration: on a
        shared machine the wall times above count other processes' work too.
    """

    method: str
    trajectory: Trajectory
    prepare_seconds: np.ndarray
    registration_seconds: np.ndarray
    registrations: tuple
    cpu_seconds: np.ndarray


def run_odometry(sequence, method, frames=None, *, intrinsics=FR3, n_components=100, max_iter=25, warm_iter=None,
                 variant="textbook", size="area", n_icp_points=2500, seed=0, callback=None):
    """Frame-to-frame visual odometry over a TUM sequence (paper §V).

    Each frame's model is built once (a GMM, or ICP's random points) and registered onto the previous frame's
    from the identity; the relative motions are composed into poses.

    Parameters
    ----------
    sequence : dgmm.tum.TumSequence
    method : {"gmm-pixels", "gmm-points", "icp"}
    frames : array-like of int, optional
        Frame indices to use, in order (e.g. ``range(300)``); all frames when omitted.
    intrinsics : dgmm.pixels.Intrinsics, default=FR3
    n_components, max_iter : int
        GMM size and EM iterations from the k-means start (paper: K=100; 25 iterations).
    warm_iter : int, optional
        EM iterations of every frame after the first, started from the previous frame's mixture; None (the
        paper's protocol) fits every frame from its own k-means start.
    variant : {"textbook", "authors"}
        The EM (``dgmm.GaussianMixture``'s ``variant``).
    size : {"area", "unit"}
        Pixel primitive size for ``"gmm-pixels"`` (see ``dgmm.pixels.pixel_primitives``).
    n_icp_points : int
        Points drawn per frame for ``"icp"`` (paper: 2,500).
    seed : int
        Frame ``k`` draws its k-means initialisation or ICP sample from ``np.random.default_rng([seed, k])``.
    callback : callable, optional
        ``callback(frame)`` with an ``OdometryFrame`` after every frame (for logging).

    Returns
    -------
    Odometry

    Raises
    ------
    DataError
        A depth image is unreadable or not of the intrinsics' size (the message names the file).
    """
    if method not in METHODS:
        raise InputError(f"method must be one of {sorted(METHODS)}, got {method!r}")
    if warm_iter is not None and warm_iter < 1:
        raise InputError(f"warm_iter must be a positive number of EM iterations or None, got {warm_iter!r}")
    indices = np.arange(len(sequence)) if frames is None else np.asarray(frames, dtype=int)
    if len(indices) < 2 or indices.min() < 0 or indices.max() >= len(sequence):
        raise InputError(f"odometry needs at least 2 frame indices in 0..{len(sequence) - 1}")
    prepare, register = METHODS[method]
    options = {"n_components": n_components, "max_iter": max_iter, "warm_iter": warm_iter, "variant": variant,
               "size": size, "n_icp_points": n_icp_points}
    rotations, translations = [np.eye(3)], [np.zeros(3)]
    previous, prepare_seconds, registrations, cpu_seconds = None, [], [], []
    for index in indices:  # sequential by nature: each pose composes the previous one
        depth = sequence.depth(index)
        if depth.shape != (intrinsics.height, intrinsics.width):
            raise DataError(f"{sequence.depth_files[index]}: {depth.shape[1]}x{depth.shape[0]} image, the "
                            f"intrinsics are for {intrinsics.width}x{intrinsics.height}")
        start, cpu_start = time.perf_counter(), time.process_time()
        model = prepare(depth, intrinsics, np.random.default_rng([seed, int(index)]), previous, options)
        prepare_seconds.append(time.perf_counter() - start)
        registration = None if previous is None else register(previous, model)
        cpu_seconds.append(time.process_time() - cpu_start)
        if registration is not None:  # T_{k+1} = T_k (T_k⁻¹ T_{k+1})
            registrations.append(registration)
            translations.append(rotations[-1] @ registration.translation + translations[-1])
            rotations.append(rotations[-1] @ registration.rotation)
        if callback is not None:
            callback(OdometryFrame(int(index), float(sequence.depth_timestamps[index]), rotations[-1],
                                   translations[-1], model, prepare_seconds[-1], registration))
        previous = model
    trajectory = Trajectory(sequence.depth_timestamps[indices], np.array(rotations), np.array(translations))
    return Odometry(method, trajectory, np.array(prepare_seconds), np.array([r.seconds for r in registrations]),
                    tuple(registrations), np.array(cpu_seconds))


# ------------------------------------------------------------------------------------------------ tables
def first_frames(sequence, n_frames, max_difference=MAX_TIME_DIFFERENCE):
    """The first ``n_frames`` frames of a sequence (all of them when it is shorter) and their ground truth.

    Parameters
    ----------
    sequence : TumSequence
    n_frames : int
    max_difference : float

    Returns
    -------
    frames : ndarray of shape (n_used,)
        ``0, 1, …, min(n_frames, len(sequence)) − 1``.
    groundtruth : Trajectory
        Ground truth of those frames that have a partner within ``max_difference`` s, stamped with their depth
        timestamps.

    Raises
    ------
    DataError
        The sequence has no ``groundtruth.txt``, or fewer than 3 of the frames have a ground-truth pose (the ATE
        alignment would not be determined); the message names the file.
    """
    frames = np.arange(min(int(n_frames), len(sequence)))
    matched, poses = sequence.groundtruth_at_frames(max_difference)
    keep = matched < len(frames)
    if keep.sum() < 3:
        raise DataError(f"{sequence.folder / 'groundtruth.txt'}: only {int(keep.sum())} of the first {len(frames)} "
                        f"depth frames have a ground-truth pose within {max_difference} s")
    return frames, poses.subset(np.flatnonzero(keep))


def frame_seconds(odometry):
    """Per-frame timings of a run as table rows.

    Returns
    -------
    rows : list of dict
        One per frame: ``frame`` (position in the run), ``timestamp``, ``model_seconds`` (GMM fit, or ICP's
        point sample), ``registration_seconds`` (onto the previous frame; ``""`` for the first frame) and
        ``cpu_seconds`` (both, CPU time of this process).
    """
    registration = ["", *odometry.registration_seconds.tolist()]
    return [{"frame": index, "timestamp": f"{timestamp:.6f}", "model_seconds": float(model),
             "registration_seconds": registered, "cpu_seconds": float(cpu)}
            for index, (timestamp, model, registered, cpu) in enumerate(
                zip(odometry.trajectory.timestamps, odometry.prepare_seconds, registration, odometry.cpu_seconds))]


def seconds_summary(rows):
    """Mean timings of one run from its ``frame_seconds`` rows (numbers or the strings of a CSV file).

    Returns
    -------
    summary : dict
        ``frames``; ``mean_model_seconds`` (over frames), ``mean_registration_seconds`` (over registrations) and
        ``mean_seconds_per_frame``, their sum: the cost of adding one frame to the trajectory;
        ``mean_cpu_seconds_per_frame`` (over frames) when the rows have ``cpu_seconds``.
    """
    model = [float(row["model_seconds"]) for row in rows]
    registration = [float(row["registration_seconds"]) for row in rows if row["registration_seconds"] != ""]
    if not model or not registration:
        raise InputError(f"timings of {len(rows)} frames: need at least one registration")
    mean_model, mean_registration = float(np.mean(model)), float(np.mean(registration))
    summary = {"frames": len(model), "mean_seconds_per_frame": mean_model + mean_registration,
               "mean_model_seconds": mean_model, "mean_registration_seconds": mean_registration}
    if "cpu_seconds" in rows[0]:
        summary["mean_cpu_seconds_per_frame"] = float(np.mean([float(row["cpu_seconds"]) for row in rows]))
    return summary
