"""The one interface the odometry loop reads depth frames through, and opening a sequence of either kind.

Two readers implement :class:`DepthSequence`: a TUM RGB-D folder (:class:`dgmm.odometry.tum.TumSequence`) and a
ROS 2 recording in MCAP, a file or a bag folder (:class:`dgmm.odometry.ros2_mcap.McapSequence`). The loop, its
methods, schedules and EM variants, the metrics and the recorders see only this interface, so a run of either kind
gives the same outputs. Frames stream in increasing index order (a recording is read front to back, a few frames
in memory at a time); timestamps, the frame count and the ground truth are known before the first frame is read.
"""
from __future__ import annotations

from pathlib import Path
from typing import Iterator, Protocol

import numpy as np

from dgmm.errors import DataError, InputError
from dgmm.odometry.pixels import Intrinsics
from dgmm.odometry.tum import MAX_TIME_DIFFERENCE, Trajectory, associate, read_sequence


class DepthSequence(Protocol):
    """What the odometry loop, the command line and the workflow read of a depth sequence.

    Attributes
    ----------
    name : str
        Names the sequence in outputs (a TUM folder's name, a recording's file or bag folder name).
    depth_timestamps : ndarray of shape (n_frames,)
        Seconds, increasing.
    groundtruth : Trajectory or None
        Camera poses in the ground truth's world, at its own timestamps; None when there is none.
    groundtruth_file : pathlib.Path or None
        The TUM trajectory file ``groundtruth`` was read from (named in errors).
    camera_frame : str
        The depth camera's frame name, the child frame of the trajectory's ``FrameTransform`` messages (a
        recording's image ``frame_id``, so that Foxglove places the recording's images on the estimated path).
    """

    name: str
    depth_timestamps: np.ndarray
    groundtruth: Trajectory | None
    groundtruth_file: Path | None
    camera_frame: str

    def __len__(self) -> int:
        """Number of depth frames."""

    def depth_frames(self, indices) -> Iterator[np.ndarray]:
        """Depth images of the frames ``indices`` (increasing), one at a time, in metres, shape (height, width),
        0 where there is no measurement."""

    def frame_source(self, index) -> str:
        """Where frame ``index`` comes from (a file, or a recording's topic and message number), for errors."""

    def camera(self, intrinsics=None) -> tuple[str, Intrinsics]:
        """The depth camera: ``intrinsics`` (``fr1|fr2|fr3|ros|FX,FY,CX,CY``) for this sequence's image size when
        given, else the sequence's own; returned as (its text for outputs, the Intrinsics)."""


def open_sequence(path, depth_topic=None, camera_info_topic=None, groundtruth=None):
    """Open a TUM RGB-D folder, or a ROS 2 recording (an ``.mcap`` file or a bag folder with ``metadata.yaml``).

    Parameters
    ----------
    path : path-like
    depth_topic : str, optional
        The recording's depth image topic; required for a recording, not accepted for a TUM folder.
    camera_info_topic : str, optional
        The recording's ``sensor_msgs/msg/CameraInfo`` topic (see ``dgmm.odometry.ros2_mcap.read_recording``).
    groundtruth : path-like, optional
        A TUM trajectory file of ground-truth poses; a TUM folder's own ``groundtruth.txt`` otherwise.

    Returns
    -------
    DepthSequence

    Raises
    ------
    InputError
        A topic given for a TUM folder, or no depth topic for a recording.
    DataError
        The sequence cannot be read (the message names the file).
    """
    path = Path(path)
    if path.suffix == ".mcap" or (path / "metadata.yaml").is_file():
        if depth_topic is None:
            raise InputError(f"{path}: a ROS 2 recording needs its depth image topic (--depth-topic)")
        from dgmm.odometry.ros2_mcap import read_recording  # mcap and its ROS 2 decoder, only for recordings

        return read_recording(path, depth_topic, camera_info_topic, groundtruth=groundtruth)
    if depth_topic is not None or camera_info_topic is not None:
        raise InputError(f"{path}: topics are for ROS 2 recordings (.mcap or a bag folder), not TUM folders")
    return read_sequence(path, groundtruth=groundtruth)


def groundtruth_at_frames(sequence, max_difference=MAX_TIME_DIFFERENCE):
    """Frame indices with a ground-truth pose within ``max_difference`` s, and those poses.

    Parameters
    ----------
    sequence : DepthSequence
    max_difference : float

    Returns
    -------
    frames : ndarray of shape (n_pairs,)
    poses : Trajectory
        Of ``n_pairs`` rows, stamped with the depth timestamps.

    Raises
    ------
    DataError
        The sequence has no ground truth.
    """
    if sequence.groundtruth is None:
        raise DataError(f"{sequence.name}: no ground truth (no groundtruth.txt in a TUM folder, no trajectory file "
                        "given)")
    frames, rows = associate(sequence.depth_timestamps, sequence.groundtruth.timestamps, max_difference)
    poses = sequence.groundtruth.subset(rows)
    return frames, Trajectory(sequence.depth_timestamps[frames], poses.rotations, poses.translations)


def first_frames(sequence, n_frames, max_difference=MAX_TIME_DIFFERENCE, *, require_groundtruth=True):
    """The first ``n_frames`` frames of a sequence (all of them when it is shorter) and their ground truth.

    Parameters
    ----------
    sequence : DepthSequence
    n_frames : int
    max_difference : float
    require_groundtruth : bool, default=True
        False: a sequence without ground truth gives None for it (the odometry runs, unscored).

    Returns
    -------
    frames : ndarray of shape (n_used,)
        ``0, 1, …, min(n_frames, len(sequence)) − 1``.
    groundtruth : Trajectory or None
        Ground truth of those frames that have a partner within ``max_difference`` s, stamped with their depth
        timestamps.

    Raises
    ------
    DataError
        The sequence has no ground truth (unless not required), or fewer than 3 of the frames have a ground-truth
        pose (the ATE alignment would not be determined); the message names the file.
    """
    frames = np.arange(min(int(n_frames), len(sequence)))
    if sequence.groundtruth is None and not require_groundtruth:
        return frames, None
    matched, poses = groundtruth_at_frames(sequence, max_difference)
    keep = matched < len(frames)
    if keep.sum() < 3:
        raise DataError(f"{sequence.groundtruth_file}: only {int(keep.sum())} of the first {len(frames)} "
                        f"depth frames have a ground-truth pose within {max_difference} s")
    return frames, poses.subset(np.flatnonzero(keep))
