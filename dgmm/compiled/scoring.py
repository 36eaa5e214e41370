"""Scoring's log-normalisers, the far terms left out, compiled with numba.

A score is ``logsumexp_k log rho`` of each evaluation point or primitive; on a surface most of a point's terms lie
far below its best component (bunny, 50k points, K = 400 fits: most terms more than 50 nats down), so numpy's
passes over every term (maximum, shift, floor, exponential, sum) cost several times one compiled pass, which takes
exponentials only of the terms within ``e^-screen`` of the best. At the library's ``SCREEN`` of 50 the left-out
terms change no sum beyond rounding (:data:`dgmm.gaussian.SCREEN`).

Here :func:`screened_log_normalisers`, for any dimension, from ``log rho`` blocks (BLAS's product of the moment
features and the coefficients); 3-D primitives score through :func:`dgmm.compiled.e_step.table_log_normalisers`,
which computes ``log rho`` in registers as the screened E-step does, never writing it out (about twice as fast:
docs/benchmarks/em.md).
"""
from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True, nogil=True, error_model="numpy")
def screened_log_normalisers(log_rho, screen):
    """``logsumexp_k log rho[n, k]`` of each row of ``log rho`` (n_rows, n_components), the terms below
    ``e^-screen`` of the row's largest left out; shape (n_rows,)."""
    n_rows, n_components = log_rho.shape
    out = np.empty(n_rows)
    for n in range(n_rows):
        peak = -np.inf
        for k in range(n_components):
            peak = max(peak, log_rho[n, k])
        total = 0.0
        for k in range(n_components):
            shifted = log_rho[n, k] - peak
            if shifted > -screen:
                total += math.exp(shifted)
        out[n] = peak + math.log(total)
    return out
