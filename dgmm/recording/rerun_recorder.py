"""A rerun recording (``.rrd``) written atomically, with its blueprint; the mixture's ellipsoids as a rerun
archetype."""
import os
import signal
import threading
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import rerun as rr

from dgmm.files import temporary_path
from dgmm.recording.blueprints import fit_blueprint
from dgmm.recording.ellipsoids import DEFAULT_N_SIGMA, covariance_ellipsoids
from dgmm.recording.output import Output


def rerun_ellipsoids(means, covariances, n_sigma=DEFAULT_N_SIGMA):
    """``rr.Ellipsoids3D`` of a mixture's components, one class id per component."""
    _, half_sizes, quaternions = covariance_ellipsoids(covariances, n_sigma)
    return rr.Ellipsoids3D(centers=np.asarray(means), half_sizes=half_sizes, quaternions=quaternions,
                           class_ids=np.arange(len(half_sizes)))


@contextmanager
def interrupts_held():
    """Hold Ctrl-C (SIGINT) until the block ends, then deliver it.

    rerun's ``RecordingStream.__del__`` assumes a finished stream: a KeyboardInterrupt raised while one is being
    built leaves a half-made object whose collection prints a traceback. Held, the interrupt arrives once the stream
    exists and the recorder can discard it. Only the main thread receives signals; elsewhere nothing is held.
    """
    previous = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is not threading.main_thread() or previous is None:  # None: not Python's to set
        yield
        return
    received = []
    signal.signal(signal.SIGINT, lambda signum, frame: received.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if received:
            signal.raise_signal(signal.SIGINT)


class RerunRecorder(Output):
    """A rerun recording (``.rrd``) of one fit, written atomically.

    Entities: ``input`` (static ``Mesh3D`` or ``Points3D``), ``mixture`` (``Ellipsoids3D``) and ``bound``
    (``Scalars``), the last two on the sequence timeline ``iteration``. The wall-clock ``log_time`` timeline
    and the recording start-time property are left out so replays depend only on the data. The file carries a
    blueprint (:mod:`dgmm.recording.blueprints`) the viewer opens on.

    Parameters
    ----------
    path : str or path-like
        Final file name; the data go to a temporary file beside it until :meth:`close`.
    application_id : str, default="dgmm"
    recording_id : str, optional
        Defaults to the file's stem.
    n_sigma : float, default=2.0
        Ellipsoid half-sizes in standard deviations.
    blueprint : rerun.blueprint.Blueprint, optional
        Defaults to the fit's (:func:`~dgmm.recording.blueprints.fit_blueprint`); the other recorders pass theirs.
    """

    def __init__(self, path, *, application_id="dgmm", recording_id=None, n_sigma=DEFAULT_N_SIGMA,
                 blueprint=None):
        self.path = Path(path)
        self.n_sigma = n_sigma
        self._temporary = temporary_path(self.path)
        self._stream = None
        try:  # the caller holds nothing to abort until __init__ returns: discard here what was opened
            with interrupts_held():  # a Ctrl-C arrives once the stream and its file exist
                self._stream = rr.RecordingStream(application_id, recording_id=recording_id or self.path.stem,
                                                  send_properties=False)
                self._stream.set_log_time_enabled(False)
                self._stream.save(self._temporary, default_blueprint=blueprint or fit_blueprint())
        except BaseException:
            self.abort()
            raise

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
        self._stream.log("mixture", rerun_ellipsoids(model.means_, model.covariances_, self.n_sigma))
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

    def set_timestamp(self, seconds, timeline="timestamp"):
        """Put what is logged next also at ``seconds`` (since the Unix epoch, nanosecond resolution) of the
        timestamp timeline ``timeline``: an input's own clock beside a sequence timeline.

        Parameters
        ----------
        seconds : float
        timeline : str, default="timestamp"
        """
        self._stream.set_time(timeline, timestamp=np.datetime64(int(round(float(seconds) * 1e9)), "ns"))

    def close(self):
        """Flush the recording and rename it into place."""
        self._stream.flush()
        self._stream.disconnect()
        os.replace(self._temporary, self.path)

    def abort(self):
        """Discard the recording (its stream may not have been built)."""
        if self._stream is not None:
            self._stream.disconnect()
        self._temporary.unlink(missing_ok=True)
