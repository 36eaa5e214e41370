"""The registration recorder: every trial's poses and errors to MCAP, chosen trials iteration by iteration to
rerun."""
import hashlib

import numpy as np
import rerun as rr

from dgmm.errors import InputError
from dgmm.recording.blueprints import registration_blueprint
from dgmm.recording.ellipsoids import DEFAULT_N_SIGMA
from dgmm.recording.foxglove_messages import ellipsoid_scene_update, poses_in_frame
from dgmm.recording.json_schemas import REGISTRATION_PARAMS_SCHEMA, REGISTRATION_TRIAL_SCHEMA
from dgmm.recording.mcap_writer import McapWriter
from dgmm.recording.output import Recording
from dgmm.recording.rerun_recorder import RerunRecorder, rerun_ellipsoids

_TRUTH_COLOR, _SOURCE_COLOR, _TARGET_COLOR = (160, 160, 160), (255, 140, 0), (40, 170, 80)


class RegistrationRecorder(Recording):
    """Callback that records registration trials: all to one MCAP file, chosen trials iteration by iteration to
    rerun.

    MCAP topics: ``/registration/params`` (once, :data:`REGISTRATION_PARAMS_SCHEMA`), ``/registration/mixture``
    (once, the target mixture as ellipsoids, when given), and per trial, at one log time,
    ``/registration/trial`` (:data:`REGISTRATION_TRIAL_SCHEMA`), ``/registration/true_pose`` and
    ``/registration/estimated_pose`` (``foxglove.PosesInFrame``, one pose each, in the model's frame ``"model"``):
    the pose of the moved source, that is the trial's motion, and the inverse of the registration that should
    undo it. A perfect registration puts both poses on top of each other.

    rerun entities: ``mixture`` (static ellipsoids, when given) and, for each recorded trial ``i``,
    ``trial-i/truth`` (static: the source points where they belong), ``trial-i/target`` (static: the target
    points of point-to-point methods), ``trial-i/source`` (the moved source points as the registration moves
    them, from iteration 0, the trial's start) and ``trial-i/objective`` (the method's cost), both on the
    timeline ``iteration``.

    Parameters
    ----------
    mcap_path : str or path-like
    rrd_path : str or path-like, optional
        Where to write the rerun recording; none if omitted.
    params : dict, optional
        Run parameters written to ``/registration/params``.
    mixture : object, optional
        The target mixture (``means_``, ``covariances_``), drawn as ellipsoids.
    recorded_trials : collection of int, default=()
        Trials whose iterations go to rerun.
    n_sigma : float, default=2.0

    Examples
    --------
    >>> with RegistrationRecorder("trials.mcap", "trials.rrd", mixture=gmm, recorded_trials={0}) as rec:
    ...     callback = rec.begin_trial(0, trial, source)                          # doctest: +SKIP
    ...     result = register_p2d(trial.apply(source), gmm, callback=callback)
    ...     rec.end_trial(result, *registration_errors(result, trial, diagonal))
    """

    def __init__(self, mcap_path, rrd_path=None, *, params=None, mixture=None, recorded_trials=(),
                 n_sigma=DEFAULT_N_SIGMA):
        self.n_sigma = n_sigma
        self.recorded_trials = frozenset(int(index) for index in recorded_trials)
        self._trial = None
        self._mcap = self._rerun = None
        try:  # Ctrl-C at any point of this leaves no file behind
            self._mcap = McapWriter(mcap_path)
            self._mcap.write("/registration/params", params or {}, REGISTRATION_PARAMS_SCHEMA)
            if mixture is not None:
                self._mcap.write("/registration/mixture", ellipsoid_scene_update(
                    mixture.means_, mixture.covariances_, log_time_ns=self._mcap.next_log_time(),
                    n_sigma=n_sigma, frame_id="model"))
            if rrd_path is not None:
                self._rerun = RerunRecorder(rrd_path, n_sigma=n_sigma,
                                            blueprint=registration_blueprint(self.recorded_trials))
                if mixture is not None:
                    self._rerun.log("mixture", rerun_ellipsoids(mixture.means_, mixture.covariances_, n_sigma))
        except BaseException:
            self.abort()
            raise

    def begin_trial(self, index, trial, source, target=None):
        """Start trial ``index``; return the per-iteration callback for the registration, or None.

        Parameters
        ----------
        index : int
        trial : dgmm.registration.RigidTrial
            The motion applied to ``source``.
        source : array-like of shape (n_points, 3)
            The source points before the trial's motion.
        target : array-like of shape (n_target, 3), optional
            Target points of a point-to-point method, drawn in rerun.

        Returns
        -------
        callback : callable or None
            ``callback(iteration, registration)`` when trial ``index`` is recorded to rerun, else None (so
            unrecorded trials are timed without logging).
        """
        if self._trial is not None:
            raise InputError(f"begin_trial({index}) called before end_trial() of trial {self._trial[0]}")
        source = np.ascontiguousarray(source, dtype=np.float64)
        moved = trial.apply(source)
        self._trial = (int(index), trial, source, moved)
        if self._rerun is None or int(index) not in self.recorded_trials:
            return None
        self._rerun.log(f"trial-{index}/truth", rr.Points3D(source, colors=_TRUTH_COLOR))
        if target is not None:
            self._rerun.log(f"trial-{index}/target", rr.Points3D(np.asarray(target), colors=_TARGET_COLOR))
        self._rerun.log(f"trial-{index}/source", rr.Points3D(moved, colors=_SOURCE_COLOR), iteration=0)
        return self

    def __call__(self, iteration, registration):
        """Log the current trial's moved source points at ``iteration`` (the registration ``callback``).

        Parameters
        ----------
        iteration : int
            From 1.
        registration : dgmm.registration.Registration
            The current estimate, from the trial-moved points back onto the model.
        """
        if self._trial is None:
            raise InputError("RegistrationRecorder called before begin_trial()")
        index, _, _, moved = self._trial
        self._rerun.log(f"trial-{index}/source", rr.Points3D(registration.apply(moved), colors=_SOURCE_COLOR),
                        iteration=iteration)
        self._rerun.log(f"trial-{index}/objective", rr.Scalars(registration.objective), iteration=iteration)

    def end_trial(self, result, rotation_error_deg, translation_error_pct):
        """Write the current trial's outcome and its true and estimated poses.

        Parameters
        ----------
        result : dgmm.registration.Registration
            The final estimate.
        rotation_error_deg, translation_error_pct : float
            The trial's errors (``dgmm.registration.registration_errors``).
        """
        if self._trial is None:
            raise InputError("end_trial() called before begin_trial()")
        index, trial, source, _ = self._trial
        log_time = self._mcap.next_log_time()
        message = {"trial": index, "rotation_error_deg": float(rotation_error_deg),
                   "translation_error_pct": float(translation_error_pct), "iterations": int(result.iterations),
                   "converged": bool(result.converged), "objective": float(result.objective),
                   "seconds": float(result.seconds), "centre": trial.centre,
                   "source_sha256": hashlib.sha256(source.tobytes()).hexdigest()}
        self._mcap.write("/registration/trial", message, REGISTRATION_TRIAL_SCHEMA, log_time)
        # The trial x -> R (x - c) + c + t is the global pose (R, c + t - R c) of the moved source.
        true_translation = trial.centre + trial.translation - trial.rotation @ trial.centre
        inverse_rotation = result.rotation.T
        poses = {"true_pose": (trial.rotation, true_translation),
                 "estimated_pose": (inverse_rotation, -inverse_rotation @ result.translation)}
        for name, (rotation, translation) in poses.items():
            self._mcap.write(f"/registration/{name}", poses_in_frame(
                rotation[None], translation[None], log_time_ns=log_time, frame_id="model"), log_time_ns=log_time)
        self._trial = None
