"""P2D registration that does not stop in a wrong basin: a coarse-to-fine schedule on the mixture's covariances.

The paper's P2D (:func:`dgmm.registration.register_p2d`) runs one BFGS from the identity on the likelihood of the
moved points under the fitted mixture. A mixture fitted to a mesh has flat, thin components (a 1000-face mesh's
triangles are a few percent of the model wide and a fraction of a percent thick), so its likelihood is a landscape
of narrow ridges: when the trial's motion is several components wide, the first BFGS steps can pull the points
onto a neighbouring sheet of the surface and stop there.

:func:`register_p2d_coarse_to_fine` does what NDT and gmmreg do against this: it registers first to the mixture
with every covariance widened by an isotropic ``(scale * radius)^2``, ``radius`` the RMS radius of the source
points about their centroid, which smooths the ridges into one broad basin, then narrows the scale stage by stage,
each stage starting from the pose of the one before, and ends on the mixture itself. Every stage is the paper's
P2D (one BFGS, rotating about the source centroid), run on the source moved by the poses found so far.
"""
from __future__ import annotations

import time

import numpy as np

from dgmm.errors import InputError
from dgmm.registration.p2d import register_p2d
from dgmm.registration.pose import Registration

SCALES = (0.5, 0.25, 0.125, 0.0625, 0.0)
"""Default schedule: widening of the covariances, in RMS radii of the source; the last stage must be 0."""


class WidenedMixture:
    """The fitted arrays of ``mixture`` with ``variance * I`` added to every covariance (what P2D reads).

    Parameters
    ----------
    mixture : fitted Gaussian mixture
        Any object with ``weights_``, ``means_`` and ``covariances_`` (n_components, 3, 3).
    variance : float
        Non-negative isotropic variance added to each covariance.
    """

    def __init__(self, mixture, variance):
        self.weights_ = np.asarray(mixture.weights_, dtype=np.float64)
        self.means_ = np.asarray(mixture.means_, dtype=np.float64)
        self.covariances_ = np.asarray(mixture.covariances_, dtype=np.float64) + variance * np.eye(3)
        # Upper-triangular U with U Uᵀ = Σ⁻¹ (scikit-learn's precisions_cholesky_): U = L⁻ᵀ for Σ = L Lᵀ.
        lower = np.linalg.cholesky(self.covariances_)
        self.precisions_cholesky_ = np.linalg.inv(lower).transpose(0, 2, 1)


def _check_scales(scales, end_at_zero=True):
    """The schedule as a tuple of floats: non-increasing, non-negative, ending at 0 (unless not ``end_at_zero``);
    else an InputError."""
    values = tuple(float(scale) for scale in scales)
    if (not values or (end_at_zero and values[-1] != 0.0) or any(b > a for a, b in zip(values, values[1:]))
            or min(values) < 0):
        ending = " and end with 0" if end_at_zero else ""
        raise InputError(f"scales must be non-negative, non-increasing{ending}, got {list(scales)}")
    return values


def register_p2d_coarse_to_fine(source, mixture, scales=SCALES, gradient="analytic", callback=None, options=None):
    """P2D registration over a coarse-to-fine schedule of widened mixtures.

    Parameters
    ----------
    source : array-like of shape (n_points, 3)
        Points to move into the mixture's frame.
    mixture : fitted Gaussian mixture
        As for :func:`dgmm.registration.register_p2d`.
    scales : sequence of float, default=SCALES
        Standard deviation added to every component at each stage, in RMS radii of the source about its centroid;
        non-increasing, ending with 0 (the mixture itself).
    gradient : {"analytic", "numeric"}, default="analytic"
        Gradient of every stage's BFGS.
    callback : callable, optional
        ``callback(iteration, registration)`` after every BFGS iteration of every stage, counted across stages,
        with the current global pose.
    options : dict, optional
        Options of every stage's BFGS (``scipy.optimize.minimize``).

    Returns
    -------
    Registration
        The composed pose; ``iterations`` summed over the stages; ``objective`` and ``converged`` of the last
        stage (the negative mean log-likelihood under the mixture itself); ``method`` ``"p2d-c2f"``.
    """
    scales = _check_scales(scales)
    points = np.asarray(source, dtype=np.float64)
    if points.ndim != 2 or points.shape[1:] != (3,) or len(points) == 0 or not np.all(np.isfinite(points)):
        raise InputError(f"source must be finite with shape (n_points, 3), got {points.shape}")
    radius = float(np.sqrt(np.mean(np.sum((points - points.mean(axis=0)) ** 2, axis=1))))
    start = time.perf_counter()
    rotation, translation = np.eye(3), np.zeros(3)
    done = 0
    for scale in scales:
        stage_mixture = WidenedMixture(mixture, (scale * radius) ** 2) if scale > 0 else mixture
        moved = points @ rotation.T + translation
        stage_callback = None
        if callback is not None:
            def stage_callback(iteration, step, base=(rotation, translation, done)):
                callback(base[2] + iteration, _compose(step, *base[:2], base[2] + iteration, start))
        step = register_p2d(moved, stage_mixture, gradient=gradient, callback=stage_callback, options=options)
        rotation, translation = step.rotation @ rotation, step.rotation @ translation + step.translation
        done += step.iterations
    return Registration(rotation, translation, done, time.perf_counter() - start, step.objective, step.converged,
                        "p2d-c2f")


def _compose(step, rotation, translation, iterations, start):
    """The global pose of a stage's ``step`` after the pose ``(rotation, translation)`` found so far."""
    return Registration(step.rotation @ rotation, step.rotation @ translation + step.translation, iterations,
                        time.perf_counter() - start, step.objective, False, "p2d-c2f")
