"""Timing checks of the visual odometry (§VI-D, Fig 7) on the first frames of a TUM sequence.

- ``d2d primitives`` ("D2D registration time was 22% faster when using GMMs built from primitives"): every frame's
  gmm-pixels and gmm-points mixtures built as the sweep's odometry builds them (textbook EM), then each consecutive
  pair registered by the sweep's D2D (``pixels``, ``points``: the schedule's rounds and cuts) and by the paper's,
  BFGS with forward differences on the determinant-free D2D cost of the whole mixtures (``pixels bfgs``,
  ``points bfgs``);
- ``odometry frame`` (Fig 7: "Runtime for both methods was similar"): one odometry step per frame, the frame's model
  and its registration onto the previous frame's, by gmm-pixels (textbook EM) and by ICP on its random points.

The frames' models are the sweep's: the methods' own functions (:data:`dgmm.odometry.METHODS`) with the options
and the per-frame seeds :func:`dgmm.odometry.run_odometry` gives them in the sweep's jobs.
"""
import numpy as np

from dgmm.experiments.checks.interleaved import interleaved_times
from dgmm.experiments.sweep import job_seed
from dgmm.odometry import METHODS, groundtruth_at_frames, odometry_runs, parse_intrinsics
from dgmm.odometry.schedule_studies import schedule_named
from dgmm.registration import register_d2d, rotation_distance_deg

VARIANT = "textbook"
"""The EM of every frame's mixture: the one both kinds of primitives run in the sweep."""
ICP_TOL = 1e-9
"""ICP's tolerance in the sweep's odometry (``run_odometry``'s default)."""


class SweepFrames:
    """The odometry methods' frame models, built frame after frame as the sweep's odometry jobs build them.

    Parameters
    ----------
    sequence : dgmm.odometry.TumSequence
    methods : sequence of str
        Keys of :data:`dgmm.odometry.METHODS`.
    name : str
        The sequence's name in the sweep (its folder's name, or ``synthetic``).
    root_seed : int
        The sweep's seed: each method's model of frame ``k`` draws from ``default_rng([seed, k])``, ``seed`` its
        odometry job's (``odometry/{name}/{run}``).
    intrinsics : str
        A ``dgmm.odometry.CAMERAS`` name or ``FX,FY,CX,CY``.
    n_components, schedule, warm_iter, pixel_size, icp_points
        The sweep's odometry settings (``warm_iter`` 0 or None: every frame from its own start).
    """

    def __init__(self, sequence, methods, *, name, root_seed, intrinsics, n_components, schedule, warm_iter,
                 pixel_size, icp_points):
        self.seeds = {method: job_seed(root_seed, f"odometry/{name}/{run}", 0)
                      for run, (method, _) in odometry_runs(methods, [VARIANT]).items()}
        self.intrinsics = parse_intrinsics(intrinsics)
        self.options = {"n_components": n_components, "warm_iter": warm_iter or None,
                        "schedule": schedule_named(schedule), "variant": VARIANT, "size": pixel_size,
                        "n_icp_points": icp_points, "icp_tol": ICP_TOL, "intrinsics": self.intrinsics}
        self.previous = dict.fromkeys(methods)
        matched, poses = groundtruth_at_frames(sequence)
        self.truth = dict(zip(matched.tolist(), poses.rotations))

    def model(self, method, index, depth):
        """``method``'s model of frame ``index`` (its ``depth``), after the one of the frame before (warm starts)."""
        prepare, _ = METHODS[method]
        model = prepare(depth, self.intrinsics, np.random.default_rng([self.seeds[method], index]),
                        self.previous[method], self.options)
        self.previous[method] = model
        return model

    def register(self, method, fixed, moving):
        """``method``'s registration of ``moving`` onto ``fixed``, as the sweep's odometry runs it."""
        return METHODS[method][1](fixed, moving, self.options)

    def describe(self, index, registration):
        """``(iterations, detail)`` of the registration of frame ``index + 1`` onto frame ``index``: the rotation
        error against the ground truth's relative rotation."""
        if index not in self.truth or index + 1 not in self.truth:
            return registration.iterations, "no ground truth"
        truth = self.truth[index].T @ self.truth[index + 1]
        return registration.iterations, f"rotation error {rotation_distance_deg(registration.rotation, truth):.3g} deg"


D2D_METHODS = {"pixels": "gmm-pixels", "points": "gmm-points"}
"""The ``d2d primitives`` check's primitives: setting prefix -> odometry method."""


def d2d_primitives_times(sequence, *, repeats, **settings):
    """CPU seconds of the D2D registrations of the first ``repeats`` frame pairs, pixel and point mixtures.

    Parameters
    ----------
    sequence : dgmm.odometry.TumSequence
    repeats : int
    **settings
        Of :class:`SweepFrames`.

    Returns
    -------
    list of dict
        Rows of :data:`dgmm.experiments.checks.interleaved.COLUMNS`: settings ``pixels``, ``points`` (the sweep's
        D2D), ``pixels bfgs``, ``points bfgs`` (the paper's); ``iterations`` the solver's, ``detail`` the rotation
        error.
    """
    frames = SweepFrames(sequence, list(D2D_METHODS.values()), **settings)

    def pairs():  # a case: (index of the fixed frame, method -> (fixed, moving) models)
        models = {method: frames.model(method, 0, sequence.depth(0)) for method in D2D_METHODS.values()}
        for index in range(repeats):
            depth = sequence.depth(index + 1)
            moving = {method: frames.model(method, index + 1, depth) for method in D2D_METHODS.values()}
            yield index, {method: (models[method], moving[method]) for method in D2D_METHODS.values()}
            models = moving

    timed = {}
    for prefix, method in D2D_METHODS.items():
        timed[prefix] = lambda case, method=method: frames.register(method, *case[1][method])
        timed[f"{prefix} bfgs"] = lambda case, method=method: register_d2d(*case[1][method], gradient="numeric")
    return interleaved_times("d2d primitives", pairs(), timed,
                             lambda case, setting, registration: frames.describe(case[0], registration))


FRAME_METHODS = ("gmm-pixels", "icp")
"""The ``odometry frame`` check's settings: odometry methods."""


def odometry_frame_times(sequence, *, repeats, **settings):
    """CPU seconds of one odometry step (the frame's model and its registration onto the previous frame's) of each
    of :data:`FRAME_METHODS`, for frames 1 to ``repeats`` (frame 0's models are built untimed).

    Parameters
    ----------
    sequence : dgmm.odometry.TumSequence
    repeats : int
    **settings
        Of :class:`SweepFrames`.

    Returns
    -------
    list of dict
        Rows of :data:`dgmm.experiments.checks.interleaved.COLUMNS`; ``iterations`` the registration's, ``detail``
        its rotation error.
    """
    frames = SweepFrames(sequence, FRAME_METHODS, **settings)
    depth = sequence.depth(0)
    for method in FRAME_METHODS:
        frames.model(method, 0, depth)

    def step(case, method):
        index, depth = case
        fixed = frames.previous[method]
        return frames.register(method, fixed, frames.model(method, index, depth))

    cases = ((index, sequence.depth(index)) for index in range(1, repeats + 1))
    return interleaved_times("odometry frame", cases, {method: (lambda case, method=method: step(case, method))
                                                       for method in FRAME_METHODS},
                             lambda case, setting, registration: frames.describe(case[0] - 1, registration))
