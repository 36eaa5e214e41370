"""The odometry recorder: per-frame timings, poses and transforms and the trajectories to MCAP, the camera path,
each frame's depth image and model to rerun."""
import numpy as np
import rerun as rr

from dgmm.recording.blueprints import odometry_blueprint
from dgmm.recording.ellipsoids import DEFAULT_N_SIGMA
from dgmm.recording.foxglove_messages import frame_transform, pose_in_frame, poses_in_frame
from dgmm.recording.json_schemas import ODOMETRY_FRAME_SCHEMA, ODOMETRY_PARAMS_SCHEMA
from dgmm.recording.mcap_writer import McapWriter
from dgmm.recording.output import Recording
from dgmm.recording.rerun_recorder import RerunRecorder, rerun_ellipsoids

_GROUNDTRUTH_COLOR, _ESTIMATE_COLOR = (40, 170, 80), (255, 140, 0)


def _ns(seconds):
    """Integer nanoseconds of a timestamp in seconds."""
    return int(round(float(seconds) * 1e9))


class OdometryRecorder(Recording):
    """Callback of ``dgmm.odometry.run_odometry`` that records a visual-odometry run to MCAP and to rerun.

    Poses are camera → frame ``x -> R x + t`` (``dgmm.odometry`` conventions). The estimate lives in the frame
    ``"odometry"`` (the first camera); ``"world"`` is the ground truth's frame. For display, the estimate is also
    drawn anchored at the first frame's ground-truth pose, ``T_world = G_0 T_odometry`` (evo's origin alignment),
    so both paths start together and the drift is visible.

    MCAP topics, log times = frame timestamps (the input's own: a recording's header stamps, so that Foxglove shows
    this file beside the input in step): ``/odometry/params`` (once, at the first frame, JSON), per frame
    ``/odometry/frame`` (JSON, :data:`ODOMETRY_FRAME_SCHEMA`), ``/odometry/pose`` (``foxglove.PoseInFrame``, frame
    ``"odometry"``) and ``/odometry/transforms`` (``foxglove.FrameTransform`` from ``"odometry"`` to
    ``camera_frame``, the frame the input's images are in, so Foxglove places them on the path; with ground truth,
    once before them, ``"world"`` to ``"odometry"``: the anchor), and at the last frame's time
    ``foxglove.PosesInFrame`` messages holding every pose: ``/odometry/estimated`` (frame ``"odometry"``, the
    poses of the trajectory file), ``/odometry/estimated_in_world`` (anchored, frame ``"world"``) and
    ``/odometry/groundtruth`` (frame ``"world"``, the ground truth at the recorded frames, when given).

    rerun entities (``world`` is z-up, as TUM's and the synthetic ground truth are): ``world/groundtruth`` (static
    line strip), and on the sequence timeline ``frame`` and the timestamp timeline ``timestamp`` (the input's
    clock): ``world/estimated`` (the anchored path so far), ``world/camera`` (its pose), ``world/camera/image``
    (the pinhole, static, and each frame's depth image at every ``pixel_step``-th pixel, in millimetres),
    ``world/camera/model`` (the frame's mixture as ellipsoids in camera coordinates, or ICP's points),
    ``seconds/model`` and ``seconds/registration``.

    Parameters
    ----------
    mcap_path : str or path-like
    rrd_path : str or path-like, optional
    params : dict, optional
        Written to ``/odometry/params``.
    groundtruth : dgmm.odometry.Trajectory, optional
        Ground truth at the frames that will be recorded, in frame order; its first pose anchors the display.
    intrinsics : dgmm.odometry.Intrinsics, optional
        Drawn as the camera's pinhole.
    camera_frame : str, default="camera"
        The depth camera's frame name (``DepthSequence.camera_frame``).
    n_sigma : float, default=2.0
    pixel_step : int, default=1
        The depth images are logged at every ``pixel_step``-th pixel (``dgmm.odometry.pixels.PIXEL_STEP``: as the
        odometry samples them).

    Examples
    --------
    >>> with OdometryRecorder("odometry.mcap", "odometry.rrd", groundtruth=truth,
    ...                       pixel_step=PIXEL_STEP) as recorder:  # doctest: +SKIP
    ...     result = run_odometry(sequence, "gmm-pixels", frames, callback=recorder)
    ...     recorder.finish(result.trajectory)
    """

    def __init__(self, mcap_path, rrd_path=None, *, params=None, groundtruth=None, intrinsics=None,
                 camera_frame="camera", n_sigma=DEFAULT_N_SIGMA, pixel_step=1):
        self._step = pixel_step
        self.n_sigma = n_sigma
        self.groundtruth = groundtruth
        self.camera_frame = camera_frame
        self._params = params or {}
        if groundtruth is not None and len(groundtruth):
            self._anchor = (np.asarray(groundtruth.rotations[0]), np.asarray(groundtruth.translations[0]))
        else:
            self._anchor = (np.eye(3), np.zeros(3))
        self._path = []
        self._last_time = 0
        self._mcap = self._rerun = None
        try:  # Ctrl-C at any point of this leaves no file behind
            self._mcap = McapWriter(mcap_path)
            if rrd_path is not None:
                self._rerun = RerunRecorder(rrd_path, n_sigma=n_sigma, blueprint=odometry_blueprint())
                self._rerun.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP)
                if groundtruth is not None:
                    self._rerun.log("world/groundtruth", rr.LineStrips3D([groundtruth.translations],
                                                                         colors=_GROUNDTRUTH_COLOR))
                if intrinsics is not None:  # the pinhole of the images logged: every pixel_step-th pixel
                    step = self._step
                    self._rerun.log("world/camera/image", rr.Pinhole(
                        focal_length=[intrinsics.fx / step, intrinsics.fy / step],
                        principal_point=[intrinsics.cx / step, intrinsics.cy / step],
                        resolution=[-(-intrinsics.width // step), -(-intrinsics.height // step)],
                        camera_xyz=rr.ViewCoordinates.RDF, image_plane_distance=0.2))
        except BaseException:
            self.abort()
            raise

    def _in_world(self, rotation, translation):
        """The anchored pose ``G_0 T`` of an odometry-frame pose."""
        anchor_rotation, anchor_translation = self._anchor
        return anchor_rotation @ rotation, anchor_rotation @ translation + anchor_translation

    def __call__(self, frame):
        """Record one frame (``run_odometry``'s ``callback``).

        Parameters
        ----------
        frame : dgmm.odometry.OdometryFrame
        """
        registration = frame.registration
        self._last_time = _ns(frame.timestamp)
        self._write_params()
        message = {"index": frame.index, "timestamp": frame.timestamp, "model_seconds": frame.prepare_seconds,
                   "registration_seconds": frame.registration_seconds,
                   "iterations": None if registration is None else int(registration.iterations),
                   "converged": None if registration is None else bool(registration.converged),
                   "objective": None if registration is None else float(registration.objective)}
        self._mcap.write("/odometry/frame", message, ODOMETRY_FRAME_SCHEMA, self._last_time)
        self._mcap.write("/odometry/pose", pose_in_frame(frame.rotation, frame.translation,
                                                         log_time_ns=self._last_time, frame_id="odometry"),
                         log_time_ns=self._last_time)
        self._mcap.write("/odometry/transforms", frame_transform(
            frame.rotation, frame.translation, log_time_ns=self._last_time, parent_frame_id="odometry",
            child_frame_id=self.camera_frame), log_time_ns=self._last_time)
        if self._rerun is None:
            return
        rotation, translation = self._in_world(frame.rotation, frame.translation)
        self._path.append(translation)
        self._rerun.set_timestamp(frame.timestamp)
        log = self._rerun.log
        if frame.depth is not None:
            millimetres = np.rint(1000.0 * frame.depth[::self._step, ::self._step]).clip(0, 65535).astype(np.uint16)
            log("world/camera/image", rr.DepthImage(millimetres, meter=1000.0), frame.index, "frame")
        log("world/estimated", rr.LineStrips3D([np.array(self._path)], colors=_ESTIMATE_COLOR), frame.index,
            "frame")
        log("world/camera", rr.Transform3D(translation=translation, mat3x3=rotation), frame.index, "frame")
        if hasattr(frame.model, "means_"):
            shown = rerun_ellipsoids(frame.model.means_, frame.model.covariances_, self.n_sigma)
        else:
            shown = rr.Points3D(np.asarray(frame.model), colors=_ESTIMATE_COLOR, radii=0.005)
        log("world/camera/model", shown, frame.index, "frame")
        log("seconds/model", rr.Scalars(frame.prepare_seconds), frame.index, "frame")
        if registration is not None:
            log("seconds/registration", rr.Scalars(frame.registration_seconds), frame.index, "frame")

    def _write_params(self):
        """``/odometry/params`` at the first frame's time, once; with ground truth, the anchor transform too."""
        if self._params is None:
            return
        self._mcap.write("/odometry/params", self._params, ODOMETRY_PARAMS_SCHEMA, self._last_time)
        if self.groundtruth is not None:
            self._mcap.write("/odometry/transforms", frame_transform(
                *self._anchor, log_time_ns=self._last_time, parent_frame_id="world", child_frame_id="odometry"),
                log_time_ns=self._last_time)
        self._params = None

    def finish(self, trajectory):
        """Write the whole estimated trajectory (and the ground truth) as ``foxglove.PosesInFrame`` messages.

        Parameters
        ----------
        trajectory : dgmm.odometry.Trajectory
            The run's estimate (``Odometry.trajectory``).
        """
        self._write_params()
        rotations, translations = np.asarray(trajectory.rotations), np.asarray(trajectory.translations)
        anchor_rotation, anchor_translation = self._anchor
        world = (anchor_rotation @ rotations, translations @ anchor_rotation.T + anchor_translation)
        messages = [("/odometry/estimated", (rotations, translations), "odometry"),
                    ("/odometry/estimated_in_world", world, "world")]
        if self.groundtruth is not None:
            messages.append(("/odometry/groundtruth", (self.groundtruth.rotations, self.groundtruth.translations),
                             "world"))
        for topic, (r, t), frame_id in messages:
            self._mcap.write(topic, poses_in_frame(r, t, log_time_ns=self._last_time, frame_id=frame_id),
                             log_time_ns=self._last_time)
