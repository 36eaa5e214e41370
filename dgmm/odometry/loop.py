"""The frame-to-frame odometry loop over a depth sequence (paper §VI-D "Visual Odometry"), and its timings.

The sequence is a TUM RGB-D folder or a ROS 2 recording, read through one interface
(:class:`dgmm.odometry.sequence.DepthSequence`), frame by frame. Poses follow :mod:`dgmm.odometry.tum`
(camera → world, ``x_w = R x_c + t``), the frames' models and
their registration :mod:`dgmm.odometry.frame_model`. Odometry registers frame ``k+1`` (moving) onto frame ``k``
(fixed); the transform returned maps camera ``k+1`` coordinates into camera ``k`` coordinates, i.e. the relative
pose ``T_k⁻¹ T_{k+1}``, and the poses are composed from the identity at the first frame. Registration starts from
the identity, as in the paper.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from dgmm.errors import DataError, InputError
from dgmm.odometry.frame_model import METHODS, Schedule
from dgmm.odometry.pixels import FR3
from dgmm.odometry.protocols import PROTOCOLS, check_protocol
from dgmm.odometry.schedule_studies import schedule_named
from dgmm.odometry.tum import Trajectory
from dgmm.registration import Registration


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
    registration_seconds : float or None
        Time of that registration, all of it (a schedule's rounds and cuts; ``registration.seconds`` counts only
        its solvers' time).
    depth : ndarray of shape (height, width) or None
        The frame's depth image in metres (what the rerun recording shows under the camera path).
    """

    index: int
    timestamp: float
    rotation: np.ndarray
    translation: np.ndarray
    model: object
    prepare_seconds: float
    registration: Registration | None
    registration_seconds: float | None
    depth: np.ndarray | None = None


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
        Per-frame registration time, all of it (a schedule's rounds and cuts; ``Registration.seconds`` counts only
        its solvers' time).
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


def run_odometry(sequence, method, frames=None, *, intrinsics=FR3, n_components=100, schedule="overlap", warm_iter=None,
                 variant="textbook", size="area", covariance="patch", protocol="ours", n_icp_points=2500, icp_tol=1e-9,
                 seed=0, callback=None):
    """Frame-to-frame visual odometry over a depth sequence (paper §VI-D).

    Each frame's model is built once (a GMM, or ICP's random points) and registered onto the previous frame's
    from the identity; the relative motions are composed into poses.

    Parameters
    ----------
    sequence : dgmm.odometry.sequence.DepthSequence
        A TUM folder (``dgmm.odometry.tum.read_sequence``) or a ROS 2 recording
        (``dgmm.odometry.ros2_mcap.read_recording``); its frames are read one at a time.
    method : {"gmm-pixels", "gmm-points", "icp"}
    frames : array-like of int, optional
        Frame indices to use, increasing (e.g. ``range(300)``); all frames when omitted.
    intrinsics : dgmm.odometry.pixels.Intrinsics, default=FR3
    n_components : int
        GMM size (paper: K=100).
    schedule : str or Schedule, default="overlap"
        How each frame's GMM starts and iterates and which D2D solver registers it: a ``Schedule``, or its name in
        ``dgmm.odometry.frame_model.SCHEDULES`` or the studies' (``dgmm.odometry.schedule_studies``).
    warm_iter : int, optional
        EM iterations of every frame after the first, started from the previous frame's mixture; None fits every
        frame from its own start, by ``schedule``.
    variant : {"textbook", "authors"}
        The EM (``dgmm.GaussianMixture``'s ``variant``).
    size : {"area", "unit"}
        Pixel primitive size for ``"gmm-pixels"`` (see ``dgmm.odometry.pixels.pixel_primitives``).
    covariance : {"patch", "disparity"}
        Pixel primitive covariance for ``"gmm-pixels"`` (``dgmm.odometry.pixel_covariance``).
    protocol : str, default="ours"
        A key of ``dgmm.odometry.protocols.PROTOCOLS``: ``"ours"`` runs with the arguments above; another
        protocol (``"ours-unit"`` and ``"authors-disparity"``: gmm-pixels; ``"authors-patch"``: gmm-pixels and
        gmm-points) replaces ``size`` and ``covariance`` with its own, and ``schedule`` where it has one
        (``variant`` is one algorithm on its unit sizes).
    n_icp_points : int
        Points drawn per frame for ``"icp"`` (paper: 2,500).
    icp_tol : float
        ICP stops when the mean matching distance changes by less (metres; ``dgmm.registration.register_icp``).
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
        A depth image is unreadable or not of the intrinsics' size (the message names the file or message).
    """
    if method not in METHODS:
        raise InputError(f"method must be one of {sorted(METHODS)}, got {method!r}")
    settings = PROTOCOLS[check_protocol(protocol)]
    if settings is not None:
        if method not in settings.methods:
            raise InputError(f"protocol {protocol!r} applies to {', '.join(settings.methods)}, not {method!r}")
        schedule, size, covariance = settings.schedule or schedule, settings.size, settings.covariance
    if not isinstance(schedule, Schedule):
        schedule = schedule_named(schedule)
    if warm_iter is not None and warm_iter < 1:
        raise InputError(f"warm_iter must be a positive number of EM iterations or None, got {warm_iter!r}")
    indices = np.arange(len(sequence)) if frames is None else np.asarray(frames, dtype=int)
    if len(indices) < 2 or indices.min() < 0 or indices.max() >= len(sequence) or np.any(np.diff(indices) <= 0):
        raise InputError(f"odometry needs at least 2 increasing frame indices in 0..{len(sequence) - 1}")
    prepare, register = METHODS[method]
    options = {"n_components": n_components, "warm_iter": warm_iter, "schedule": schedule, "variant": variant,
               "size": size, "covariance": covariance, "n_icp_points": n_icp_points, "icp_tol": icp_tol,
               "intrinsics": intrinsics}
    rotations, translations = [np.eye(3)], [np.zeros(3)]
    previous, prepare_seconds, registrations, registration_seconds, cpu_seconds = None, [], [], [], []
    # sequential by nature: each pose composes the previous one; frames stream from the sequence one at a time
    for index, depth in zip(indices, sequence.depth_frames(indices), strict=True):
        if depth.shape != (intrinsics.height, intrinsics.width):
            raise DataError(f"{sequence.frame_source(index)}: {depth.shape[1]}x{depth.shape[0]} image, the "
                            f"intrinsics are for {intrinsics.width}x{intrinsics.height}")
        start, cpu_start = time.perf_counter(), time.process_time()
        model = prepare(depth, intrinsics, np.random.default_rng([seed, int(index)]), previous, options)
        prepared = time.perf_counter()
        registration = None if previous is None else register(previous, model, options)
        registered = time.perf_counter()
        cpu_seconds.append(time.process_time() - cpu_start)
        prepare_seconds.append(prepared - start)
        if registration is not None:  # T_{k+1} = T_k (T_k⁻¹ T_{k+1})
            registrations.append(registration)
            registration_seconds.append(registered - prepared)
            translations.append(rotations[-1] @ registration.translation + translations[-1])
            rotations.append(rotations[-1] @ registration.rotation)
        if callback is not None:
            callback(OdometryFrame(int(index), float(sequence.depth_timestamps[index]), rotations[-1],
                                   translations[-1], model, prepare_seconds[-1], registration,
                                   registration_seconds[-1] if registration is not None else None, depth))
        previous = model
    trajectory = Trajectory(sequence.depth_timestamps[indices], np.array(rotations), np.array(translations))
    return Odometry(method, trajectory, np.array(prepare_seconds), np.array(registration_seconds),
                    tuple(registrations), np.array(cpu_seconds))


# ------------------------------------------------------------------------------------------------ timings
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
