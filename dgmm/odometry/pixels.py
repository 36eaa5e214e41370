"""Depth pixels as geometry: pinhole intrinsics of TUM's cameras, back-projection and pixel-rectangle primitives.

Camera frame: optical, x right, y down, z forward; pixel ``(u, v)`` is (column, row). Depth in metres, 0 = no
measurement (``dgmm.odometry.tum.read_depth``).
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from dgmm.errors import InputError
from dgmm.odometry.pixel_covariance import PIXEL_COVARIANCES
from dgmm.primitives import Primitives

PIXEL_STEP = 4
"""Back-project every 4th pixel of every 4th row: 640×480 → 160×120 (paper §VI-D)."""


# ------------------------------------------------------------------------------------------------ camera
@dataclass(frozen=True)
class Intrinsics:
    """Pinhole intrinsics in pixels and the image size.

    Attributes
    ----------
    fx, fy, cx, cy : float
    width, height : int
    """

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int

    def rays(self, step=1):
        """Camera-frame rays ``((u − cx)/fx, (v − cy)/fy, 1)`` through every ``step``-th pixel.

        Parameters
        ----------
        step : int
            Pixels ``u = 0, step, 2 step, …`` and ``v`` likewise: the grid ``depth[::step, ::step]``.

        Returns
        -------
        rays : ndarray of shape (n_rows * n_cols, 3)
            Raster order (row-major), ``n_rows = ceil(height / step)``; a point at depth ``Z`` is ``Z * ray``.
        """
        v, u = np.mgrid[0:self.height:step, 0:self.width:step]
        return np.stack([(u.ravel() - self.cx) / self.fx, (v.ravel() - self.cy) / self.fy,
                         np.ones(u.size)], axis=1)

    def project(self, points):
        """Pixel coordinates of camera-frame points, and which are in front of the camera.

        Parameters
        ----------
        points : ndarray of shape (n, 3)

        Returns
        -------
        u, v : ndarrays of shape (n,)
            ``fx x / z + cx`` and ``fy y / z + cy`` (for points not in front, as if ``z`` were 1).
        front : ndarray of bool, shape (n,)
            ``z > 0``.
        """
        front = points[:, 2] > 0
        depth = np.where(front, points[:, 2], 1.0)
        return self.fx * points[:, 0] / depth + self.cx, self.fy * points[:, 1] / depth + self.cy, front


CAMERAS = {
    "fr1": Intrinsics(fx=517.3, fy=516.5, cx=318.6, cy=255.3, width=640, height=480),
    "fr2": Intrinsics(fx=520.9, fy=521.0, cx=325.1, cy=249.7, width=640, height=480),
    "fr3": Intrinsics(fx=535.4, fy=539.2, cx=320.1, cy=247.6, width=640, height=480),
    "ros": Intrinsics(fx=525.0, fy=525.0, cx=319.5, cy=239.5, width=640, height=480),
}
"""TUM's calibrated depth cameras (freiburg 1, 2, 3; "Intrinsic Camera Calibration of the Kinect") and the ROS
default that TUM recommends for the pre-registered depth images of freiburg 1 and 2 (fr3's are registered to its
calibration). fr1 and fr2 also have lens distortion, which dgmm does not model."""

FR3 = CAMERAS["fr3"]
"""Freiburg 3 depth camera (the paper's sequence and the synthetic one)."""

SEQUENCE_CAMERAS = {"1": "ros", "2": "ros", "3": "fr3"}
"""TUM's ``rgbd_dataset_freiburgN_*`` -> the default intrinsics (``CAMERAS`` key) for its depth images: the ROS
default for freiburg 1 and 2 (TUM's advice for their pre-registered depth; docs/user_guide/odometry.md measures it
against the fr1 calibration), the calibration for freiburg 3."""


def parse_intrinsics(text, width=640, height=480):
    """Intrinsics named ``fr1|fr2|fr3|ros`` or given as ``FX,FY,CX,CY`` (pixels; 640×480 unless stated).

    Raises
    ------
    InputError
        Another name, or not four positive finite numbers.
    """
    if text in CAMERAS:
        return CAMERAS[text]
    try:
        fx, fy, cx, cy = (float(value) for value in str(text).split(","))
    except ValueError:
        raise InputError(f"intrinsics must be one of {', '.join(CAMERAS)} or FX,FY,CX,CY, got {text!r}") from None
    if not all(np.isfinite([fx, fy, cx, cy])) or min(fx, fy) <= 0:
        raise InputError(f"intrinsics FX,FY,CX,CY must be finite with FX, FY > 0, got {text!r}")
    return Intrinsics(fx, fy, cx, cy, width, height)


def sequence_intrinsics(folder_name):
    """Default intrinsics of a TUM sequence from its folder name (``rgbd_dataset_freiburgN_*``).

    Returns
    -------
    name : str
        The ``CAMERAS`` key.

    Raises
    ------
    InputError
        The name does not say which freiburg camera recorded it.
    """
    match = re.search(r"freiburg([123])", str(folder_name))
    if match is None:
        raise InputError(f"cannot tell the camera from the sequence name {folder_name!r} (no freiburg1/2/3 in it): "
                         f"give the intrinsics ({', '.join(CAMERAS)} or FX,FY,CX,CY)")
    return SEQUENCE_CAMERAS[match.group(1)]


def _grid_depth(depth, intrinsics, step):
    """``depth[::step, ::step]`` flattened, after checking the image matches the intrinsics."""
    depth = np.asarray(depth, dtype=np.float64)
    if depth.shape != (intrinsics.height, intrinsics.width):
        raise InputError(f"depth must have shape ({intrinsics.height}, {intrinsics.width}), got {depth.shape}")
    return depth[::step, ::step].ravel()


def backproject(depth, intrinsics=FR3, step=PIXEL_STEP):
    """Camera-frame points of every ``step``-th pixel with a measurement.

    Parameters
    ----------
    depth : array-like of shape (height, width)
        Metres, 0 = no measurement.
    intrinsics : Intrinsics
    step : int

    Returns
    -------
    points : ndarray of shape (n_valid, 3)
        ``Z ((u − cx)/fx, (v − cy)/fy, 1)`` in raster order, zero-depth pixels dropped.
    """
    z = _grid_depth(depth, intrinsics, step)
    valid = z > 0
    return intrinsics.rays(step)[valid] * z[valid, None]


def _unit_sizes(width_x, width_y):
    return np.ones_like(width_x)


def _area_sizes(width_x, width_y):
    return width_x * width_y


# size -> function(widths in x, widths in y) -> alpha_p
PIXEL_SIZES = {"area": _area_sizes, "unit": _unit_sizes}


def pixel_primitives(depth, intrinsics=FR3, step=PIXEL_STEP, size="area", covariance="patch"):
    """Every ``step``-th pixel as a primitive (paper §VI-D, the uncertainty primitive): its back-projected point,
    a covariance and a size.

    The pixel block seen at depth ``Z`` covers ``w_x = step Z / fx`` by ``w_y = step Z / fy`` metres; the
    uniform distribution over that rectangle has covariance ``diag(w_x² / 12, w_y² / 12, 0)`` in the camera frame
    (``"patch"``); ``"disparity"`` is the authors' box from that footprint and a ±1 px disparity error
    (:mod:`dgmm.odometry.pixel_covariance`).

    Parameters
    ----------
    depth : array-like of shape (height, width)
        Metres, 0 = no measurement.
    intrinsics : Intrinsics
    step : int
    size : {"area", "unit"}, default="area"
        ``alpha_p``: the paper defines a primitive's size as its extent ``∫_S dS`` (§"Generalization to other
        primitives"), here the footprint area ``w_x w_y``; this also undoes the ``1/Z²`` density of pixels on
        the surface. ``"unit"`` counts every pixel once, as the plain points do (and as the authors' odometry
        notebooks do: ``set_areas(np.ones(n))``).
    covariance : {"patch", "disparity"}, default="patch"
        The primitive's covariance (:data:`dgmm.odometry.pixel_covariance.PIXEL_COVARIANCES`).

    Returns
    -------
    Primitives
        ``n_valid`` primitives in raster order, zero-depth pixels dropped.
    """
    if size not in PIXEL_SIZES:
        raise InputError(f"size must be one of {sorted(PIXEL_SIZES)}, got {size!r}")
    if covariance not in PIXEL_COVARIANCES:
        raise InputError(f"covariance must be one of {sorted(PIXEL_COVARIANCES)}, got {covariance!r}")
    points = backproject(depth, intrinsics, step)
    width_x, width_y = step * points[:, 2] / intrinsics.fx, step * points[:, 2] / intrinsics.fy
    return Primitives(points, PIXEL_COVARIANCES[covariance](points, intrinsics, step),
                      PIXEL_SIZES[size](width_x, width_y))
