"""The covariance of a pixel primitive: a flat patch of its footprint, or the authors' disparity box.

Both are read from the authors' odometry notebooks (leonidk/direct_gmm, ``gen_gmm-mine-patch.ipynb`` and
``gen_gmm-mine.ipynb``, the pixel primitives of paper §VI-D): every ``step``-th pixel of every ``step``-th row stands
for the ``step × step`` pixel block around it, seen at its depth ``Z``.

- ``"patch"``: the uniform distribution over the block's footprint, a camera-aligned rectangle
  ``w_x = step Z / fx`` by ``w_y = step Z / fy`` metres at depth ``Z``: ``diag(w_x² / 12, w_y² / 12, 0)``.
- ``"disparity"``: the notebook's box from the footprint and a ±1 px disparity error of a stereo pair of
  ``baseline`` 0.075 m: disparity ``d = fx b / Z`` (clipped to 2..325 px after the ±1) gives the nearer depth
  ``z_f = fx b / (d + 1)`` and the farther ``z_b = fx b / (d - 1)``. Eight points are built as the notebook builds
  them, for the block's half-width ``h = step / 2`` px, at each of the rows ``v - cy ± h``: the ray of column
  offset ``u - cx + h`` at depths ``z_f`` and ``Z``, and the ray of offset ``u - cx - h`` at depths ``Z`` and
  ``z_b`` (not the eight corners of a box: the near point lies on the right ray, the far one on the left). The
  covariance is the notebook's ``Σ_c (c cᵀ - m mᵀ) / 12`` over those points, ``m`` their mean: 8/12 of their own
  covariance, twice the uniform covariance a parallelepiped with such corners would have (its corners' covariance is
  three times its uniform one). The primitive's mean stays the pixel's back-projected point.

Kept exactly as the notebooks compute them (reproducing the authors' protocol), factors and all; each is a pure
function of the pixels' camera-frame points, vectorised over them.
"""
from __future__ import annotations

import numpy as np

from dgmm.errors import InputError

BASELINE = 0.075
"""Stereo baseline (metres) of the notebook's disparity error model (the Kinect's projector-camera baseline)."""

DISPARITY_ERROR = 1.0
"""The notebook's disparity error, pixels (``size_of_disp_error``)."""

DISPARITY_RANGE = (2.0, 325.0)
"""The notebook's clip of the disparities ``d ± 1`` (``min_disp``, ``max_disp``: ``fx b / 0.125`` m rounded up)."""


def patch_covariances(points, intrinsics, step):
    """``diag((step Z/fx)² / 12, (step Z/fy)² / 12, 0)`` of every point (``Z`` its depth): the uniform distribution
    over its pixel block's footprint, flat in the camera's view direction.

    Parameters
    ----------
    points : ndarray of shape (n, 3)
        Camera-frame points of pixels with a measurement (``Z > 0``).
    intrinsics : dgmm.odometry.pixels.Intrinsics
    step : int
        The pixel grid's step: each point stands for a ``step × step`` block.

    Returns
    -------
    covariances : ndarray of shape (n, 3, 3)
    """
    depth = points[:, 2]
    covariances = np.zeros((len(points), 3, 3))
    covariances[:, 0, 0] = (step * depth / intrinsics.fx) ** 2 / 12.0
    covariances[:, 1, 1] = (step * depth / intrinsics.fy) ** 2 / 12.0
    return covariances


def disparity_box_points(points, intrinsics, step, baseline=BASELINE, disparity_error=DISPARITY_ERROR,
                         disparity_range=DISPARITY_RANGE):
    """The eight points of the notebook's disparity box of every pixel (see the module's docstring).

    Returns
    -------
    box : ndarray of shape (8, n, 3)
        The notebook's order: (front, left, right, back) at the row offset ``+h``, then the same at ``-h``.
    """
    depth = points[:, 2]
    # the pixel's offsets from the principal point, u - cx and v - cy, from its back-projection
    du, dv = points[:, 0] / depth * intrinsics.fx, points[:, 1] / depth * intrinsics.fy
    disparity = intrinsics.fx * baseline / depth
    near = intrinsics.fx * baseline / np.clip(disparity + disparity_error, *disparity_range)
    far = intrinsics.fx * baseline / np.clip(disparity - disparity_error, *disparity_range)
    half = 0.5 * step
    right, left = (du + half) / intrinsics.fx, (du - half) / intrinsics.fx
    corners = []
    for row in ((dv + half) / intrinsics.fy, (dv - half) / intrinsics.fy):
        for column, z in ((right, near), (left, depth), (right, depth), (left, far)):
            corners.append(np.stack([column * z, row * z, z], axis=1))
    return np.stack(corners)


def disparity_box_covariances(points, intrinsics, step, baseline=BASELINE, disparity_error=DISPARITY_ERROR,
                              disparity_range=DISPARITY_RANGE):
    """The notebook's covariance of every pixel's disparity box: ``Σ_c (c cᵀ - m mᵀ) / 12`` over the eight points
    ``c`` of :func:`disparity_box_points`, ``m`` their mean.

    Parameters
    ----------
    points : ndarray of shape (n, 3)
        Camera-frame points of pixels with a measurement (``Z > 0``).
    intrinsics : dgmm.odometry.pixels.Intrinsics
    step : int
        The pixel grid's step: each point stands for a ``step × step`` block.
    baseline, disparity_error, disparity_range
        The error model: metres, pixels, and the clip of the disparities (pixels).

    Returns
    -------
    covariances : ndarray of shape (n, 3, 3)
    """
    box = disparity_box_points(points, intrinsics, step, baseline, disparity_error, disparity_range)
    offsets = box - box.mean(axis=0)
    return np.einsum("cni,cnj->nij", offsets, offsets) / 12.0


# covariance -> function(points, intrinsics, step) -> covariances of the pixel primitives
PIXEL_COVARIANCES = {"patch": patch_covariances, "disparity": disparity_box_covariances}


def pixel_covariances(kind, points, intrinsics, step):
    """Covariances of the pixel primitives at ``points`` by name (:data:`PIXEL_COVARIANCES`).

    Raises
    ------
    InputError
        An unknown ``kind``.
    """
    if kind not in PIXEL_COVARIANCES:
        raise InputError(f"pixel covariance must be one of {sorted(PIXEL_COVARIANCES)}, got {kind!r}")
    return PIXEL_COVARIANCES[kind](points, intrinsics, step)
