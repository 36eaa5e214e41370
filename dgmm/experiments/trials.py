"""The paper's registration experiment (§VI-A "Mesh Registration", Fig 6 and Table 1) as plain functions.

One experiment registers the source points of many random rigid trials back onto one model with several
methods (:data:`METHODS`). Every method sees the same trials (authors' protocol, leonidk/direct_gmm):

- ``n_points`` source points (the model mesh's vertex count) drawn without replacement from a dense surface
  sample of the model, and as many target points drawn independently from the same sample (ICP and CPD
  register to these, as the authors' code does);
- a random rigid motion about the source centroid (:func:`dgmm.registration.random_trials`): Euler angles
  uniform in ±15° per axis, translation uniform in ±0.05 per axis scaled by the model's bounding-box diagonal
  over the bunny's.

Trial ``i`` of an experiment draws all of this from its own generator, seeded by the root seed, the experiment's
key and ``i`` (:func:`dgmm.experiments.sweep.job_seed`), so any chunk of trials can be rebuilt alone, in any process.

P2D methods maximise the likelihood of the moved source under a Gaussian mixture fitted once per method
(:func:`fit_mixture`): to the mesh's triangles (``mesh-*``, exact triangles) or to its vertices (``points-*``),
from a k-means or a random start.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from dgmm.errors import InputError
from dgmm.experiments.sweep import REPRESENTATIONS, SIZED, job_seed
from dgmm.mixture import GaussianMixture
from dgmm.registration import (BUNNY_DIAGONAL, RigidTrial, random_trials, register_cpd, register_icp, register_p2d,
                               registration_errors)
from dgmm.registration.coarse_to_fine import register_p2d_coarse_to_fine

COLUMNS = ("trial", "rotation_error_deg", "translation_error_pct", "iterations", "converged")
"""Columns of the rows :func:`run_trials` returns (all deterministic; wall times are returned apart)."""


@dataclass(frozen=True)
class Method:
    """One registration method of the experiment.

    Attributes
    ----------
    algorithm : {"p2d", "p2d-c2f", "icp", "cpd"}
        Key of the registration function and of its options in :func:`run_trials`.
    representation : str or None
        How the mesh becomes the mixture's input (a ``dgmm.experiments.sweep.REPRESENTATIONS`` key); None for methods
        that register to points.
    init : {"kmeans", "random"} or None
        The mixture's initialisation.
    """

    algorithm: str
    representation: str | None = None
    init: str | None = None

    @property
    def needs_mixture(self):
        """Whether the method registers to a fitted mixture."""
        return self.representation is not None


_MIXTURE_INPUTS = {"mesh": "exact", "points": "vertices"}
METHODS = {
    **{f"{kind}-{init}{suffix}": Method(algorithm, representation, init)
       for suffix, algorithm in (("", "p2d"), ("-c2f", "p2d-c2f"))
       for kind, representation in _MIXTURE_INPUTS.items() for init in ("kmeans", "random")},
    "icp": Method("icp"),
    "cpd": Method("cpd"),
}
"""The paper's Fig 6 methods: P2D on mesh and point mixtures, point-to-point ICP and CPD; and ``*-c2f``, P2D on the
same mixtures over a coarse-to-fine schedule of widened covariances (:mod:`dgmm.registration.coarse_to_fine`)."""

# algorithm -> register(moved source, target points, mixture, callback=..., **options)
_ALGORITHMS = {
    "p2d": lambda moved, target, mixture, **options: register_p2d(moved, mixture, **options),
    "p2d-c2f": lambda moved, target, mixture, **options: register_p2d_coarse_to_fine(moved, mixture, **options),
    "icp": lambda moved, target, mixture, **options: register_icp(moved, target, **options),
    "cpd": lambda moved, target, mixture, **options: register_cpd(moved, target, **options),
}


def mixture_source(name):
    """The method whose fitted mixture method ``name`` registers to: ``*-c2f`` uses its paper P2D's (the same
    mixture, so that the two compare on it), every other method its own."""
    get_method(name)
    return name.removesuffix("-c2f")


NO_VARIANT = "none"
"""The EM variant recorded for methods without a mixture (ICP, CPD)."""


def method_variants(name, variants):
    """The EM variants method ``name`` runs under: each of ``variants`` for mixtures of sized primitives (mesh-*),
    textbook only for point mixtures (where every variant is the same algorithm), :data:`NO_VARIANT` for methods
    without a mixture."""
    spec = get_method(name)
    if not spec.needs_mixture:
        return [NO_VARIANT]
    return list(variants) if spec.representation in SIZED else ["textbook"]


def get_method(name):
    """The :class:`Method` called ``name``, or an InputError listing the known ones."""
    if name not in METHODS:
        raise InputError(f"registration method {name!r}: must be one of {tuple(METHODS)}")
    return METHODS[name]


def bounding_diagonal(points):
    """Length of the diagonal of the axis-aligned bounding box of ``points`` (n_points, 3)."""
    points = np.asarray(points, dtype=np.float64)
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def fit_mixture(method, vertices, faces, *, n_components, max_iter, tol, reg_covar, variant, seed, callback=None):
    """Fit the Gaussian mixture a P2D method registers to.

    Parameters
    ----------
    method : str
        A key of :data:`METHODS` that needs a mixture.
    vertices : ndarray of shape (n_vertices, 3)
    faces : ndarray of shape (n_faces, 3)
    n_components, max_iter, tol, reg_covar, variant
        Estimator settings (:class:`dgmm.GaussianMixture`).
    seed : int
        ``random_state`` of the fit.
    callback : callable, optional
        ``callback(iteration, model)`` after every EM iteration.

    Returns
    -------
    GaussianMixture
    """
    spec = get_method(method)
    if not spec.needs_mixture:
        raise InputError(f"registration method {method!r} uses no mixture")
    prims = REPRESENTATIONS[spec.representation](vertices, faces)
    return GaussianMixture(n_components, init=spec.init, max_iter=max_iter, tol=tol, reg_covar=reg_covar,
                           variant=variant, random_state=seed, callback=callback).fit(prims)


@dataclass(frozen=True)
class TrialSetup:
    """Everything one trial gives every method.

    Attributes
    ----------
    index : int
    trial : RigidTrial
        The motion applied to ``source``, about its centroid.
    source : ndarray of shape (n_points, 3)
        Points on the model: where a perfect registration brings the moved source back.
    target : ndarray of shape (n_points, 3)
        An independent draw from the same dense sample: the target of point-to-point methods.
    """

    index: int
    trial: RigidTrial
    source: np.ndarray
    target: np.ndarray

    @property
    def moved(self):
        """The source moved by the trial, shape (n_points, 3): what every method registers."""
        return self.trial.apply(self.source)


PROTOCOLS = ("scaled", "literal")
"""Trial translations: ``scaled`` by the model's diagonal over the bunny's, or the authors' ``literal`` ±0.05 in
the model's own units (registration_test.py, written for the bunny in metres, where both coincide). The P2D
mixtures' covariance floor follows the same choice (:func:`protocol_reg_covar`)."""


def _protocol_length(diagonal, protocol):
    """The length the bunny's diagonal stands for under ``protocol``: the model's ``diagonal`` (``scaled``), or
    the bunny's own in the model's units (``literal``)."""
    if protocol not in PROTOCOLS:
        raise InputError(f"trial protocol {protocol!r}: must be one of {PROTOCOLS}")
    return diagonal if protocol == "scaled" else BUNNY_DIAGONAL


def protocol_reg_covar(reg_covar, diagonal, protocol):
    """The covariance floor of a registration mixture under ``protocol``.

    ``reg_covar`` (scikit-learn's absolute 1e-6, as the authors ran it) is a variance in the model's units: on the
    bunny, in metres, it keeps every component at least 1 mm (0.4% of the diagonal) thick, but on the models in
    millimetres it allows components a thousandth of a millimetre thick, flat sheets on a 2 m statue. ``scaled``
    transfers the bunny's floor with the trials, ``reg_covar * (diagonal / BUNNY_DIAGONAL) ** 2``, so that a model
    and a scaled copy of it get scaled copies of one mixture; ``literal`` keeps ``reg_covar`` as it is.
    """
    length = _protocol_length(diagonal, protocol)
    if not (np.isfinite(length) and length > 0):
        raise InputError(f"diagonal must be a positive number, got {diagonal}")
    return float(reg_covar * (length / BUNNY_DIAGONAL) ** 2)


def make_trials(dense, n_points, indices, *, root_seed, key, diagonal, max_angle_deg=15.0, max_translation=0.05,
                protocol="scaled"):
    """The trials ``indices`` of the experiment ``key``, each from its own seed.

    Parameters
    ----------
    dense : array-like of shape (n_dense, 3)
        Dense surface sample of the model.
    n_points : int
        Source (and target) points per trial, at most ``n_dense``.
    indices : iterable of int
        Trial numbers; trial ``i`` is the same whatever other trials are asked for.
    root_seed : int
    key : str
        Names the experiment (model and mesh), so that experiments draw independent trials.
    diagonal : float
        The model's bounding-box diagonal, the scale of the trial translations.
    max_angle_deg, max_translation : float
        See :func:`dgmm.registration.random_trials`.
    protocol : {"scaled", "literal"}, default="scaled"
        See :data:`PROTOCOLS`: ``max_translation`` times ``diagonal / BUNNY_DIAGONAL``, or in model units.

    Returns
    -------
    list of TrialSetup
    """
    scale = _protocol_length(diagonal, protocol)  # random_trials scales by scale / BUNNY_DIAGONAL
    dense = np.asarray(dense, dtype=np.float64)
    if dense.ndim != 2 or dense.shape[1] != 3:
        raise InputError(f"dense sample must have shape (n_points, 3), got {dense.shape}")
    if not 1 <= int(n_points) <= len(dense):
        raise InputError(f"n_points must be between 1 and the dense sample's {len(dense)} points, got {n_points}")
    setups = []
    for index in indices:
        rng = np.random.default_rng(job_seed(root_seed, key, index))
        source = dense[rng.choice(len(dense), int(n_points), replace=False)]
        target = dense[rng.choice(len(dense), int(n_points), replace=False)]
        (trial,) = random_trials(1, rng, scale, source.mean(axis=0), max_angle_deg, max_translation)
        setups.append(TrialSetup(int(index), trial, source, target))
    return setups


def run_trials(method, setups, diagonal, *, mixture=None, options=None, recorder=None):
    """Register every trial's moved source with ``method`` and measure its errors.

    Parameters
    ----------
    method : str
        A key of :data:`METHODS`.
    setups : list of TrialSetup
    diagonal : float
        The model's bounding-box diagonal (translation errors are in percent of it).
    mixture : fitted Gaussian mixture, optional
        Required by P2D methods.
    options : dict, optional
        Keyword arguments of each algorithm's registration function, keyed by algorithm, e.g.
        ``{"p2d": {"gradient": "analytic"}, "icp": {"max_iter": 50000, "tol": 1e-9}}``.
    recorder : dgmm.recording.RegistrationRecorder, optional
        Receives every trial (``begin_trial``/``callback``/``end_trial``).

    Returns
    -------
    rows : list of dict
        One per trial, with the keys of :data:`COLUMNS`.
    seconds : list of float
        Wall time of each registration (for trials recorded iteration by iteration, logging included).
    """
    spec = get_method(method)
    if spec.needs_mixture and mixture is None:
        raise InputError(f"registration method {method!r} needs a fitted mixture")
    register = _ALGORITHMS[spec.algorithm]
    settings = (options or {}).get(spec.algorithm, {})
    rows, seconds = [], []
    for setup in setups:
        shown_target = None if spec.needs_mixture else setup.target
        callback = None if recorder is None else recorder.begin_trial(setup.index, setup.trial, setup.source,
                                                                      shown_target)
        start = time.perf_counter()
        result = register(setup.moved, setup.target, mixture, callback=callback, **settings)
        seconds.append(time.perf_counter() - start)
        rotation_error, translation_error = registration_errors(result, setup.trial, diagonal)
        if recorder is not None:
            recorder.end_trial(result, rotation_error, translation_error)
        rows.append({"trial": setup.index, "rotation_error_deg": rotation_error,
                     "translation_error_pct": translation_error, "iterations": result.iterations,
                     "converged": result.converged})
    return rows, seconds
