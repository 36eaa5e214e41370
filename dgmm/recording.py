"""Record fits to MCAP (for Foxglove) and to rerun (``.rrd``) through the estimator's ``callback``.

The core estimator knows nothing of this module: it calls ``callback(iteration, model)`` after every EM
iteration (iteration = 1, 2, ...) with ``model.weights_ (n_components,)``, ``model.means_ (n_components, 3)``,
``model.covariances_ (n_components, 3, 3)`` and ``model.history_`` (the bound after each iteration so far).

- :class:`McapWriter` writes JSON-encoded messages, each channel with a JSON schema, with deterministic log
  times (message ``n`` of the file is logged at ``n * TICK_NS`` nanoseconds), so the same messages give the
  same bytes.
- :class:`RerunRecorder` writes a rerun recording: the input (static), the mixture as ellipsoids and the bound
  as a scalar series, both on the sequence timeline ``iteration``.
- :class:`FitRecorder` is the callback the workflow passes to the estimator: every seed's bound and wall time
  per iteration and its final mixture go to one MCAP file, the first seed's iterations to rerun.
- :class:`RegistrationRecorder` does the same for registration trials (``dgmm.trials.run_trials``): every
  trial's true and estimated pose and errors to MCAP, the source points of chosen trials moving iteration by
  iteration to rerun (registration methods call ``callback(iteration, registration)``).
- :class:`OdometryRecorder` is ``dgmm.odometry.run_odometry``'s ``callback``: per-frame timings and the estimated
  and ground-truth trajectories to MCAP, the camera path and each frame's mixture to rerun on the ``frame``
  timeline.

Every file is written under a temporary name beside its target and renamed on a clean close, so a failed job
leaves no partial output. Ellipsoids come from :func:`covariance_ellipsoids`, shared by both writers.
"""
import hashlib
import json
import os
import time
from pathlib import Path

import numpy as np
import rerun as rr
from mcap.writer import Writer
from scipy.spatial.transform import Rotation

from dgmm.errors import InputError
from dgmm.files import temporary_path

TICK_NS = 1_000_000
"""Log-time step between consecutive MCAP messages, in nanoseconds (1 ms, counted from the Unix epoch)."""

DEFAULT_N_SIGMA = 2.0
"""Ellipsoids are drawn at this many standard deviations along each principal axis."""


# ---------------------------------------------------------------------------------------------------------
# Ellipsoid math, shared by both writers
# ---------------------------------------------------------------------------------------------------------

def covariance_ellipsoids(covariances, n_sigma=DEFAULT_N_SIGMA):
    """Principal axes of covariance ellipsoids as proper rotations and half-sizes.

    ``covariances[i] = rotations[i] @ diag((half_sizes[i] / n_sigma) ** 2) @ rotations[i].T``.

    Parameters
    ----------
    covariances : array-like of shape (n_components, 3, 3)
        Symmetric positive semi-definite matrices.
    n_sigma : float, default=2.0
        Number of standard deviations the half-sizes span.

    Returns
    -------
    rotations : ndarray of shape (n_components, 3, 3)
        Columns are the principal axes (eigenvectors, ascending eigenvalue); determinant +1.
    half_sizes : ndarray of shape (n_components, 3)
        ``n_sigma * sqrt(eigenvalue)`` along each column of ``rotations``.
    quaternions : ndarray of shape (n_components, 4)
        ``rotations`` as unit quaternions in (x, y, z, w) order, the order of Foxglove and rerun.
    """
    covariances = np.asarray(covariances, dtype=np.float64)
    if covariances.ndim != 3 or covariances.shape[1:] != (3, 3):
        raise InputError(f"covariances must have shape (n_components, 3, 3), got {covariances.shape}")
    eigenvalues, rotations = np.linalg.eigh(covariances)
    # eigh may return a reflection; flipping one axis keeps the same ellipsoid and makes it a rotation.
    rotations[:, :, 2] *= np.sign(np.linalg.det(rotations))[:, None]
    half_sizes = n_sigma * np.sqrt(np.clip(eigenvalues, 0.0, None))
    quaternions = Rotation.from_matrix(rotations).as_quat()
    return rotations, half_sizes, quaternions


# ---------------------------------------------------------------------------------------------------------
# JSON schemas
# ---------------------------------------------------------------------------------------------------------

def _struct(title, properties, required=True):
    """JSON schema of an object in the style of Foxglove's published schemas.

    Parameters
    ----------
    title : str
        Schema title (Foxglove's are ``foxglove.<Name>``).
    properties : dict
        Property name -> JSON schema.
    required : bool, default=True
        Whether every property is required.

    Returns
    -------
    schema : dict
    """
    schema = {"title": title, "type": "object", "properties": properties}
    if required:
        schema["required"] = list(properties)
    return schema


def _numbers(title, names):
    """Schema of an object whose properties ``names`` are all required numbers."""
    return _struct(title, {name: {"type": "number"} for name in names})


def _array(items):
    """Schema of an array of ``items``."""
    return {"type": "array", "items": items}


_TIME = _struct(
    "time",
    {"sec": {"type": "integer", "minimum": 0}, "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}},
    required=False,
)
_DURATION = _struct(
    "duration",
    {"sec": {"type": "integer"}, "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}},
    required=False,
)
_VECTOR3 = _numbers("foxglove.Vector3", "xyz")
_POSE = _struct("foxglove.Pose", {"position": _VECTOR3, "orientation": _numbers("foxglove.Quaternion", "xyzw")})
_COLOR = _numbers("foxglove.Color", "rgba")
_KEY_VALUE = _struct("foxglove.KeyValuePair", {"key": {"type": "string"}, "value": {"type": "string"}})
_SPHERE = _struct("foxglove.SpherePrimitive", {"pose": _POSE, "size": _VECTOR3, "color": _COLOR})
_UNUSED_PRIMITIVES = ("Arrow", "Cube", "Cylinder", "Line", "TriangleList", "Text", "Model")
_UNUSED_FIELDS = ("arrows", "cubes", "cylinders", "lines", "triangles", "texts", "models")

SCENE_UPDATE_SCHEMA = _struct(
    "foxglove.SceneUpdate",
    {
        "deletions": _array(_struct(
            "foxglove.SceneEntityDeletion",
            {
                "timestamp": _TIME,
                "type": {"title": "foxglove.SceneEntityDeletionType",
                         "oneOf": [{"title": "MATCHING_ID", "const": 0}, {"title": "ALL", "const": 1}]},
                "id": {"type": "string"},
            },
        )),
        "entities": _array(_struct(
            "foxglove.SceneEntity",
            {
                "timestamp": _TIME,
                "frame_id": {"type": "string"},
                "id": {"type": "string"},
                "lifetime": _DURATION,
                "frame_locked": {"type": "boolean"},
                "metadata": _array(_KEY_VALUE),
                "spheres": _array(_SPHERE),
                # dgmm writes only spheres; the other primitive lists stay empty and their item schemas are
                # abbreviated to their titles here.
                **{field: _array({"title": f"foxglove.{name}Primitive", "type": "object"})
                   for field, name in zip(_UNUSED_FIELDS, _UNUSED_PRIMITIVES)},
            },
        )),
    },
)
"""Foxglove's ``foxglove.SceneUpdate`` JSON schema (optional lineage fields and unused primitive items omitted)."""

POSES_IN_FRAME_SCHEMA = _struct(
    "foxglove.PosesInFrame", {"timestamp": _TIME, "frame_id": {"type": "string"}, "poses": _array(_POSE)}
)
"""Foxglove's ``foxglove.PosesInFrame`` JSON schema (optional lineage fields omitted)."""

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
        "centre": _array({"type": "number"}),
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


# ---------------------------------------------------------------------------------------------------------
# Foxglove messages
# ---------------------------------------------------------------------------------------------------------

def _time(ns):
    """Foxglove ``time`` from integer nanoseconds."""
    sec, nsec = divmod(int(ns), 1_000_000_000)
    return {"sec": sec, "nsec": nsec}


def _named(values, keys="xyz"):
    """``{key: float(value)}`` for matching ``keys`` (a string of names) and ``values`` of the same length."""
    return {key: float(value) for key, value in zip(keys, values, strict=True)}


def _pose(position, quaternion):
    """Foxglove ``Pose`` from a position (3,) and a quaternion (4,) in (x, y, z, w) order."""
    return {"position": _named(position), "orientation": _named(quaternion, "xyzw")}


def ellipsoid_scene_update(means, covariances, *, log_time_ns, entity_id="mixture", frame_id="world",
                           n_sigma=DEFAULT_N_SIGMA, color=(0.2, 0.6, 1.0, 0.5), metadata=None):
    """A ``foxglove.SceneUpdate`` with one entity drawing a mixture's components as ellipsoids.

    Each component is a ``SpherePrimitive`` centred on its mean, oriented by the proper rotation of its
    principal axes, with ``size`` (full diameters) ``2 * n_sigma * sqrt(eigenvalue)``.

    Parameters
    ----------
    means : array-like of shape (n_components, 3)
    covariances : array-like of shape (n_components, 3, 3)
    log_time_ns : int
        Entity timestamp in nanoseconds.
    entity_id : str, default="mixture"
        An entity replaces any earlier one with the same id on the same topic.
    frame_id : str, default="world"
    n_sigma : float, default=2.0
    color : tuple of 4 floats, default=(0.2, 0.6, 1.0, 0.5)
        RGBA in [0, 1].
    metadata : dict of str to str, optional
        Shown by Foxglove beside the entity.

    Returns
    -------
    message : dict
        JSON-ready message valid under :data:`SCENE_UPDATE_SCHEMA`.
    """
    means = np.asarray(means, dtype=np.float64)
    _, half_sizes, quaternions = covariance_ellipsoids(covariances, n_sigma)
    if means.shape != (len(half_sizes), 3):
        raise InputError(f"means must have shape ({len(half_sizes)}, 3), got {means.shape}")
    rgba = _named(color, "rgba")
    spheres = [{"pose": _pose(mean, quaternion), "size": _named(2.0 * half), "color": rgba}
               for mean, half, quaternion in zip(means, half_sizes, quaternions)]
    entity = {
        "timestamp": _time(log_time_ns),
        "frame_id": frame_id,
        "id": entity_id,
        "lifetime": {"sec": 0, "nsec": 0},
        "frame_locked": False,
        "metadata": [{"key": str(key), "value": str(value)} for key, value in (metadata or {}).items()],
        "spheres": spheres,
        **{field: [] for field in _UNUSED_FIELDS},
    }
    return {"deletions": [], "entities": [entity]}


def poses_in_frame(rotations, translations, *, log_time_ns, frame_id="world"):
    """A ``foxglove.PosesInFrame`` from rigid transforms ``x -> R x + t``.

    Parameters
    ----------
    rotations : array-like of shape (n_poses, 3, 3)
        Proper rotation matrices.
    translations : array-like of shape (n_poses, 3)
    log_time_ns : int
        Message timestamp in nanoseconds.
    frame_id : str, default="world"

    Returns
    -------
    message : dict
        JSON-ready message valid under :data:`POSES_IN_FRAME_SCHEMA`.
    """
    translations = np.asarray(translations, dtype=np.float64).reshape(-1, 3)
    quaternions = Rotation.from_matrix(np.asarray(rotations, dtype=np.float64).reshape(-1, 3, 3)).as_quat()
    if len(quaternions) != len(translations):
        raise InputError(f"got {len(quaternions)} rotations but {len(translations)} translations")
    return {
        "timestamp": _time(log_time_ns),
        "frame_id": frame_id,
        "poses": [_pose(t, q) for t, q in zip(translations, quaternions)],
    }


# ---------------------------------------------------------------------------------------------------------
# Writers
# ---------------------------------------------------------------------------------------------------------

class _Output:
    """An output written to a temporary file: a context manager that closes it (renaming it into place) when the
    block succeeds and aborts it (discarding it) when the block raises. Subclasses define ``close`` and ``abort``."""

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            self.close()
        else:
            self.abort()


class _Recording(_Output):
    """An MCAP file (``self._mcap``) and an optional rerun recording (``self._rerun``), kept or discarded
    together."""

    def close(self):
        """Finish both files and rename them into place."""
        self._mcap.close()
        if self._rerun is not None:
            self._rerun.close()

    def abort(self):
        """Discard both files."""
        self._mcap.abort()
        if self._rerun is not None:
            self._rerun.abort()


def _json_default(value):
    """Make numpy scalars and arrays JSON-serialisable."""
    if isinstance(value, (np.generic, np.ndarray)):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


class McapWriter(_Output):
    """An MCAP file of JSON messages, each topic a channel with a JSON schema, written atomically.

    Use as a context manager: on a clean exit the file is renamed into place, on an exception it is removed.

    Parameters
    ----------
    path : str or path-like
        Final file name; the data go to a temporary file beside it until :meth:`close`.

    Examples
    --------
    >>> with McapWriter("fit.mcap") as out:                                    # doctest: +SKIP
    ...     out.write("/fit/params", {"n_components": 25}, FIT_PARAMS_SCHEMA)
    """

    def __init__(self, path):
        self.path = Path(path)
        self._temporary = temporary_path(self.path)
        self._stream = open(self._temporary, "wb")
        self._writer = Writer(self._stream)
        self._writer.start(profile="", library="dgmm")
        self._schema_ids = {}
        self._channels = {}
        self._n_messages = 0

    def next_log_time(self):
        """Log time (ns) that :meth:`write` gives the next message by default."""
        return self._n_messages * TICK_NS

    def write(self, topic, message, schema, log_time_ns=None):
        """Write one JSON message on ``topic``.

        The topic's channel, and the schema's record (keyed by its ``title``), are registered on first use.

        Parameters
        ----------
        topic : str
        message : dict
            JSON-serialisable (numpy scalars and arrays allowed); NaN and infinity are rejected.
        schema : dict
            JSON schema of the message, with a ``title`` naming it (e.g. ``foxglove.SceneUpdate``).
        log_time_ns : int, optional
            Defaults to :meth:`next_log_time`, so messages are evenly spaced in file order.
        """
        if log_time_ns is None:
            log_time_ns = self.next_log_time()
        name = schema["title"]
        if name not in self._schema_ids:
            data = json.dumps(schema, sort_keys=True).encode()
            self._schema_ids[name] = self._writer.register_schema(name=name, encoding="jsonschema", data=data)
        channel = self._channels.get(topic)
        if channel is None:
            channel_id = self._writer.register_channel(topic, "json", self._schema_ids[name])
            channel = self._channels[topic] = (channel_id, name)
        elif channel[1] != name:
            raise InputError(f"MCAP topic {topic!r} carries {channel[1]!r} messages, not {name!r}")
        data = json.dumps(message, default=_json_default, allow_nan=False, separators=(",", ":")).encode()
        self._writer.add_message(channel[0], log_time=log_time_ns, data=data, publish_time=log_time_ns,
                                 sequence=self._n_messages)
        self._n_messages += 1

    def close(self):
        """Finish the file and rename it into place."""
        self._writer.finish()
        self._stream.close()
        os.replace(self._temporary, self.path)

    def abort(self):
        """Discard the file."""
        self._stream.close()
        self._temporary.unlink(missing_ok=True)


def _ellipsoids(means, covariances, n_sigma):
    """``rr.Ellipsoids3D`` of a mixture's components, one class id per component."""
    _, half_sizes, quaternions = covariance_ellipsoids(covariances, n_sigma)
    return rr.Ellipsoids3D(centers=np.asarray(means), half_sizes=half_sizes, quaternions=quaternions,
                           class_ids=np.arange(len(half_sizes)))


class RerunRecorder(_Output):
    """A rerun recording (``.rrd``) of one fit, written atomically.

    Entities: ``input`` (static ``Mesh3D`` or ``Points3D``), ``mixture`` (``Ellipsoids3D``) and ``bound``
    (``Scalars``), the last two on the sequence timeline ``iteration``. The wall-clock ``log_time`` timeline
    and the recording start-time property are left out so replays depend only on the data.

    Parameters
    ----------
    path : str or path-like
        Final file name; the data go to a temporary file beside it until :meth:`close`.
    application_id : str, default="dgmm"
    recording_id : str, optional
        Defaults to the file's stem.
    n_sigma : float, default=2.0
        Ellipsoid half-sizes in standard deviations.
    """

    def __init__(self, path, *, application_id="dgmm", recording_id=None, n_sigma=DEFAULT_N_SIGMA):
        self.path = Path(path)
        self.n_sigma = n_sigma
        self._temporary = temporary_path(self.path)
        self._stream = rr.RecordingStream(application_id, recording_id=recording_id or self.path.stem,
                                          send_properties=False)
        self._stream.set_log_time_enabled(False)
        self._stream.save(self._temporary)

    def log_input(self, data):
        """Log the fitted input once, as static data.

        Parameters
        ----------
        data : trimesh.Trimesh, Primitives or array-like of shape (n_points, 3)
            A mesh (anything with ``vertices`` and ``faces``) is logged as ``Mesh3D``; primitives (anything with
            ``means``) as ``Points3D`` of their means; an array as ``Points3D``.
        """
        if hasattr(data, "vertices") and hasattr(data, "faces"):
            archetype = rr.Mesh3D(vertex_positions=np.asarray(data.vertices, dtype=np.float32),
                                  triangle_indices=np.asarray(data.faces, dtype=np.uint32))
        else:
            points = data.means if hasattr(data, "means") else data
            archetype = rr.Points3D(np.asarray(points, dtype=np.float32).reshape(-1, 3))
        self._stream.log("input", archetype, static=True)

    def log_iteration(self, iteration, model):
        """Log the mixture as ellipsoids and the bound at ``iteration``; fits ``callback(iteration, model)``.

        Parameters
        ----------
        iteration : int
            EM iteration, from 1.
        model : object
            With ``means_ (n_components, 3)``, ``covariances_ (n_components, 3, 3)`` and ``history_``.
        """
        self._stream.set_time("iteration", sequence=iteration)
        self._stream.log("mixture", _ellipsoids(model.means_, model.covariances_, self.n_sigma))
        self._stream.log("bound", rr.Scalars(float(model.history_[-1])))

    __call__ = log_iteration

    def log(self, entity, archetype, iteration=None, timeline="iteration"):
        """Log any rerun archetype on ``entity``: static without ``iteration``, else at that step of the
        sequence timeline ``timeline``.

        Parameters
        ----------
        entity : str
        archetype : rerun archetype
        iteration : int, optional
        timeline : str, default="iteration"
            E.g. ``"frame"`` for odometry.
        """
        if iteration is None:
            self._stream.log(entity, archetype, static=True)
        else:
            self._stream.set_time(timeline, sequence=iteration)
            self._stream.log(entity, archetype)

    def close(self):
        """Flush the recording and rename it into place."""
        self._stream.flush()
        self._stream.disconnect()
        os.replace(self._temporary, self.path)

    def abort(self):
        """Discard the recording."""
        self._stream.disconnect()
        self._temporary.unlink(missing_ok=True)


class FitRecorder(_Recording):
    """Callback that records the fits of several seeds: all to one MCAP file, the first to rerun.

    MCAP topics: ``/fit/params`` (once, :data:`FIT_PARAMS_SCHEMA`), ``/fit/iteration`` (per seed and
    iteration, :data:`FIT_ITERATION_SCHEMA`) and ``/fit/mixture`` (each seed's final mixture as ellipsoids,
    ``foxglove.SceneUpdate``, entity id ``seed-<seed>``).

    Parameters
    ----------
    mcap_path : str or path-like
    rrd_path : str or path-like, optional
        Where to write the rerun recording of the first seed; none if omitted.
    params : dict, optional
        Run parameters written to ``/fit/params``.
    data : trimesh.Trimesh, Primitives or array-like of shape (n_points, 3), optional
        The input, logged to rerun.
    n_sigma : float, default=2.0
        Ellipsoid half-sizes in standard deviations.
    clock : callable, default=time.perf_counter
        Returns seconds; pass a fake clock for byte-identical files.

    Examples
    --------
    >>> with FitRecorder("fit.mcap", "fit.rrd", params=params, data=mesh) as recorder:  # doctest: +SKIP
    ...     for seed in seeds:
    ...         recorder.begin_seed(seed)
    ...         model = GaussianMixture(25, random_state=seed, callback=recorder).fit(mesh)
    ...         recorder.end_seed(model)
    """

    def __init__(self, mcap_path, rrd_path=None, *, params=None, data=None, n_sigma=DEFAULT_N_SIGMA,
                 clock=time.perf_counter):
        self.n_sigma = n_sigma
        self._clock = clock
        self._seed = None
        self._started = None
        self._rerun_seed = None
        self._mcap = McapWriter(mcap_path)
        self._rerun = None
        try:
            self._mcap.write("/fit/params", params or {}, FIT_PARAMS_SCHEMA)
            if rrd_path is not None:
                self._rerun = RerunRecorder(rrd_path, n_sigma=n_sigma)
                if data is not None:
                    self._rerun.log_input(data)
        except BaseException:
            self.abort()
            raise

    def begin_seed(self, seed):
        """Start recording the fit of ``seed``; its wall time counts from here.

        Parameters
        ----------
        seed : int
        """
        if self._seed is not None:
            raise InputError(f"begin_seed({seed}) called before end_seed() of seed {self._seed}")
        self._seed = int(seed)
        if self._rerun_seed is None:
            self._rerun_seed = self._seed
        self._started = self._clock()

    def __call__(self, iteration, model):
        """Record one EM iteration of the current seed (the estimator's ``callback``).

        Parameters
        ----------
        iteration : int
            From 1.
        model : object
            With ``means_``, ``covariances_`` and ``history_`` (``history_[-1]`` is the current bound).
        """
        if self._seed is None:
            raise InputError("FitRecorder called before begin_seed(seed)")
        message = {"seed": self._seed, "iteration": int(iteration), "bound": float(model.history_[-1]),
                   "seconds": self._clock() - self._started}
        self._mcap.write("/fit/iteration", message, FIT_ITERATION_SCHEMA)
        if self._rerun is not None and self._seed == self._rerun_seed:
            self._rerun.log_iteration(iteration, model)

    def end_seed(self, model):
        """Write the current seed's final mixture as ellipsoids.

        Parameters
        ----------
        model : object
            The fitted estimator, with ``weights_``, ``means_``, ``covariances_`` and ``history_``.
        """
        if self._seed is None:
            raise InputError("end_seed() called before begin_seed(seed)")
        metadata = {"seed": self._seed, "n_components": len(model.weights_), "n_sigma": self.n_sigma,
                    "bound": repr(float(model.history_[-1]))}
        message = ellipsoid_scene_update(model.means_, model.covariances_, entity_id=f"seed-{self._seed}",
                                         log_time_ns=self._mcap.next_log_time(), n_sigma=self.n_sigma,
                                         metadata=metadata)
        self._mcap.write("/fit/mixture", message, SCENE_UPDATE_SCHEMA)
        self._seed = None



_TRUTH_COLOR, _SOURCE_COLOR, _TARGET_COLOR = (160, 160, 160), (255, 140, 0), (40, 170, 80)


class RegistrationRecorder(_Recording):
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
        self._mcap = McapWriter(mcap_path)
        self._rerun = None
        try:
            self._mcap.write("/registration/params", params or {}, REGISTRATION_PARAMS_SCHEMA)
            if mixture is not None:
                self._mcap.write("/registration/mixture", ellipsoid_scene_update(
                    mixture.means_, mixture.covariances_, log_time_ns=self._mcap.next_log_time(),
                    n_sigma=n_sigma, frame_id="model"), SCENE_UPDATE_SCHEMA)
            if rrd_path is not None:
                self._rerun = RerunRecorder(rrd_path, n_sigma=n_sigma)
                if mixture is not None:
                    self._rerun.log("mixture", _ellipsoids(mixture.means_, mixture.covariances_, n_sigma))
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
                rotation[None], translation[None], log_time_ns=log_time, frame_id="model"),
                POSES_IN_FRAME_SCHEMA, log_time)
        self._trial = None



_GROUNDTRUTH_COLOR, _ESTIMATE_COLOR = (40, 170, 80), (255, 140, 0)


def _ns(seconds):
    """Integer nanoseconds of a timestamp in seconds."""
    return int(round(float(seconds) * 1e9))


class OdometryRecorder(_Recording):
    """Callback of ``dgmm.odometry.run_odometry`` that records a visual-odometry run to MCAP and to rerun.

    Poses are camera → frame ``x -> R x + t`` (``dgmm.odometry`` conventions). The estimate lives in the frame
    ``"odometry"`` (the first camera); ``"world"`` is the ground truth's frame. For display, the estimate is also
    drawn anchored at the first frame's ground-truth pose, ``T_world = G_0 T_odometry`` (evo's origin alignment),
    so both paths start together and the drift is visible.

    MCAP topics, JSON, log times = frame timestamps: ``/odometry/params`` (once), ``/odometry/frame`` (each frame,
    :data:`ODOMETRY_FRAME_SCHEMA`), and at the last frame's time ``foxglove.PosesInFrame`` messages holding every
    pose: ``/odometry/estimated`` (frame ``"odometry"``, the poses of the trajectory file),
    ``/odometry/estimated_in_world`` (anchored, frame ``"world"``) and ``/odometry/groundtruth`` (frame
    ``"world"``, the ground truth at the recorded frames, when given).

    rerun entities (``world`` is z-up, as TUM's and the synthetic ground truth are): ``world/groundtruth`` (static
    line strip), and on the sequence timeline ``frame``: ``world/estimated`` (the anchored path so far),
    ``world/camera`` (its pose), ``world/camera/image`` (the pinhole, static), ``world/camera/model`` (the
    frame's mixture as ellipsoids in camera coordinates, or ICP's points), ``seconds/model`` and
    ``seconds/registration``.

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
    n_sigma : float, default=2.0

    Examples
    --------
    >>> with OdometryRecorder("odometry.mcap", "odometry.rrd", groundtruth=truth) as recorder:  # doctest: +SKIP
    ...     result = run_odometry(sequence, "gmm-pixels", frames, callback=recorder)
    ...     recorder.finish(result.trajectory)
    """

    def __init__(self, mcap_path, rrd_path=None, *, params=None, groundtruth=None, intrinsics=None,
                 n_sigma=DEFAULT_N_SIGMA):
        self.n_sigma = n_sigma
        self.groundtruth = groundtruth
        if groundtruth is not None and len(groundtruth):
            self._anchor = (np.asarray(groundtruth.rotations[0]), np.asarray(groundtruth.translations[0]))
        else:
            self._anchor = (np.eye(3), np.zeros(3))
        self._path = []
        self._last_time = 0
        self._mcap = McapWriter(mcap_path)
        self._rerun = None
        try:
            start = 0 if groundtruth is None or not len(groundtruth) else _ns(groundtruth.timestamps[0])
            self._mcap.write("/odometry/params", params or {}, ODOMETRY_PARAMS_SCHEMA, start)
            if rrd_path is not None:
                self._rerun = RerunRecorder(rrd_path, n_sigma=n_sigma)
                self._rerun.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP)
                if groundtruth is not None:
                    self._rerun.log("world/groundtruth", rr.LineStrips3D([groundtruth.translations],
                                                                         colors=_GROUNDTRUTH_COLOR))
                if intrinsics is not None:
                    self._rerun.log("world/camera/image", rr.Pinhole(
                        focal_length=[intrinsics.fx, intrinsics.fy], principal_point=[intrinsics.cx, intrinsics.cy],
                        resolution=[intrinsics.width, intrinsics.height], camera_xyz=rr.ViewCoordinates.RDF,
                        image_plane_distance=0.2))
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
        message = {"index": frame.index, "timestamp": frame.timestamp, "model_seconds": frame.prepare_seconds,
                   "registration_seconds": None if registration is None else float(registration.seconds),
                   "iterations": None if registration is None else int(registration.iterations),
                   "converged": None if registration is None else bool(registration.converged),
                   "objective": None if registration is None else float(registration.objective)}
        self._mcap.write("/odometry/frame", message, ODOMETRY_FRAME_SCHEMA, self._last_time)
        if self._rerun is None:
            return
        rotation, translation = self._in_world(frame.rotation, frame.translation)
        self._path.append(translation)
        log = self._rerun.log
        log("world/estimated", rr.LineStrips3D([np.array(self._path)], colors=_ESTIMATE_COLOR), frame.index,
            "frame")
        log("world/camera", rr.Transform3D(translation=translation, mat3x3=rotation), frame.index, "frame")
        if hasattr(frame.model, "means_"):
            shown = _ellipsoids(frame.model.means_, frame.model.covariances_, self.n_sigma)
        else:
            shown = rr.Points3D(np.asarray(frame.model), colors=_ESTIMATE_COLOR, radii=0.005)
        log("world/camera/model", shown, frame.index, "frame")
        log("seconds/model", rr.Scalars(frame.prepare_seconds), frame.index, "frame")
        if registration is not None:
            log("seconds/registration", rr.Scalars(registration.seconds), frame.index, "frame")

    def finish(self, trajectory):
        """Write the whole estimated trajectory (and the ground truth) as ``foxglove.PosesInFrame`` messages.

        Parameters
        ----------
        trajectory : dgmm.odometry.Trajectory
            The run's estimate (``Odometry.trajectory``).
        """
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
                             POSES_IN_FRAME_SCHEMA, self._last_time)

