"""Record fits, registrations and odometry to MCAP (for Foxglove) and to rerun (``.rrd``) through callbacks.

The core estimator knows nothing of this package: it calls ``callback(iteration, model)`` after every EM
iteration (iteration = 1, 2, ...) with ``model.weights_ (n_components,)``, ``model.means_ (n_components, 3)``,
``model.covariances_ (n_components, 3, 3)`` and ``model.history_`` (the bound after each iteration so far).

One concept per module:

- :mod:`~dgmm.recording.ellipsoids`: a mixture's covariances as ellipsoids, shared by both formats.
- :mod:`~dgmm.recording.foxglove_messages`: ``foxglove.SceneUpdate`` and ``foxglove.PosesInFrame`` messages,
  built with Foxglove's maintained protobuf types.
- :mod:`~dgmm.recording.json_schemas`: JSON schemas of dgmm's own messages (parameters, per-iteration,
  per-trial and per-frame outcomes).
- :mod:`~dgmm.recording.mcap_writer`: :class:`McapWriter`, both kinds of message in one MCAP file, with
  deterministic log times.
- :mod:`~dgmm.recording.rerun_recorder`: :class:`RerunRecorder`, a rerun recording of one fit.
- :mod:`~dgmm.recording.blueprints`: the layout every ``.rrd`` opens with.
- :mod:`~dgmm.recording.fit_recorder`, :mod:`~dgmm.recording.registration_recorder`,
  :mod:`~dgmm.recording.odometry_recorder`: the callbacks the workflow and the CLI pass to the estimator,
  ``dgmm.experiments.trials.run_trials`` and ``dgmm.odometry.run_odometry``.

Every file is written under a temporary name beside its target and renamed on a clean close, so a failed job
leaves no partial output (:mod:`~dgmm.recording.output`).
"""
from dgmm.errors import needs

with needs("recording"):  # rerun, mcap and Foxglove's protobuf types, imported by every recorder
    from dgmm.recording.blueprints import fit_blueprint, odometry_blueprint, registration_blueprint
    from dgmm.recording.ellipsoids import DEFAULT_N_SIGMA, covariance_ellipsoids
    from dgmm.recording.fit_recorder import FitRecorder
    from dgmm.recording.foxglove_messages import ellipsoid_scene_update, poses_in_frame
    from dgmm.recording.json_schemas import (FIT_ITERATION_SCHEMA, FIT_PARAMS_SCHEMA, ODOMETRY_FRAME_SCHEMA,
                                             ODOMETRY_PARAMS_SCHEMA, REGISTRATION_PARAMS_SCHEMA,
                                             REGISTRATION_TRIAL_SCHEMA)
    from dgmm.recording.mcap_writer import TICK_NS, McapWriter
    from dgmm.recording.odometry_recorder import OdometryRecorder
    from dgmm.recording.registration_recorder import RegistrationRecorder
    from dgmm.recording.rerun_recorder import RerunRecorder, rerun_ellipsoids

__all__ = [
    "DEFAULT_N_SIGMA", "FIT_ITERATION_SCHEMA", "FIT_PARAMS_SCHEMA", "ODOMETRY_FRAME_SCHEMA", "ODOMETRY_PARAMS_SCHEMA",
    "REGISTRATION_PARAMS_SCHEMA", "REGISTRATION_TRIAL_SCHEMA", "TICK_NS", "FitRecorder", "McapWriter",
    "OdometryRecorder", "RegistrationRecorder", "RerunRecorder", "covariance_ellipsoids", "ellipsoid_scene_update",
    "fit_blueprint", "odometry_blueprint", "poses_in_frame", "registration_blueprint", "rerun_ellipsoids",
]
