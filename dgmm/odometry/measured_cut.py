"""D2D of two odometry frames on what each measured of the other (the schedule's ``cut_rounds``).

Each frame's mixture covers only what its camera measured. Where the other frame measured nothing (outside its
image, or in its band of invalid depth: TUM's pre-registered fr1 depth has no measurement in its first rows and last
columns) a component is cut off by a boundary that moves with the camera, and D2D prefers to keep those boundaries
together: it is pulled toward the identity and under-measures the motion (fr1/xyz: lateral translation over 10
frames at 0.82 of the truth). From a first registration's pose, every primitive that does not land on a measured
pixel of the other frame is taken out of its frame's mixture (:func:`cut`) and D2D runs again from that pose on the
two cut mixtures (:func:`register_measured`), round after round until the pose settles (:func:`register_cut_rounds`).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from dgmm.gaussian import layout
from dgmm.mixture import EStep
from dgmm.odometry.overlap import centroid_and_radius
from dgmm.registration import FittedMixture, register_d2d
from dgmm.variants import VARIANTS

_MIN_MASS = 1e-3
"""A component that keeps less than this fraction of its mass is dropped (weight 0) rather than re-estimated."""


@dataclass(frozen=True)
class MeasuredFrame:
    """A frame's fitted mixture with the primitives it was fitted to and the pixels that measured depth.

    Reads as the mixture (``weights_``, ``means_``, ``covariances_``, ``precisions_cholesky_``), so registration,
    warm starts and recorders take it in its place.

    Attributes
    ----------
    mixture : dgmm.GaussianMixture
    primitives : dgmm.Primitives
        In camera coordinates.
    measured : ndarray of bool, shape (n_rows, n_cols)
        The grid ``depth[::step, ::step] > 0``.
    intrinsics : dgmm.odometry.pixels.Intrinsics
    step : int
    variant : str
        The EM variant the mixture was fitted with (its M-step weights).
    refit_seed : int or None
        Seeds every refit of the frame on a common view (the ``common-view`` schedule), so that runs repeat.
    """

    mixture: object
    primitives: object
    measured: np.ndarray
    intrinsics: object
    step: int
    variant: str
    refit_seed: int | None = None

    def __getattr__(self, name):  # the fitted attributes of the mixture
        if name.endswith("_") and not name.startswith("_"):
            return getattr(self.mixture, name)
        raise AttributeError(name)

    @cached_property
    def last_e_step(self):
        """The E-step of the fit's last M-step (under ``mixture.e_step_params_``, screened as the fit was), set up
        once for every cut, with its coefficients laid out for :func:`dgmm.compiled.e_step.screened_e_step_sums`."""
        e_step = EStep(*self.mixture.e_step_params_, screen=self.mixture.screen)
        return e_step, np.ascontiguousarray(e_step.coefficients.T)

    @cached_property
    def variant_weights(self):
        """The variant's E-step scale and M-step weight of every primitive (:data:`dgmm.variants.VARIANTS`)."""
        return VARIANTS[self.variant](self.primitives.weights)


def seen_by(points, frame, rotation=None, translation=None):
    """Which points, moved by ``(rotation, translation)`` into ``frame``'s camera, project onto a pixel of its grid
    that measured depth (:func:`dgmm.compiled.visibility.seen_on_grid`).

    Parameters
    ----------
    points : ndarray of shape (n, 3)
    frame : MeasuredFrame
    rotation : ndarray of shape (3, 3), optional
        The identity when omitted: ``points`` in ``frame``'s camera coordinates.
    translation : ndarray of shape (3,), optional
        Zero when omitted.

    Returns
    -------
    seen : ndarray of bool, shape (n,)
        In front of the camera and nearest to a grid pixel (``u, v`` multiples of ``step``) with a measurement.
    """
    from dgmm.compiled.visibility import seen_on_grid  # numba loads only for the schedules that cut
    rotation = np.eye(3) if rotation is None else np.ascontiguousarray(rotation, dtype=float)
    translation = np.zeros(3) if translation is None else np.asarray(translation, dtype=float)
    camera = frame.intrinsics
    return seen_on_grid(np.ascontiguousarray(points, dtype=float), rotation, translation,
                        np.array([camera.fx, camera.fy, camera.cx, camera.cy]), frame.step, frame.measured)


def unseen_primitives(fixed, moving, rotation, translation):
    """The primitives of each frame that the other does not measure at the pose ``x_fixed = R x_moving + t``.

    Returns
    -------
    fixed_unseen, moving_unseen : ndarrays of bool, shape (n_primitives,) of each frame
    """
    fixed_unseen = ~seen_by(fixed.primitives.means, moving, rotation.T, -rotation.T @ translation)
    moving_unseen = ~seen_by(moving.primitives.means, fixed, rotation, translation)
    return fixed_unseen, moving_unseen


def cut(frame, unseen):
    """The frame's mixture without the primitives ``unseen``: each component's M-step moments less theirs.

    Component ``k`` of the fitted mixture holds mass ``M_k = π_k Σ_p a_p`` (``a_p`` the variant's M-step weights)
    with mean ``μ_k`` and covariance ``Σ_k``; the unseen primitives contribute ``m_k = Σ r_pk a_p``,
    ``s_k = Σ r_pk a_p (x_p - μ_k)`` and ``T_k = Σ r_pk a_p ((x_p - μ_k)(x_p - μ_k)ᵀ + C_p)`` with the
    responsibilities ``r_pk`` of the fit's last M-step (the variant's E-step under the parameters before it,
    ``e_step_params_``). What is left: mass ``M_k - m_k``, mean ``μ_k - s_k / (M_k - m_k)`` and covariance
    ``(M_k Σ_k - T_k) / (M_k - m_k) - d dᵀ`` with ``d`` that shift: exactly the last M-step over the seen primitives,
    converged or not (``reg_covar`` is taken off the fitted covariances and added back). A component left with less
    than ``_MIN_MASS`` of its mass gets weight 0; if every component does, the mixture is returned uncut.

    Parameters
    ----------
    frame : MeasuredFrame
    unseen : ndarray of bool, shape (n_primitives,)

    Returns
    -------
    weights, means, covariances : ndarrays of shape (K,), (K, 3), (K, 3, 3)
    """
    from dgmm.compiled.measured_cut import cut_components  # numba loads only for the schedules that cut
    mixture = frame.mixture
    weights, means = mixture.weights_, mixture.means_
    rows = np.flatnonzero(unseen)
    if not len(rows):
        return weights, means, mixture.covariances_
    regulariser = mixture.reg_covar * np.eye(3)  # the M-step adds it to every covariance: the moments are without
    e_step = frame.last_e_step[0]
    left, means, covariances = cut_components(means, mixture.covariances_ - regulariser,
                                              weights * frame.variant_weights[1].sum(), unseen_sums(frame, rows),
                                              e_step.centre, e_step.unit, _MIN_MASS)
    if not left.any():  # the other frame sees none of it: nothing to cut to
        return weights, mixture.means_, mixture.covariances_
    return left / left.sum(), means, covariances + regulariser


def unseen_sums(frame, rows):
    """The M-step sums of the primitives ``rows`` under the responsibilities of the fit's last E-step, about the
    E-step's centre ``c`` in its unit ``u``: ``Σ r_pk a_p`` times the moment table's columns ``xx, yy, zz, 2xy, 2xz,
    2yz, x, y, z, 1`` of ``(x_p - c) / u`` (``C_p / u²`` on the second moments), shape (K, 10); one compiled pass
    (:func:`dgmm.compiled.e_step.screened_e_step_sums`, the fit's own E-step kernel, screened as the fit was)."""
    from dgmm.compiled.e_step import moment_table, screened_e_step_sums  # numba loads only for the schedules that cut
    e_step, coefficients = frame.last_e_step
    scale, mstep_weights = frame.variant_weights
    n_quadratic = layout(3).n_quadratic
    moments = moment_table(frame.primitives.means[rows], frame.primitives.covariances[rows], e_step.centre,
                           float(e_step.unit))  # mixture._moment_features' values, in one pass
    features = moments.copy()
    features[:, :n_quadratic] *= scale[rows, None]
    screen = np.inf if e_step.screen is None else float(e_step.screen)
    return screened_e_step_sums(features, coefficients, np.ascontiguousarray(moments[:, :n_quadratic]),
                                mstep_weights[rows], screen, np.empty(len(rows)))


def _cut_mixture(frame, unseen):
    """The frame's mixture cut to its seen primitives (:func:`cut`), components of weight 0 left out, as the
    :class:`~dgmm.registration.fitted.FittedMixture` that D2D reads: its arrays are float64 of the right shapes
    and its weights positive by construction, so D2D's input checks are skipped."""
    weights, means, covariances = cut(frame, unseen)
    keep = weights > 0
    precisions_cholesky = np.transpose(np.linalg.inv(np.linalg.cholesky(covariances[keep])), (0, 2, 1))
    return FittedMixture(weights[keep], means[keep], covariances[keep], precisions_cholesky)


def register_measured(fixed, moving, first, solver="gauss-newton", options=None):
    """D2D from the pose of the registration ``first`` on the parts of each frame the other measures there.

    Parameters
    ----------
    fixed, moving : MeasuredFrame
    first : Registration
        ``x_fixed = R x_moving + t`` of the whole frames.
    solver : {"bfgs", "gauss-newton"}
    options : dict, optional
        The solver's (:func:`dgmm.registration.register_d2d`).

    Returns
    -------
    Registration
        The second registration, ``seconds`` and ``iterations`` counting both.
    """
    rotation, translation = first.rotation, first.translation
    fixed_unseen, moving_unseen = unseen_primitives(fixed, moving, rotation, translation)
    second = register_d2d(_cut_mixture(fixed, fixed_unseen), _cut_mixture(moving, moving_unseen),
                          initial_rotation=rotation, initial_translation=translation, options=options, solver=solver)
    return dataclasses.replace(second, iterations=first.iterations + second.iterations,
                               seconds=first.seconds + second.seconds)


def register_cut_rounds(fixed, moving, first, rounds, tol, solver="gauss-newton", options=None):
    """Up to ``rounds`` of :func:`register_measured`, each from the pose before, until a round moves the pose by
    less than ``tol``.

    A cut at a pose some centimetres off keeps part of the pull toward the identity, and each round removes most of
    what is left (fr1/xyz: the pose moves by a median 4.4, 0.38 and 0.07 mm in the first three rounds); a round
    that moves it by less than ``tol`` leaves less than that to the next.

    Parameters
    ----------
    fixed, moving : MeasuredFrame
    first : Registration
        ``x_fixed = R x_moving + t`` of the whole frames.
    rounds : int
        At most this many rounds.
    tol : float
        Rounds stop once the moving mixture's weighted centroid moves by less than ``tol`` RMS radii (its weighted
        spread about that centroid) and the rotation by less than ``tol`` radians.
    solver, options
        Of :func:`register_measured`.

    Returns
    -------
    Registration
        The last round's, ``seconds`` and ``iterations`` counting every round and ``first``.
    """
    centroid, radius = centroid_and_radius(moving)
    registration = first
    for _ in range(int(rounds)):
        before, registration = registration, register_measured(fixed, moving, registration, solver, options)
        if pose_change(before, registration, centroid, radius) < tol:
            break
    return registration


def pose_change(first, second, centroid, radius):
    """How far apart two poses ``x -> R x + t`` are: the larger of the distance between the images of ``centroid``
    in ``radius`` units and the angle of ``R_2 R_1ᵀ`` in radians (Gauss-Newton's stopping measure, between poses).

    The angle ``θ`` from the chord ``|R_2 - R_1|_F = 2√2 sin(θ / 2)``: exact for rotations and accurate at small
    angles, without scipy's rotation conversion, which the stopping test would pay at every step."""
    shift = second.rotation @ centroid + second.translation - first.rotation @ centroid - first.translation
    chord = np.linalg.norm(second.rotation - first.rotation) / (2.0 * np.sqrt(2.0))
    return max(np.linalg.norm(shift) / radius, 2.0 * np.arcsin(min(chord, 1.0)))
