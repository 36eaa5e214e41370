"""EM's E-step with the pairs far below a primitive's best left at 0, compiled with numba.

The E-step's time goes to ``exp`` of every (component, primitive) pair's ``log rho``; on a surface most pairs are
far below the primitive's best component (fr1/xyz frames at K = 100: 91% more than 50 nats below). With a screen
``s``, terms ``exp(log rho - peak)`` below ``e^-s`` are 0 and their exponentials are skipped: at ``s = 50`` each
changes its primitive's sum (at least 1) by under ``2e-22``, below rounding for up to 10⁵ components, so a screened
fit equals the unscreened one to rounding. Beyond the paper (which computes every pair); opted into by
``GaussianMixture(screen=...)``, the odometry frames' mixtures (:mod:`dgmm.odometry.frame_model`).

- :func:`screened_e_step_sums`: a screened fit's E-step and M-step sums in one pass over a block's primitives (the
  numpy E-step's product, exponentials and M-step product, one primitive at a time, the M-step over the kept pairs
  only), on :func:`screen_block`;
- :func:`table_log_normalisers`: scoring's log-normalisers of 3-D primitives on the same :func:`screen_block` (every
  3-D ``score``; other dimensions: :mod:`dgmm.compiled.scoring`);
- :func:`exp_shifted_screened`: the exponentials alone, for responsibilities (``EStep(screen=...)``).
"""
from __future__ import annotations

import math

import numba
import numpy as np
from numba.core import types
from numba.extending import intrinsic


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


@intrinsic
def _trailing_zeros(typingctx, mask):
    """The index of the lowest set bit of a nonzero uint64 (LLVM's ``cttz``)."""
    def codegen(context, builder, signature, args):
        lowest = builder.cttz(args[0], context.get_constant(types.boolean, True))  # poison at 0: never called so
        return builder.zext(lowest, context.get_value_type(types.int64))
    return types.int64(types.uint64), codegen


BLOCK = 32
"""Primitives whose ``log rho`` :func:`screen_block` computes together: the loop over a block's primitives
vectorises with each component's 11 coefficients held in registers (as the P2D cost's,
:data:`dgmm.compiled.registration.BLOCK`)."""


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def block_arrays(n_components):
    """:func:`screen_block`'s working arrays for ``n_components``: a block's features (11, BLOCK), its ``log rho``
    (n_components, BLOCK), each primitive's best (BLOCK,), and the pairs within the screen as bits."""
    features = np.zeros((11, BLOCK))  # a last, partial block's unused columns: finite, their results unread
    return (features, np.empty((n_components, BLOCK)), np.empty(BLOCK),
            np.empty(((n_components + 63) // 64, BLOCK), dtype=np.uint64))


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def screen_block(features, first, coefficients, screen, block):
    """``log rho`` of the (up to) :data:`BLOCK` rows of ``features`` from ``first`` (summed in the coefficients' row
    order: a primitive's values do not depend on its block), each one's best, and the pairs within ``e^-screen`` of
    it as bits (a compare per pair, no branch: on fr1/xyz frames a tenth less time than a branch per pair), into
    ``block`` (:func:`block_arrays`); returns the number of rows."""
    size = min(BLOCK, features.shape[0] - first)
    block_features, log_rho, peaks, bits = block
    for j in range(size):
        for c in range(11):
            block_features[c, j] = features[first + j, c]
    for k in range(coefficients.shape[1]):
        c0, c1, c2, c3 = coefficients[0, k], coefficients[1, k], coefficients[2, k], coefficients[3, k]
        c4, c5, c6, c7 = coefficients[4, k], coefficients[5, k], coefficients[6, k], coefficients[7, k]
        c8, c9, c10 = coefficients[8, k], coefficients[9, k], coefficients[10, k]
        for j in range(BLOCK):
            log_rho[k, j] = (block_features[0, j] * c0 + block_features[1, j] * c1 + block_features[2, j] * c2
                             + block_features[3, j] * c3 + block_features[4, j] * c4 + block_features[5, j] * c5
                             + block_features[6, j] * c6 + block_features[7, j] * c7 + block_features[8, j] * c8
                             + block_features[9, j] * c9 + block_features[10, j] * c10)
    peaks[:] = -np.inf  # in a loop of its own: taken in the loop above, the running maximum kept it scalar
    for k in range(coefficients.shape[1]):
        for j in range(BLOCK):
            peaks[j] = np.maximum(peaks[j], log_rho[k, j])  # vectorises; max() measured 3x slower
    bits[:, :] = 0
    for k in range(coefficients.shape[1]):  # the pairs within the screen as bits, without a branch per pair
        word, shift = k >> 6, np.uint64(k & 63)
        for j in range(BLOCK):
            bits[word, j] |= np.uint64(log_rho[k, j] - peaks[j] > -screen) << shift
    return size


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def kept_components(bits, j, kept):
    """Write the components of row ``j``'s set bits into ``kept``, ascending; return their count."""
    count = 0
    for word in range(bits.shape[0]):
        mask = bits[word, j]
        while mask:
            kept[count] = 64 * word + _trailing_zeros(mask)
            count += 1
            mask &= mask - np.uint64(1)
    return count


@numba.njit(cache=True, nogil=True, error_model="numpy")
def screened_e_step_sums(features, coefficients, moments, row_weights, screen, log_norm):
    """One block of a screened fit's E-step fused with its M-step sums: :func:`screen_block` :data:`BLOCK`
    primitives at a time, then primitive by primitive, from its set bits in order, the exponentials of the kept
    pairs, its log-normaliser, and the kept pairs' responsibilities times its weighted moments.

    Parameters
    ----------
    features : ndarray of shape (n_rows, 11)
        The scaled moment table's rows (``dgmm.mixture._scaled_table``).
    coefficients : ndarray of shape (11, n_components)
        ``dgmm.gaussian.log_density_coefficients``, transposed: ``log rho = features @ coefficients``.
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
    n_rows, n_components = features.shape[0], coefficients.shape[1]
    sums = np.zeros((n_components, 10))
    block = block_arrays(n_components)
    log_rho, peaks, bits = block[1], block[2], block[3]
    terms = np.empty(n_components)
    kept = np.empty(n_components, dtype=np.int64)
    row = np.empty(10)
    for first in range(0, n_rows, BLOCK):
        size = screen_block(features, first, coefficients, screen, block)
        for j in range(size):
            peak = peaks[j]
            count = kept_components(bits, j, kept)
            total = 0.0
            for i in range(count):
                terms[i] = math.exp(log_rho[kept[i], j] - peak)
                total += terms[i]
            log_norm[first + j] = peak + math.log(total)
            factor = row_weights[first + j] / total
            for c in range(10):
                row[c] = moments[first + j, c] * factor
            for i in range(count):
                k, term = kept[i], terms[i]
                for c in range(10):
                    sums[k, c] += term * row[c]
    return sums


@numba.njit(cache=True, nogil=True, error_model="numpy")
def table_log_normalisers(table, coefficients, screen):
    """``logsumexp_k log rho`` of each row of a 3-D moment table (n_rows, 11) under ``coefficients`` (11,
    n_components), the terms below ``e^-screen`` of the row's largest left out; shape (n_rows,). Kept terms are
    summed in component order, each row's value whatever its block."""
    out = np.empty(table.shape[0])
    block = block_arrays(coefficients.shape[1])
    log_rho, peaks, bits = block[1], block[2], block[3]
    kept = np.empty(coefficients.shape[1], dtype=np.int64)
    for first in range(0, table.shape[0], BLOCK):
        for j in range(screen_block(table, first, coefficients, screen, block)):
            total = 0.0
            for i in range(kept_components(bits, j, kept)):
                total += math.exp(log_rho[kept[i], j] - peaks[j])
            out[first + j] = peaks[j] + math.log(total)
    return out


@numba.njit(cache=True, nogil=True, error_model="numpy")
def screened_e_step_block_sums(features, coefficients, moments, row_weights, screen, log_norm, starts):
    """:func:`screened_e_step_sums` of every row block ``starts[b]:starts[b + 1]`` in turn, their sums added in block
    order as :meth:`dgmm.em_blocks.BlockPass.run` adds them: the same sums to the bit, in one call where a call per
    block cost a fit on one thread a twentieth of its time (an fr1/xyz frame: 27 blocks per E-step)."""
    total = np.zeros((coefficients.shape[1], 10))
    for block in range(len(starts) - 1):
        rows = slice(starts[block], starts[block + 1])
        part = screened_e_step_sums(features[rows], coefficients, moments[rows], row_weights[rows], screen,
                                    log_norm[rows])
        total = part if block == 0 else total + part
    return total


@numba.njit(cache=True, nogil=True, error_model="numpy")
def moment_table(means, covariances, centre, unit):
    """``dgmm.mixture._moment_features`` of 3-D primitives, unscaled, in one pass: the columns ``x², y², z², 2xy,
    2xz, 2yz, x, y, z, 1, 1`` of ``x = (μ - centre) / unit`` with ``Σ / unit²`` added to the second moments (doubled
    off the diagonal), each value rounded as numpy's passes round it (a screened fit's table: numpy's ten passes over
    the (n_prims, 11) table took a tenth of an fr1/xyz frame's fit).

    Parameters
    ----------
    means : ndarray of shape (n_prims, 3)
    covariances : ndarray of shape (n_prims, 3, 3)
    centre : ndarray of shape (3,)
    unit : float

    Returns
    -------
    table : ndarray of shape (n_prims, 11)
    """
    table = np.empty((means.shape[0], 11))
    squared_unit = unit ** 2
    for n in range(means.shape[0]):
        x, y, z = (means[n, 0] - centre[0]) / unit, (means[n, 1] - centre[1]) / unit, (means[n, 2] - centre[2]) / unit
        table[n, 0] = x * x + covariances[n, 0, 0] / squared_unit
        table[n, 1] = y * y + covariances[n, 1, 1] / squared_unit
        table[n, 2] = z * z + covariances[n, 2, 2] / squared_unit
        table[n, 3] = x * y * 2.0 + covariances[n, 0, 1] / squared_unit * 2.0
        table[n, 4] = x * z * 2.0 + covariances[n, 0, 2] / squared_unit * 2.0
        table[n, 5] = y * z * 2.0 + covariances[n, 1, 2] / squared_unit * 2.0
        table[n, 6], table[n, 7], table[n, 8] = x, y, z
        table[n, 9] = table[n, 10] = 1.0
    return table
