"""Input checks shared by the registration modules: arrays of a given shape, finite, float64."""
from __future__ import annotations

import numpy as np

from dgmm.errors import InputError


def as_array(name, array, shape):
    """Return ``array`` as float64 of ``shape`` (``None`` entries are free, but at least 1), or raise."""
    try:
        values = np.asarray(array, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} is not a numeric array: {exc}") from None
    expected = "(" + ", ".join("n" if size is None else str(size) for size in shape) + ")"
    if values.ndim != len(shape) or any(size is not None and got != size for got, size in zip(values.shape, shape)):
        raise InputError(f"{name} must have shape {expected}, got {values.shape}")
    if values.size == 0:
        raise InputError(f"{name} is empty")
    if not np.all(np.isfinite(values)):
        raise InputError(f"{name} contains NaN or infinite values")
    return values


def as_points(name, points):
    """Return ``points`` as a finite float64 array of shape (n_points, 3) with n_points >= 1, or raise."""
    return as_array(name, points, (None, 3))

