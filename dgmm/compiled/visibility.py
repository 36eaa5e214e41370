"""Which of a frame's points another odometry frame measured, compiled with numba (the cut rounds' visibility
test, :func:`dgmm.odometry.measured_cut.unseen_primitives`): one pass over the points instead of numpy's dozen
temporaries of the frame's size per test."""
from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True, error_model="numpy")
def seen_on_grid(points, rotation, translation, camera, step, measured):
    """Whether each point, moved to ``R x + t``, is in front of the camera and nearest to a pixel of the grid
    ``measured`` (``u, v`` multiples of ``step``) that measured depth.

    Parameters
    ----------
    points : ndarray of shape (n, 3)
    rotation : ndarray of shape (3, 3)
    translation : ndarray of shape (3,)
    camera : ndarray of shape (4,)
        ``fx, fy, cx, cy``.
    step : int
    measured : ndarray of bool, shape (n_rows, n_cols)

    Returns
    -------
    seen : ndarray of bool, shape (n,)
        As :func:`dgmm.odometry.measured_cut.seen_by` of the moved points: ``u = fx x / z + cx``,
        ``v = fy y / z + cy`` rounded half to even to the grid.
    """
    n_rows, n_cols = measured.shape
    fx, fy, cx, cy = camera[0], camera[1], camera[2], camera[3]
    seen = np.zeros(points.shape[0], dtype=np.bool_)
    for i in range(points.shape[0]):
        x, y, z = points[i, 0], points[i, 1], points[i, 2]
        moved_z = rotation[2, 0] * x + rotation[2, 1] * y + rotation[2, 2] * z + translation[2]
        if moved_z <= 0:
            continue
        moved_x = rotation[0, 0] * x + rotation[0, 1] * y + rotation[0, 2] * z + translation[0]
        moved_y = rotation[1, 0] * x + rotation[1, 1] * y + rotation[1, 2] * z + translation[1]
        col = np.rint((fx * moved_x / moved_z + cx) / step)
        row = np.rint((fy * moved_y / moved_z + cy) / step)
        if 0 <= col < n_cols and 0 <= row < n_rows:
            seen[i] = measured[int(row), int(col)]
    return seen
