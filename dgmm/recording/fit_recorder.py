"""The fit recorder: the estimator's ``callback`` writing every seed's fit to MCAP and the first seed's to rerun."""
import time

from dgmm.errors import InputError
from dgmm.recording.ellipsoids import DEFAULT_N_SIGMA
from dgmm.recording.foxglove_messages import ellipsoid_scene_update
from dgmm.recording.json_schemas import FIT_ITERATION_SCHEMA, FIT_PARAMS_SCHEMA
from dgmm.recording.mcap_writer import McapWriter
from dgmm.recording.output import Recording
from dgmm.recording.rerun_recorder import RerunRecorder


class FitRecorder(Recording):
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
        self._mcap = self._rerun = None
        try:  # Ctrl-C at any point of this leaves no file behind
            self._mcap = McapWriter(mcap_path)
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
        self._mcap.write("/fit/mixture", message)
        self._seed = None
