"""The per-frame model of each odometry method and how two frames' models are registered (paper §VI-D).

Methods: ``"gmm-pixels"`` fits a K-component GMM to per-pixel rectangle primitives (:mod:`dgmm.odometry.pixels`)
and registers with the determinant-free D2D cost; ``"gmm-points"`` does the same with the plain back-projected
points; ``"icp"`` keeps 2,500 points drawn at random from each frame's back-projection for point-to-point ICP.

Schedules (:data:`SCHEDULES`): the paper does not state how each frame's EM starts or how long it runs, nor its
odometry's solver, so the sweep's schedule is chosen by measurement (``benchmarks/studies/odometry_schedules.py``,
against the alternatives of :mod:`dgmm.odometry.schedule_studies`). Every frame's start is drawn from its own seed.

Warm start (``warm_iter``): every frame after the first starts from the previous frame's mixture (its starved
components restarted on the data) and runs ``warm_iter`` iterations. It under-measures the motion: a few EM
iterations move a component only part of the way its data moved (EM's mean update lags along surfaces that extend
past the component), so D2D between the previous mixture and its lagging successor sees part of the motion, and
the shortfall compounds into drift (measured: docs/studies/odometry_constants.md).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dgmm.errors import InputError
from dgmm.gaussian import SCREEN
from dgmm.mixture import GaussianMixture
from dgmm.odometry.em_start import lloyd_start
from dgmm.odometry.measured_cut import MeasuredFrame, register_cut_rounds
from dgmm.odometry.overlap import register_d2d_common_view, register_d2d_overlap
from dgmm.odometry.protocols import OURS, protocol_runs
from dgmm.odometry.pixels import PIXEL_STEP, backproject, pixel_primitives
from dgmm.odometry.sklearn_em import SKLEARN_MAX_ITER, SKLEARN_TOL, fit_sklearn_defaults
from dgmm.primitives import Primitives
from dgmm.registration import register_d2d, register_icp

REG_COVAR = 1e-6
"""Every frame's mixture's ``reg_covar`` (``GaussianMixture``'s default)."""

EM_BLOCK_BYTES = 2**19
"""Every frame's EM streams its responsibilities in blocks of this many bytes (``GaussianMixture``'s
``memory_limit``): a frame's responsibilities (about 14,000 pixels x K = 100) are 11.5 MB, and EM's passes over
half-MiB blocks stay in the CPU's cache (measured: docs/studies/odometry_constants.md)."""

ROUND_TOL = 1e-4
"""Gauss-Newton's stopping tolerance (pose change in radians and RMS radii) of the cut rounds' registrations, in
place of the solver's 1e-8; below :data:`CUT_TOL`, which the rounds' pose changes are held to, so a looser solve
changes no estimate that the rounds keep and saves CPU. The registration before the rounds, only their start,
stops at :data:`CUT_TOL` (measured: docs/studies/odometry_constants.md)."""

CUT_TOL = 1e-3
"""Cut rounds stop once a round moves the pose by less (radians, and RMS radii of the moving mixture: 1 mm at
fr1/xyz's radius of about 1 m; :func:`dgmm.odometry.measured_cut.register_cut_rounds`): the ATE stays within the
seed-to-seed spread of always running all three rounds, for a quarter less of the rounds' CPU (measured on fr1/xyz
and the rotation-only room: docs/studies/odometry_constants.md)."""

STARVED_WEIGHT = 0.1
"""Warm start: a component of the previous frame's mixture whose weight is below ``STARVED_WEIGHT / K`` restarts."""


def _warm_start(mixture, prims, rng):
    """The previous frame's mixture as this frame's EM start, every starved component (weight below
    ``STARVED_WEIGHT / K``) restarted at a primitive drawn by size, with the live components' median covariance
    and weight ``1 / K``.

    Without the restart a component that loses its primitives (the scene leaves the view, or its neighbours win
    them) keeps a weight near 0 and the ``reg_covar`` covariance for good: on fr1/xyz the effective number of
    components ``1 / Σ π²`` falls from 79 to 7 within 55 frames and D2D loses its grip.
    """
    k = len(mixture.weights_)
    weights, means, covariances = mixture.weights_.copy(), mixture.means_.copy(), mixture.covariances_.copy()
    starved = weights < STARVED_WEIGHT / k
    if starved.any():
        picks = rng.choice(len(prims), size=int(starved.sum()), p=prims.weights / prims.weights.sum())
        means[starved] = prims.means[picks]
        covariances[starved] = np.median(covariances[~starved], axis=0)
        weights[starved] = 1.0 / k
        weights /= weights.sum()
    return weights, means, np.linalg.inv(covariances)


@dataclass(frozen=True)
class Schedule:
    """How every frame's mixture is fitted and registered: its EM start, its EM iterations, the D2D solver.

    Attributes
    ----------
    seed_sample : int or None
        None: scikit-learn's k-means (k-means++ seeds, Lloyd to convergence) on every primitive, ``GaussianMixture``'s
        own ``init="kmeans"``. An int: k-means++ seeds drawn from that many primitives picked at random, refined by
        ``lloyd_iter`` Lloyd iterations on every primitive; the start is their hard-label M-step.
    lloyd_iter : int
        Lloyd iterations on every primitive after the seeds (unused when ``seed_sample`` is None).
    em_iter : int
        EM iterations from the start (a sampled start runs exactly that many, without the E-step after the last
        M-step that only a bound would need: ``GaussianMixture(tol=None)``).
    solver : {"bfgs", "gauss-newton"}
        D2D's solver (``dgmm.registration.register_d2d``).
    overlap_rounds : int, default=0
        Rounds of D2D, at each of ``overlap_scales``, on the components the other frame's camera sees
        (:func:`dgmm.odometry.overlap.register_d2d_overlap`); 0 registers the whole mixtures once.
    overlap_scales : tuple of float, default=(0.0,)
        Coarse-to-fine widening of those rounds, in RMS radii of the moving mixture, non-increasing; ending with 0
        unless cut rounds follow (they register the mixtures themselves).
    overlap_refits : int, default=0
        After the rounds, refit both frames on the primitives the other camera sees and register them from the
        pose so far, this many times (:func:`dgmm.odometry.overlap.register_d2d_common_view`; two more fits per
        frame each).
    cut_rounds : int, default=0
        Then, at most this many times, cut both mixtures to the primitives the other frame measures at the pose so
        far and register them from it, until a round moves the pose by less than :data:`CUT_TOL`
        (:func:`dgmm.odometry.measured_cut.register_cut_rounds`): what only one frame measured pulls D2D toward the
        identity, and a cut at a pose some centimetres off keeps part of that pull, so each round removes most of
        what is left of it.
    em_tol : float or None, default=None
        None: EM runs ``em_iter`` iterations (a k-means start: until its bound moves by less than 1e-12). A number
        (with ``seed_sample`` None): scikit-learn's ``GaussianMixture`` stopping rule at that ``tol``, up to
        ``em_iter`` iterations (:func:`dgmm.odometry.sklearn_em.fit_sklearn_defaults`).
    """

    seed_sample: int | None
    lloyd_iter: int
    em_iter: int
    solver: str
    overlap_rounds: int = 0
    overlap_scales: tuple = (0.0,)
    overlap_refits: int = 0
    cut_rounds: int = 0
    em_tol: float | None = None

    def __post_init__(self):
        if self.em_tol is not None and self.seed_sample is not None:
            raise InputError(f"em_tol {self.em_tol} is scikit-learn's stopping rule: it needs the k-means start "
                             "(seed_sample None)")
        if self.overlap_scales[-1] != 0.0 and not self.cut_rounds:
            raise InputError(f"overlap_scales {self.overlap_scales} end widened: they need cut rounds after them")


SCHEDULES = {
    "overlap": Schedule(seed_sample=1024, lloyd_iter=3, em_iter=2, solver="gauss-newton", overlap_rounds=1,
                        overlap_scales=(0.0625,), cut_rounds=3),
    "authors": Schedule(seed_sample=None, lloyd_iter=0, em_iter=SKLEARN_MAX_ITER, solver="bfgs", em_tol=SKLEARN_TOL),
}
"""The library's per-frame schedules: the sweep's, chosen by measurement, and the authors' protocol's (the studies'
alternatives are in :mod:`dgmm.odometry.schedule_studies`). ``"overlap"``, the default: k-means++ seeds from 1,024
primitives, 3 Lloyd iterations and 2 EM iterations on every primitive; Gauss-Newton D2D first on the components
each camera sees of the other, widened by 0.0625 RMS radii (it keeps fast turns in the right basin), then up to
three times, until the pose settles (:data:`CUT_TOL`), cut to the primitives each frame measures of the other at
the pose so far and registered again (``cut_rounds``): what only one frame measured no longer pulls the estimate
toward the identity. ``"authors"``: the authors' notebooks' per-frame fit, scikit-learn's ``GaussianMixture(100)``
at its defaults (k-means start, up to 100 iterations, ``tol`` 1e-3; :mod:`dgmm.odometry.sklearn_em`), and BFGS D2D
of the whole mixtures from the identity (``reg_results.ipynb``); with unit pixel sizes and a ``patch`` or
``disparity`` covariance it is the authors' protocol (:mod:`dgmm.odometry.protocols`)."""


def _fit_mixture(prims, rng, previous, options):
    """The frame's K-component GMM: from its schedule's start seeded by ``rng``, or from ``previous`` (warm start).

    ``previous`` is the previous frame's mixture or ``None`` (see :func:`_warm_start`).
    """
    schedule, k = options["schedule"], options["n_components"]
    # screened EM: the pairs left out are about 9 in 10 of a fr1/xyz frame's at K = 100 (docs/benchmarks/odometry.md)
    common = dict(variant=options["variant"], random_state=rng, reg_covar=REG_COVAR, memory_limit=EM_BLOCK_BYTES,
                  screen=SCREEN)
    if previous is not None and options["warm_iter"] is not None:
        weights, means, precisions = _warm_start(previous, prims, rng)
        return GaussianMixture(k, max_iter=options["warm_iter"], weights_init=weights, means_init=means,
                               precisions_init=precisions, **common).fit(prims)
    if schedule.em_tol is not None:
        return fit_sklearn_defaults(prims, k, rng, max_iter=schedule.em_iter, tol=schedule.em_tol,
                                    **{key: value for key, value in common.items() if key != "random_state"})
    if schedule.seed_sample is None:
        return GaussianMixture(k, max_iter=schedule.em_iter, **common).fit(prims)
    weights, means, precisions = lloyd_start(prims, k, schedule.seed_sample, schedule.lloyd_iter, options["variant"],
                                             rng, REG_COVAR)
    return GaussianMixture(k, max_iter=schedule.em_iter, tol=None, weights_init=weights, means_init=means,
                           precisions_init=precisions, **common).fit(prims)


def _view_mixture(prims, depth, intrinsics, rng, previous, options):
    """The frame's mixture; a :class:`~dgmm.odometry.measured_cut.MeasuredFrame` (the mixture, its primitives, its
    measured pixels) when the schedule's registration cuts or refits it, with ``overlap_refits`` a seed for the
    refits drawn from the frame's ``rng`` after the fit."""
    schedule = options["schedule"]
    mixture = _fit_mixture(prims, rng, previous, options)
    if not (schedule.overlap_refits or schedule.cut_rounds):
        return mixture
    refit_seed = int(rng.integers(np.iinfo(np.int64).max)) if schedule.overlap_refits else None
    return MeasuredFrame(mixture, prims, np.asarray(depth)[::PIXEL_STEP, ::PIXEL_STEP] > 0, intrinsics, PIXEL_STEP,
                         options["variant"], refit_seed)


def _prepare_pixels(depth, intrinsics, rng, previous, options):
    prims = pixel_primitives(depth, intrinsics, size=options["size"], covariance=options.get("covariance", "patch"))
    return _view_mixture(prims, depth, intrinsics, rng, previous, options)


def _prepare_points(depth, intrinsics, rng, previous, options):
    prims = Primitives.from_points(backproject(depth, intrinsics))
    return _view_mixture(prims, depth, intrinsics, rng, previous, options)


def _prepare_icp(depth, intrinsics, rng, previous, options):
    points = backproject(depth, intrinsics)
    return points[rng.choice(len(points), size=min(options["n_icp_points"], len(points)), replace=False)]


def _register_d2d(fixed, moving, options):
    schedule = options["schedule"]
    if schedule.overlap_refits:
        views = fixed, moving

        def fit(prims, frame):  # every refit of a frame from its own seed: the same bytes run to run
            return _fit_mixture(prims, np.random.default_rng(views[frame].refit_seed), None, options)

        registration = register_d2d_common_view(*((view, view.primitives) for view in views), fit,
                                                options["intrinsics"], schedule.overlap_refits,
                                                max(schedule.overlap_rounds, 1), schedule.overlap_scales,
                                                schedule.solver)
    elif schedule.overlap_rounds:
        registration = register_d2d_overlap(fixed, moving, options["intrinsics"], schedule.overlap_rounds,
                                            schedule.overlap_scales, schedule.solver,
                                            _solver_options(schedule, CUT_TOL))
    else:
        registration = register_d2d(fixed, moving, solver=schedule.solver,
                                    options=_solver_options(schedule, CUT_TOL))
    if schedule.cut_rounds:
        registration = register_cut_rounds(fixed, moving, registration, schedule.cut_rounds, CUT_TOL, schedule.solver,
                                           _solver_options(schedule, ROUND_TOL))
    return registration


def _solver_options(schedule, tol):
    """D2D's solver options under ``schedule``: ``tol`` with cut rounds (Gauss-Newton only)."""
    if schedule.cut_rounds and schedule.solver == "gauss-newton":
        return {"tol": tol}
    return None


def _register_icp(fixed, moving, options):
    return register_icp(moving, fixed, tol=options["icp_tol"])


# method -> (prepare(depth, intrinsics, rng, previous model, options) -> frame model,
#            register(fixed, moving, options) -> Registration)
METHODS = {
    "gmm-pixels": (_prepare_pixels, _register_d2d),
    "gmm-points": (_prepare_points, _register_d2d),
    "icp": (_prepare_icp, _register_icp),
}


MIXTURE_METHODS = ("gmm-pixels", "gmm-points")
"""The methods that fit a GMM per frame, and so run with an EM ``variant``."""

UNSIZED_METHODS = ("gmm-points",)
"""Mixture methods whose primitives all have size 1: every EM variant is the same algorithm there (the authors'
E-step scale ``alpha / min(alpha)`` is 1 and their unweighted M-step is the textbook one), so they run textbook EM
only, as the registration's point mixtures do (``dgmm.experiments.trials.method_variants``)."""


def odometry_runs(methods, variants, protocols=(OURS,)):
    """The (method, variant) pairs of a sweep, named as its jobs' folders.

    Parameters
    ----------
    methods : sequence of str
        Keys of ``METHODS``.
    variants : sequence of str
        EM variants of the mixture methods of sized primitives (gmm-pixels); :data:`UNSIZED_METHODS` run textbook
        EM only and ICP has none.
    protocols : sequence of str, default=("ours",)
        Keys of :data:`dgmm.odometry.protocols.PROTOCOLS`: ``"ours"`` runs every method with every variant as
        above; each of the authors' protocols adds a run per method it applies to
        (:func:`dgmm.odometry.protocols.protocol_runs`; :func:`dgmm.odometry.protocols.run_protocol` tells a run's
        protocol from its name).

    Returns
    -------
    runs : dict of str to (str, str)
        ``"gmm-pixels-textbook" -> ("gmm-pixels", "textbook")`` …, ``"icp" -> ("icp", "")``, then
        ``"gmm-pixels-authors-patch" -> ("gmm-pixels", "authors")`` …, in the given order.
    """
    def method_variants(method):
        if method not in MIXTURE_METHODS:
            return [""]
        return ["textbook"] if method in UNSIZED_METHODS else list(variants)

    ours = {f"{method}-{variant}" if variant else method: (method, variant)
            for method in methods for variant in method_variants(method)} if OURS in protocols else {}
    return {**ours, **protocol_runs(protocols, methods)}
