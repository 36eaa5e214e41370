"""EM's E-step with the pairs far below a primitive's best left at 0, compiled with numba.

The E-step's time goes to ``exp`` of every (component, primitive) pair's ``log rho``; on a surface most pairs are
far below the primitive's best component (fr1/xyz frames at K = 100: 91% more than 50 nats below). With a screen
``s``, terms ``exp(log rho - peak)`` below ``e^-s`` are 0 and their exponentials are skipped: at ``s = 50`` each
changes its primitive's sum (at least 1) by under ``2e-22``, below rounding for up to 10⁵ components, so a screened
fit equals the unscreened one to rounding. Beyond the paper (which computes every pair); opted into by
``GaussianMixture(screen=...)``, the odometry frames' mixtures (:mod:`dgmm.odometry.frame_model`).

- :func:`screened_e_step_sums`: a screened fit's E-step and M-step sums in one pass over a block's primitives (the
  numpy E-step's product, exponentials and M-step product, one primitive at a time, the M-step over the kept pairs
  only);
- :func:`exp_shifted_screened`: the exponentials alone, for responsibilities (``EStep(screen=...)``).
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


@numba.njit(cache=True, nogil=True, error_model="numpy")
def screened_e_step_sums(features, coefficients, moments, row_weights, screen, log_norm):
    """One block of a screened fit's E-step fused with its M-step sums, primitive by primitive: ``log rho`` of every
    component, the exponentials of the pairs within ``e^-screen`` of the primitive's best, its log-normaliser, and
    the kept pairs' responsibilities times its weighted moments.

    Parameters
    ----------
    features : ndarray of shape (n_rows, 11)
        The scaled moment table's rows (``dgmm.mixture._scaled_table``).
    coefficients : ndarray of shape (11, n_components)
        ``dgmm.mixture._component_coefficients``, transposed: ``log rho = features @ coefficients``.
    moments : ndarray of shape (n_rows, 10)
        The unscaled moment table's columns 0-9.
    row_weights : ndarray of shape (n_rows,)
        The primitives' M-step weights.
    screen : float
    log_norm : ndarray of shape (n_rows,)
        Filled with each primitive's ``logsumexp_k log rho``.

    Returns
    -------
    sums : ndarray of shape (n_components, 10)
        ``dgmm.mixture._m_step_sums`` of the block's responsibilities.
    """
    n_components = coefficients.shape[1]
    sums = np.zeros((n_components, 10))
    log_rho, terms = np.empty(n_components), np.empty(n_components)
    kept = np.empty(n_components, dtype=np.int64)
    row = np.empty(10)
    for j in range(features.shape[0]):
        f = features[j]
        peak = -np.inf
        for k in range(n_components):  # one expression per component: the loop vectorises
            log_rho[k] = (f[0] * coefficients[0, k] + f[1] * coefficients[1, k] + f[2] * coefficients[2, k]
                          + f[3] * coefficients[3, k] + f[4] * coefficients[4, k] + f[5] * coefficients[5, k]
                          + f[6] * coefficients[6, k] + f[7] * coefficients[7, k] + f[8] * coefficients[8, k]
                          + f[9] * coefficients[9, k] + f[10] * coefficients[10, k])
        for k in range(n_components):
            peak = max(peak, log_rho[k])
        count = 0
        for k in range(n_components):  # branch-free: every index is written, the kept ones advance
            kept[count] = k
            count += log_rho[k] - peak > -screen
        total = 0.0
        for i in range(count):
            terms[i] = math.exp(log_rho[kept[i]] - peak)
            total += terms[i]
        log_norm[j] = peak + math.log(total)
        factor = row_weights[j] / total
        for c in range(10):
            row[c] = moments[j, c] * factor
        for i in range(count):
            k, term = kept[i], terms[i]
            for c in range(10):
                sums[k, c] += term * row[c]
    return sums
