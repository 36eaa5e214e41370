"""JSON schemas of dgmm's own MCAP messages: run parameters and per-iteration, per-trial and per-frame outcomes.

No maintained type carries these (Foxglove's drawable types are in :mod:`dgmm.recording.foxglove_messages`), so
they are JSON with a JSON schema, which Foxglove plots directly (e.g. ``/fit/iteration.bound``).
"""

FIT_ITERATION_SCHEMA = {
    "title": "dgmm.FitIteration",
    "description": "One EM iteration of one seed's fit",
    "type": "object",
    "properties": {
        "seed": {"type": "integer"},
        "iteration": {"type": "integer", "minimum": 1},
        "bound": {"type": "number", "description": "Lower bound after this iteration (model.history_[-1])"},
        "seconds": {"type": "number", "minimum": 0,
                    "description": "Wall time since the seed's fit began, initialisation included"},
    },
    "required": ["seed", "iteration", "bound", "seconds"],
    "additionalProperties": False,
}

FIT_PARAMS_SCHEMA = {
    "title": "dgmm.FitParams",
    "description": "Parameters of the run (estimator settings, input, seeds), written once",
    "type": "object",
}

REGISTRATION_PARAMS_SCHEMA = {
    "title": "dgmm.RegistrationParams",
    "description": "Parameters of the run (model, method, trials, settings, bounding-box diagonal), written once",
    "type": "object",
}

REGISTRATION_TRIAL_SCHEMA = {
    "title": "dgmm.RegistrationTrial",
    "description": "Outcome of one registration trial",
    "type": "object",
    "properties": {
        "trial": {"type": "integer", "minimum": 0},
        "rotation_error_deg": {"type": "number", "minimum": 0},
        "translation_error_pct": {"type": "number", "minimum": 0,
                                  "description": "In percent of the bounding-box diagonal"},
        "iterations": {"type": "integer", "minimum": 0},
        "converged": {"type": "boolean"},
        "objective": {"type": "number", "description": "The method's final cost"},
        "seconds": {"type": "number", "minimum": 0, "description": "Wall time of the registration"},
        "centre": {"type": "array", "items": {"type": "number"}},
        "source_sha256": {"type": "string", "description": "Digest of the source points (float64, C order)"},
    },
    "required": ["trial", "rotation_error_deg", "translation_error_pct", "iterations", "converged", "objective",
                 "seconds", "centre", "source_sha256"],
    "additionalProperties": False,
}
"""One trial on ``/registration/trial``; its poses go to ``/registration/true_pose`` and
``/registration/estimated_pose`` at the same log time. ``centre`` is the point the translation error is
measured at (the source centroid)."""

ODOMETRY_PARAMS_SCHEMA = {
    "title": "dgmm.OdometryParams",
    "description": "Parameters of the run (sequence, method, frames, settings, seed), written once",
    "type": "object",
}

ODOMETRY_FRAME_SCHEMA = {
    "title": "dgmm.OdometryFrame",
    "description": "One frame of frame-to-frame odometry: its model and its registration onto the previous frame",
    "type": "object",
    "properties": {
        "index": {"type": "integer", "minimum": 0, "description": "Frame index in the sequence"},
        "timestamp": {"type": "number", "description": "Depth timestamp (s)"},
        "model_seconds": {"type": "number", "minimum": 0,
                          "description": "Time to build the frame's model (GMM fit, or ICP's point sample)"},
        "registration_seconds": {"type": ["number", "null"], "minimum": 0,
                                 "description": "Time to register onto the previous frame; null for the first"},
        "iterations": {"type": ["integer", "null"], "minimum": 0},
        "converged": {"type": ["boolean", "null"]},
        "objective": {"type": ["number", "null"]},
    },
    "required": ["index", "timestamp", "model_seconds", "registration_seconds", "iterations", "converged",
                 "objective"],
    "additionalProperties": False,
}
"""One frame on ``/odometry/frame``, logged at the frame's timestamp."""
