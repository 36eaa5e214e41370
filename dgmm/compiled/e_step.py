"""EM's responsibilities with the pairs far below a primitive's best left at 0, compiled with numba.

The E-step's time goes to ``exp`` of every (component, primitive) pair's ``log rho``; on a surface most pairs are
far below the primitive's best component (fr1/xyz frames at K = 100: 91% more than 50 nats below). With a screen
``s``, terms ``exp(log rho - peak)`` below ``e^-s`` are 0 and their exponentials are skipped: at ``s = 50`` each
changes its primitive's sum (at least 1) by under ``2e-22``, below rounding for up to 10⁵ components, so a screened
fit equals the unscreened one to rounding. Beyond the paper (which computes every pair); opted into by
``GaussianMixture(screen=...)``, the odometry frames' mixtures (:mod:`dgmm.odometry.frame_model`).
"""
from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True, nogil=True, error_model="numpy")
def exp_shifted_screened(log_rho, screen):
    """Replace ``log rho`` (n_components, n_rows) by ``exp(log rho - peak)`` where that is above ``e^-screen``,
    else 0, in place; return ``peak`` and the column sums, both (n_rows,)."""
    n_components, n_rows = log_rho.shape
    peak = np.full(n_rows, -np.inf)
    for i in range(n_components):
        for j in range(n_rows):
            peak[j] = max(peak[j], log_rho[i, j])
    total = np.zeros(n_rows)
    for i in range(n_components):
        for j in range(n_rows):
            shifted = log_rho[i, j] - peak[j]
            if shifted > -screen:
                log_rho[i, j] = math.exp(shifted)
                total[j] += log_rho[i, j]
            else:
                log_rho[i, j] = 0.0
    return peak, total
