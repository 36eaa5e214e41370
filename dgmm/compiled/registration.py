"""The P2D and D2D costs and their derivatives compiled with numba: P2D for both solvers, D2D for Gauss-Newton.

- P2D (:func:`dgmm.registration.p2d.p2d_pose_cost` for Gauss-Newton, :func:`~dgmm.registration.p2d.p2d_params_cost` for
  BFGS) spends its time in the likelihood of every trial pose: ``n_points x n_components`` exponentials. A point's
  responsibility ``e^{l_nk - max_k l_nk}`` under a component more than :data:`dgmm.gaussian.SCREEN` nats below its best
  adds less than half a unit in the last place to the point's sum (which is at least 1), so the P2D kernels compute
  every log-density (10 multiply-adds) but the exponential and the moments only of the pairs within the screen.
  Gauss-Newton's whole loop runs here too (:func:`p2d_gauss_newton`, the steps of
  :func:`dgmm.registration.solvers.minimise_gauss_newton`): between its 15-20 kernel calls a registration, the solver's
  Python took a third of the time.
- D2D (:func:`dgmm.registration.d2d.d2d_pose_cost`, odometry's inner loop): the numpy D2D bounds every pair's term
  before computing the ones that may matter, then works on arrays of a few hundred to a few thousand pairs, and at
  odometry's sizes (K = 100 per frame) its time goes to numpy's per-call overhead. Here every pair's exact term is
  computed in one pass (about 50 floating-point operations a pair), and the derivatives run over the pairs within
  ``e^-screen`` of the largest term, the pairs the numpy derivatives keep. Gauss-Newton's whole loop runs here too
  (:func:`d2d_gauss_newton`), as P2D's.

The numpy functions stay the reference (``p2d_pose_cost(compiled=False)``, ``p2d_params_cost(compiled=False)``,
``d2d_pose_cost(compiled=False)``, tested against these). The kernels and the 3x3 helpers they call live in this one
file, and the registration modules' thresholds come in as arguments: numba's on-disk cache checks only the file of the
function it compiled, so a helper or a constant in another file could change without the cached code noticing.
"""
from __future__ import annotations

import math

import numba
from numba.extending import overload
import numpy as np

# ---- 3x3 helpers

@numba.njit(cache=True, nogil=True, error_model="numpy")
def _product(x, y, out):
    """``out = x y`` for 3x3 matrices."""
    for a in range(3):
        for b in range(3):
            out[a, b] = x[a, 0] * y[0, b] + x[a, 1] * y[1, b] + x[a, 2] * y[2, b]


# ---- P2D

BLOCK = 32
"""Points whose log-densities :func:`p2d_negative_mean_log_likelihood` computes together: the loop over a block's
points vectorises with each component's 10 coefficients held in registers. One bunny cost (453 points, K=100, AVX-512)
took 122, 61, 60 and 62 µs with blocks of 8, 16, 32 and 64 points, and 101 µs point by point over the components."""


_TAYLOR = tuple(1.0 / math.factorial(k) for k in range(13, -1, -1))
"""``1/k!`` from ``k = 13`` down to 0: Horner's coefficients of ``e^r``'s Taylor polynomial (:func:`_exp_in_place`)."""
_POWERS_OF_TWO = 2.0 ** np.arange(-1022, 1)
"""``2^n`` at index ``n + 1022``, the normal powers up to 1."""


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _exp_in_place(values, exponents):
    """``values = e^values`` for ``values`` in [-708, 0], within an ulp of ``math.exp`` (2.2e-16 relative over
    [-700, 0]), in loops that vectorise, where ``math.exp``'s libm calls do not: a bunny cost (453 points, K=100)
    in 87 µs against 99.

    ``x = n ln 2 + r`` with ``n`` the nearest integer (rounded by adding and subtracting 1.5 * 2^52) and ``ln 2`` in
    two parts (Cody and Waite: ``n ln2_hi`` is exact), ``|r| <= ln 2 / 2``; ``e^r`` by its degree-13 Taylor polynomial
    (truncated at ``r^14 / 14! < 5e-18``), times ``2^n`` from a table. ``exponents``, as long as ``values``, is
    scratch for ``n``. Loops over the slices' own ranges: numba's loops over ``range(start, stop)`` of a larger array
    keep the negative-index checks that stop them vectorising.
    """
    for i in range(values.shape[0]):
        x = values[i]
        n = (x * 1.4426950408889634 + 6755399441055744.0) - 6755399441055744.0
        r = (x - n * 0.6931471803691238) - n * 1.9082149292705877e-10
        polynomial = 0.0
        for coefficient in _TAYLOR:
            polynomial = polynomial * r + coefficient
        values[i] = polynomial
        exponents[i] = n
    for i in range(values.shape[0]):
        values[i] *= _POWERS_OF_TWO[max(int(exponents[i]), -1022) + 1022]  # below -708, 2^-1022 e^r: not 0, as tiny


@numba.njit(cache=True, nogil=True, error_model="numpy")
def p2d_pose_buffers(n_points, n_components):
    """Buffers for :func:`p2d_negative_mean_log_likelihood` to leave a pose's moved points and screened pairs in,
    for :func:`p2d_pose_derivatives` at the same pose: ``(rotated (n_points, 3), offsets (n_points, 3), starts
    (n_points + 1,), components, terms, sums (n_points,))``."""
    size = n_points * n_components
    return (np.empty((n_points, 3)), np.empty((n_points, 3)), np.empty(n_points + 1, dtype=np.int64),
            np.empty(size, dtype=np.int64), np.empty(size), np.empty(n_points))


@numba.njit(cache=True, nogil=True, error_model="numpy")
def p2d_negative_mean_log_likelihood(local, rotation, shift, table, screen, vector_exp, rotated, offsets, starts,
                                     components, terms, sums):
    """``-1/n Σ_n log Σ_k π_k N(y_n | μ_k, Σ_k)`` of the points ``y_n = R x_n + shift + origin``.

    A block of :data:`BLOCK` points at a time: their :func:`~dgmm.gaussian.quadratic_features`, every
    log-density ``l_nk`` (the features times the table's column, summed in the table's row order: a point's values do
    not depend on its block) and each point's largest; then, point by point, the pairs within ``screen``, in
    component order; then the block's exponentials, and each point's sum.

    Parameters
    ----------
    local : ndarray of shape (n_points, 3)
        ``x_n``, the points about the centre of rotation.
    rotation : ndarray of shape (3, 3)
    shift : ndarray of shape (3,)
        ``c + t' - origin``.
    table : ndarray of shape (10, n_components)
        :attr:`~dgmm.registration.fitted.FittedMixture.log_density_table`.
    screen : float
        Pairs with ``l_nk < max_k l_nk - screen`` are left out: :data:`dgmm.gaussian.SCREEN` (BFGS) or
        :func:`dgmm.registration.p2d.gauss_newton_screen` (Gauss-Newton).
    vector_exp : bool
        The exponentials by :func:`_exp_in_place` (Gauss-Newton's: within an ulp, an eighth less time a cost) or by
        ``math.exp`` (BFGS's: the bits the paper's runs have always had).
    rotated, offsets, starts, components, terms, sums : ndarray
        The :func:`p2d_pose_buffers`, filled: ``rotated`` with ``R x_n``, ``offsets`` with ``y_n - origin``, and
        the pairs within ``screen``: point ``n``'s are ``components[starts[n]:starts[n + 1]]``, with
        ``e^{l_nk - max_k l_nk}`` in ``terms`` and their sum in ``sums[n]``.
    """
    n_points, n_components = local.shape[0], table.shape[1]
    features = np.zeros((9, BLOCK))  # a last, partial block's unused columns: finite values whose results go unread
    log_density = np.empty((n_components, BLOCK))
    tops = np.empty(BLOCK)
    exponents = np.empty(BLOCK * n_components)  # _exp_in_place's scratch
    total = 0.0
    count = 0
    for first in range(0, n_points, BLOCK):
        size = min(BLOCK, n_points - first)
        for j in range(size):
            n = first + j
            for a in range(3):
                rotated[n, a] = (rotation[a, 0] * local[n, 0] + rotation[a, 1] * local[n, 1]
                                 + rotation[a, 2] * local[n, 2])
                offsets[n, a] = rotated[n, a] + shift[a]
            x, y, z = offsets[n, 0], offsets[n, 1], offsets[n, 2]
            features[0, j], features[1, j], features[2, j] = x * x, y * y, z * z
            features[3, j], features[4, j], features[5, j] = x * y * 2.0, x * z * 2.0, y * z * 2.0
            features[6, j], features[7, j], features[8, j] = x, y, z
        tops[:] = -np.inf
        for k in range(n_components):
            t0, t1, t2, t3, t4 = table[0, k], table[1, k], table[2, k], table[3, k], table[4, k]
            t5, t6, t7, t8, t9 = table[5, k], table[6, k], table[7, k], table[8, k], table[9, k]
            for j in range(BLOCK):
                value = (features[0, j] * t0 + features[1, j] * t1 + features[2, j] * t2 + features[3, j] * t3
                         + features[4, j] * t4 + features[5, j] * t5 + features[6, j] * t6 + features[7, j] * t7
                         + features[8, j] * t8 + t9)
                log_density[k, j] = value
                tops[j] = max(tops[j], value)
        for j in range(size):
            n = first + j
            threshold = tops[j] - screen
            starts[n] = count
            for k in range(n_components):
                if log_density[k, j] > threshold:
                    components[count] = k
                    terms[count] = log_density[k, j] - tops[j]
                    count += 1
        starts[first + size] = count
        if vector_exp:
            _exp_in_place(terms[starts[first]:count], exponents[:count - starts[first]])
        else:
            for i in range(starts[first], count):
                terms[i] = math.exp(terms[i])
        for j in range(size):
            n = first + j
            sum_ = 0.0
            for i in range(starts[n], starts[n + 1]):
                sum_ += terms[i]
            sums[n] = sum_
            total += math.log(sum_) + tops[j]
    return -total / n_points


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _pair_gradient(precisions, precision_means, k, d0, d1, d2):
    """``g_nk = P_k (y_n - μ_k)`` (three scalars) from the offset ``d = y_n - origin``, by ``P_k``'s upper entries."""
    p00, p01, p02 = precisions[k, 0, 0], precisions[k, 0, 1], precisions[k, 0, 2]
    p11, p12, p22 = precisions[k, 1, 1], precisions[k, 1, 2], precisions[k, 2, 2]
    return (p00 * d0 + p01 * d1 + p02 * d2 - precision_means[k, 0],
            p01 * d0 + p11 * d1 + p12 * d2 - precision_means[k, 1],
            p02 * d0 + p12 * d1 + p22 * d2 - precision_means[k, 2])


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _add_pose_blocks(a00, a01, a02, a11, a12, a22, p, out):
    """``out += `` the distinct entries of ``Jᵀ A J`` (6, 6) for a symmetric ``A``, ``J = [I, -[p]x]``: ``A``'s
    upper triangle (6), ``-A [p]x`` (9, row-major) and ``-[p]x A [p]x``'s upper triangle (6), into ``out`` (21,)
    (:func:`_pose_matrix` unpacks them). Where an update of the 36 entries from a 3x3 product (as D2D's) would, this
    takes 30 products into 21 sums: the Gauss-Newton derivatives' per-point cost."""
    p0, p1, p2 = p[0], p[1], p[2]
    # B = A [p]x, column by column: [p]x's columns are (0, p2, -p1), (-p2, 0, p0), (p1, -p0, 0)
    b00, b01, b02 = a01 * p2 - a02 * p1, a02 * p0 - a00 * p2, a00 * p1 - a01 * p0
    b10, b11, b12 = a11 * p2 - a12 * p1, a12 * p0 - a01 * p2, a01 * p1 - a11 * p0
    b20, b21, b22 = a12 * p2 - a22 * p1, a22 * p0 - a02 * p2, a02 * p1 - a12 * p0
    out[0] += a00
    out[1] += a01
    out[2] += a02
    out[3] += a11
    out[4] += a12
    out[5] += a22
    out[6] -= b00
    out[7] -= b01
    out[8] -= b02
    out[9] -= b10
    out[10] -= b11
    out[11] -= b12
    out[12] -= b20
    out[13] -= b21
    out[14] -= b22
    # -[p]x B, by [p]x's rows (0, -p2, p1), (p2, 0, -p0), (-p1, p0, 0)
    out[15] -= p1 * b20 - p2 * b10
    out[16] -= p1 * b21 - p2 * b11
    out[17] -= p1 * b22 - p2 * b12
    out[18] -= p2 * b01 - p0 * b21
    out[19] -= p2 * b02 - p0 * b22
    out[20] -= p0 * b12 - p1 * b02


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _pose_matrix(blocks, scale, out):
    """``out`` (6, 6) ``= scale`` times the symmetric matrix of :func:`_add_pose_blocks`' 21 sums."""
    upper = ((0, 1, 2), (1, 3, 4), (2, 4, 5))
    for a in range(3):
        for b in range(3):
            out[a, b] = scale * blocks[upper[a][b]]
            out[a, 3 + b] = out[3 + b, a] = scale * blocks[6 + 3 * a + b]
            out[3 + a, 3 + b] = scale * blocks[15 + upper[a][b]]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def p2d_pose_derivatives(precisions, precision_means, rotated, offsets, starts, components, terms, sums):
    """Gradient, Gauss-Newton matrix and exact Hessian over ``(δ, ω)`` of the cost at the pose of ``offsets``
    (what :func:`~dgmm.registration.p2d.p2d_pose_cost`'s ``derivatives()`` returns), from the screened pairs
    :func:`p2d_negative_mean_log_likelihood` left at that pose.

    Parameters
    ----------
    precisions : ndarray of shape (n_components, 3, 3)
        ``P_k``.
    precision_means : ndarray of shape (n_components, 3)
        ``P_k (μ_k - origin)``.
    rotated, offsets, starts, components, terms, sums : ndarray
        The :func:`p2d_pose_buffers` as the cost left them: ``rotated`` holds ``p_n = R (x_n - c)`` (``dy_n = δ -
        [p_n]x ω``).

    Returns
    -------
    gradient : ndarray of shape (6,)
    gauss_newton : ndarray of shape (6, 6)
        ``1/n Σ_n J_nᵀ W_n J_n``, ``W_n = Σ_k r_nk P_k`` and ``J_n = [I, -[p_n]x]``.
    exact : ndarray of shape (6, 6)
        The same with the exact Hessian of ``-log p(y_n)``, ``W_n - (Σ_k r_nk g_nk g_nkᵀ - ḡ_n ḡ_nᵀ)``, plus the
        rotation's second-order term ``Σ_n sym(ḡ_n p_nᵀ) - (ḡ_n·p_n) I`` (``g_nk = P_k (y_n - μ_k)``).
    """
    n_points = offsets.shape[0]
    gradient = np.zeros(6)
    blocks = np.zeros((2, 21))  # the Gauss-Newton matrix's and the exact Hessian's (_add_pose_blocks)
    outer = np.zeros((3, 3))
    for n in range(n_points):
        d0, d1, d2 = offsets[n, 0], offsets[n, 1], offsets[n, 2]
        # The sums over the point's pairs in scalars (the 3x3 ones symmetric): kept in registers, where sums into
        # arrays would be stored and reloaded at every pair.
        w00 = w01 = w02 = w11 = w12 = w22 = 0.0  # W_n = Σ_k r_nk P_k
        s00 = s01 = s02 = s11 = s12 = s22 = 0.0  # Σ_k r_nk g_nk g_nkᵀ
        m0 = m1 = m2 = 0.0  # ḡ_n
        # Unsigned indices: numba checks signed ones for negative values at every load (4-5% of this kernel's time).
        for i in range(np.uint64(starts[n]), np.uint64(starts[n + 1])):
            k, r = np.uint64(components[i]), terms[i] / sums[n]
            p00, p01, p02 = precisions[k, 0, 0], precisions[k, 0, 1], precisions[k, 0, 2]
            p11, p12, p22 = precisions[k, 1, 1], precisions[k, 1, 2], precisions[k, 2, 2]
            g0, g1, g2 = _pair_gradient(precisions, precision_means, k, d0, d1, d2)
            m0 += r * g0
            m1 += r * g1
            m2 += r * g2
            w00 += r * p00
            w01 += r * p01
            w02 += r * p02
            w11 += r * p11
            w12 += r * p12
            w22 += r * p22
            s00 += r * g0 * g0
            s01 += r * g0 * g1
            s02 += r * g0 * g2
            s11 += r * g1 * g1
            s12 += r * g1 * g2
            s22 += r * g2 * g2
        p = rotated[n]
        for b in range(3):
            outer[0, b] += m0 * p[b]
            outer[1, b] += m1 * p[b]
            outer[2, b] += m2 * p[b]
        gradient[0] += m0  # J_nᵀ ḡ_n: (ḡ_n, p_n x ḡ_n)
        gradient[1] += m1
        gradient[2] += m2
        gradient[3] += p[1] * m2 - p[2] * m1
        gradient[4] += p[2] * m0 - p[0] * m2
        gradient[5] += p[0] * m1 - p[1] * m0
        _add_pose_blocks(w00, w01, w02, w11, w12, w22, p, blocks[0])
        _add_pose_blocks(w00 - s00 + m0 * m0, w01 - s01 + m0 * m1, w02 - s02 + m0 * m2, w11 - s11 + m1 * m1,
                         w12 - s12 + m1 * m2, w22 - s22 + m2 * m2, p, blocks[1])
    gradient /= n_points
    gauss_newton, exact = np.empty((6, 6)), np.empty((6, 6))
    _pose_matrix(blocks[0], 1.0 / n_points, gauss_newton)
    _pose_matrix(blocks[1], 1.0 / n_points, exact)
    outer /= n_points
    trace = outer[0, 0] + outer[1, 1] + outer[2, 2]
    for a in range(3):
        for b in range(3):
            exact[3 + a, 3 + b] += 0.5 * (outer[a, b] + outer[b, a]) - (trace if a == b else 0.0)
    return gradient, gauss_newton, exact


@numba.njit(cache=True, nogil=True, error_model="numpy")
def quaternion_rotation_and_jacobian(quaternion):
    """``R(q / |q|)`` (3, 3) and its derivative with respect to the unnormalised ``q`` (4, 3, 3): the formulas of
    :func:`dgmm.registration.rotations.rotation_and_jacobian`, without numpy's calls (about 90 µs there, a sixth of a
    BFGS P2D evaluation). A zero quaternion gives NaNs, which BFGS's cost check reports."""
    norm = math.sqrt(quaternion[0] ** 2 + quaternion[1] ** 2 + quaternion[2] ** 2 + quaternion[3] ** 2)
    u = quaternion / norm
    w, x, y, z = u[0], u[1], u[2], u[3]
    rotation = np.empty((3, 3))
    rotation[0, 0], rotation[0, 1], rotation[0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)
    rotation[1, 0], rotation[1, 1], rotation[1, 2] = 2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)
    rotation[2, 0], rotation[2, 1], rotation[2, 2] = 2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)
    unit = np.empty((4, 3, 3))  # d R / d u_j, halved
    unit[0, 0, 0], unit[0, 0, 1], unit[0, 0, 2] = 0.0, -z, y
    unit[0, 1, 0], unit[0, 1, 1], unit[0, 1, 2] = z, 0.0, -x
    unit[0, 2, 0], unit[0, 2, 1], unit[0, 2, 2] = -y, x, 0.0
    unit[1, 0, 0], unit[1, 0, 1], unit[1, 0, 2] = 0.0, y, z
    unit[1, 1, 0], unit[1, 1, 1], unit[1, 1, 2] = y, -2 * x, -w
    unit[1, 2, 0], unit[1, 2, 1], unit[1, 2, 2] = z, w, -2 * x
    unit[2, 0, 0], unit[2, 0, 1], unit[2, 0, 2] = -2 * y, x, w
    unit[2, 1, 0], unit[2, 1, 1], unit[2, 1, 2] = x, 0.0, z
    unit[2, 2, 0], unit[2, 2, 1], unit[2, 2, 2] = -w, z, -2 * y
    unit[3, 0, 0], unit[3, 0, 1], unit[3, 0, 2] = -2 * z, -w, x
    unit[3, 1, 0], unit[3, 1, 1], unit[3, 1, 2] = w, -2 * z, y
    unit[3, 2, 0], unit[3, 2, 1], unit[3, 2, 2] = x, y, 0.0
    jacobian = np.zeros((4, 3, 3))
    for i in range(4):  # (I - u uᵀ) / |q| times d R / d u
        for j in range(4):
            scale = 2.0 * ((1.0 if i == j else 0.0) - u[i] * u[j]) / norm
            for a in range(3):
                for b in range(3):
                    jacobian[i, a, b] += scale * unit[j, a, b]
    return rotation, jacobian


@numba.njit(cache=True, nogil=True, error_model="numpy")
def p2d_params_gradient(precisions, precision_means, local, jacobian, offsets, starts, components, terms, sums):
    """BFGS's gradient over ``(t', q)`` (7,) (:func:`~dgmm.registration.p2d.p2d_cost`'s) from the screened pairs
    :func:`p2d_negative_mean_log_likelihood` left at a pose: ``1/n Σ_n ḡ_n`` and ``Σ_ab (1/n Σ_n ḡ_n x_nᵀ)_ab
    dR_ab/dq_j``, ``ḡ_n = Σ_k r_nk P_k (y_n - μ_k)``, ``x_n`` the unmoved ``local`` points and ``jacobian``
    :func:`quaternion_rotation_and_jacobian`'s."""
    n_points = offsets.shape[0]
    gradient = np.zeros(7)
    outer = np.zeros((3, 3))
    for n in range(n_points):
        d0, d1, d2 = offsets[n, 0], offsets[n, 1], offsets[n, 2]
        m0 = m1 = m2 = 0.0
        for i in range(starts[n], starts[n + 1]):
            r = terms[i] / sums[n]
            g0, g1, g2 = _pair_gradient(precisions, precision_means, components[i], d0, d1, d2)
            m0 += r * g0
            m1 += r * g1
            m2 += r * g2
        gradient[0] += m0
        gradient[1] += m1
        gradient[2] += m2
        for b in range(3):
            outer[0, b] += m0 * local[n, b]
            outer[1, b] += m1 * local[n, b]
            outer[2, b] += m2 * local[n, b]
    for j in range(4):
        for a in range(3):
            for b in range(3):
                gradient[3 + j] += outer[a, b] * jacobian[j, a, b]
    return gradient / n_points


# ---- P2D's Gauss-Newton solver: solvers.minimise_gauss_newton's loop on these kernels

@numba.njit(cache=True, nogil=True, error_model="numpy")
def _cholesky(matrix, factor):
    """Lower Cholesky factor of a symmetric ``matrix`` into ``factor``; False if it is not positive definite."""
    size = matrix.shape[0]
    for j in range(size):
        diagonal = matrix[j, j]
        for k in range(j):
            diagonal -= factor[j, k] * factor[j, k]
        if not diagonal > 0.0:  # also NaN
            return False
        factor[j, j] = math.sqrt(diagonal)
        for i in range(j + 1, size):
            entry = matrix[i, j]
            for k in range(j):
                entry -= factor[i, k] * factor[j, k]
            factor[i, j] = entry / factor[j, j]
    return True


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _damped_step(hessian, gradient, damping, scratch, factor, step):
    """``step = -(H + λ diag H)⁻¹ g`` by Cholesky (``H`` is positive definite or semi-definite here), or zero if
    that matrix has no factor (solvers._damped_step's singular case)."""
    size = gradient.shape[0]
    for a in range(size):
        for b in range(size):
            scratch[a, b] = hessian[a, b]
        scratch[a, a] += damping * hessian[a, a]
    if not _cholesky(scratch, factor):
        step[:] = 0.0
        return
    for a in range(size):  # L z = -g, then Lᵀ step = z
        value = -gradient[a]
        for k in range(a):
            value -= factor[a, k] * step[k]
        step[a] = value / factor[a, a]
    for a in range(size - 1, -1, -1):
        value = step[a]
        for k in range(a + 1, size):
            value -= factor[k, a] * step[k]
        step[a] = value / factor[a, a]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _step_size(step, scale):
    """``max |step / scale|``: the stopping test's size of a step."""
    size = 0.0
    for a in range(6):
        size = max(size, abs(step[a]) / scale[a])
    return size


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _capped(step, length, scale, max_step, move):
    """``move = length step``, shortened so that it turns by at most ``max_step`` radians and moves by at most
    ``max_step`` RMS radii (solvers._capped); returns whether it was shortened."""
    translation = rotation = 0.0
    for a in range(3):
        translation += (length * step[a] / scale[a]) ** 2
        rotation += (length * step[3 + a]) ** 2
    size = max(math.sqrt(translation), math.sqrt(rotation))
    factor = length if size <= max_step else length * (max_step / size)
    for a in range(6):
        move[a] = factor * step[a]
    return size > max_step


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _turned(rotvec, rotation, out):
    """``out = exp([w]x) rotation`` (Rodrigues' formula, as dgmm.registration.rotations.exp_rotation)."""
    x, y, z = rotvec[0], rotvec[1], rotvec[2]
    theta2 = x * x + y * y + z * z
    if theta2 < 1e-16:
        a, b = 1.0, 0.5
    else:
        theta = math.sqrt(theta2)
        a, b = math.sin(theta) / theta, (1.0 - math.cos(theta)) / theta2
    turn = np.empty((3, 3))
    turn[0, 0], turn[0, 1], turn[0, 2] = 1.0 - b * (y * y + z * z), b * x * y - a * z, b * x * z + a * y
    turn[1, 0], turn[1, 1], turn[1, 2] = b * x * y + a * z, 1.0 - b * (x * x + z * z), b * y * z - a * x
    turn[2, 0], turn[2, 1], turn[2, 2] = b * x * z - a * y, b * y * z + a * x, 1.0 - b * (x * x + y * y)
    _product(turn, rotation, out)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _next_over_relaxation(cost, slope, length, new_cost):
    """solvers.next_over_relaxation."""
    curvature = new_cost - cost - slope * length
    best = -slope * length * length / (2.0 * curvature) if curvature > 0 else 2.0 * length
    return max(1.0, min(best, 2.0 * length))


ENDED, SEARCH_FAILED, NOT_FINITE = 0, 1, 2
"""How :func:`p2d_gauss_newton` stopped."""


@numba.njit(cache=True, nogil=True, error_model="numpy")
def p2d_gauss_newton(local, shift, table, precisions, precision_means, screen, scale, max_iter, tol, damping,
                     max_step, constants, rotations, translations, costs):
    """:func:`dgmm.registration.solvers.minimise_gauss_newton` on the P2D kernels, from the pose ``rotations[0]``,
    ``translations[0]`` (``x -> R x_n + c + t'`` of the ``local`` points ``x_n``): the same steps, line search,
    damping and stopping rule, with no Python between the kernels.

    Parameters
    ----------
    local, table, precisions, precision_means, screen
        As :func:`p2d_negative_mean_log_likelihood` and :func:`p2d_pose_derivatives` take them.
    shift : ndarray of shape (3,)
        ``c - origin``.
    scale : ndarray of shape (6,)
        The stopping test's units of ``(δ, ω)``.
    max_iter, tol, damping, max_step
        The solver's options.
    constants : tuple
        The solver's ``(OVER_RELAXATION, _NEWTON_CONTRACTION, _MIN_DAMPING, _MAX_DAMPING, _BACKTRACKS)``.
    rotations, translations, costs : ndarray of shape (max_iter + 1, 3, 3), (max_iter + 1, 3), (max_iter + 1,)
        Filled with the pose ``(R, t')`` and cost after each iteration (row 0: the start).

    Returns
    -------
    iterations : int
    converged : bool
    status : int
        :data:`ENDED` (converged, or ``max_iter`` iterations: the pose is row ``iterations``),
        :data:`SEARCH_FAILED` (no pose along the last step lowered the cost: the pose is row ``iterations - 1``) or
        :data:`NOT_FINITE` (the cost or its derivatives stopped being finite at iteration ``iterations``).
    """
    buffers = p2d_pose_buffers(local.shape[0], table.shape[1]), p2d_pose_buffers(local.shape[0], table.shape[1])
    return _gauss_newton_loop((local, shift, table, precisions, precision_means, screen), *buffers, scale, max_iter,
                              tol, damping, max_step, constants, rotations, translations, costs)


# ---- D2D

def d2d_kept_pairs(n_fixed, n_moving):
    """Buffers for :func:`d2d_negative_overlap` to leave the kept pairs in, for :func:`d2d_pose_derivatives` at the same
    pose: ``(count (1,), fixed index, moving index, log terms)``."""
    size = n_fixed * n_moving
    return np.zeros(1, dtype=np.int64), np.empty(size, dtype=np.int64), np.empty(size, dtype=np.int64), np.empty(size)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _inverse_and_exponent(fixed_covariance, moving_covariance, y, inverse):
    """``S⁻¹`` of ``S = Σᵢ + C`` into ``inverse`` (by its adjugate, as the numpy cost) and ``-½ yᵀ S⁻¹ y``."""
    a, b, c = fixed_covariance[0, 0] + moving_covariance[0, 0], fixed_covariance[1, 1] + moving_covariance[1, 1], \
        fixed_covariance[2, 2] + moving_covariance[2, 2]
    d, e, f = fixed_covariance[0, 1] + moving_covariance[0, 1], fixed_covariance[0, 2] + moving_covariance[0, 2], \
        fixed_covariance[1, 2] + moving_covariance[1, 2]
    axx, ayy, azz = b * c - f * f, a * c - e * e, a * b - d * d
    axy, axz, ayz = e * f - d * c, d * f - b * e, d * e - a * f
    determinant = a * axx + d * axy + e * axz
    inverse[0, 0], inverse[1, 1], inverse[2, 2] = axx / determinant, ayy / determinant, azz / determinant
    inverse[0, 1] = inverse[1, 0] = axy / determinant
    inverse[0, 2] = inverse[2, 0] = axz / determinant
    inverse[1, 2] = inverse[2, 1] = ayz / determinant
    quadratic = 0.0
    for r in range(3):
        quadratic += y[r] * (inverse[r, 0] * y[0] + inverse[r, 1] * y[1] + inverse[r, 2] * y[2])
    return -0.5 * quadratic


@numba.njit(cache=True, nogil=True, error_model="numpy")
def d2d_negative_overlap(fixed_means, fixed_covariances, moved, moved_covariances, log_weights, screen, floor,
                         count, fixed_index, moving_index, log_terms):
    """The D2D cost ``-Σᵢⱼ πᵢ πⱼ exp(-½ yᵢⱼᵀ Sᵢⱼ⁻¹ yᵢⱼ)`` over the pairs within ``e^-screen`` of the largest
    term, which it leaves in the :func:`d2d_kept_pairs` buffers.

    Parameters
    ----------
    fixed_means : ndarray of shape (n_fixed, 3)
    fixed_covariances : ndarray of shape (n_fixed, 3, 3)
    moved : ndarray of shape (n_moving, 3)
        ``R (μⱼ - c) + c + t'``.
    moved_covariances : ndarray of shape (n_moving, 3, 3)
        ``R Σⱼ Rᵀ``.
    log_weights : ndarray of shape (n_fixed, n_moving)
        ``log πᵢ + log πⱼ``.
    screen, floor : float
        :data:`dgmm.gaussian.SCREEN` and the numpy cost's exponent floor
        (:data:`dgmm.registration.fitted.EXP_FLOOR`).
    count, fixed_index, moving_index, log_terms : ndarray
        The buffers.
    """
    n_fixed, n_moving = fixed_means.shape[0], moved.shape[0]
    exponents = np.empty(n_fixed * n_moving)
    inverse, y = np.empty((3, 3)), np.empty(3)
    top = -np.inf
    for i in range(n_fixed):
        for j in range(n_moving):
            for r in range(3):
                y[r] = fixed_means[i, r] - moved[j, r]
            exponent = max(_inverse_and_exponent(fixed_covariances[i], moved_covariances[j], y, inverse)
                           + log_weights[i, j], floor)  # floored as the numpy cost's
            exponents[i * n_moving + j] = exponent
            top = max(top, exponent)
    kept = 0
    cost = 0.0
    for pair in range(n_fixed * n_moving):
        if exponents[pair] >= top - screen:
            fixed_index[kept], moving_index[kept] = pair // n_moving, pair % n_moving
            log_terms[kept] = exponents[pair]
            cost -= math.exp(exponents[pair])
            kept += 1
    count[0] = kept
    return cost


@numba.njit(inline="always")
def _skew_t(a0, a1, a2):
    """``[a]x`` as a row-major 9-tuple: the D2D derivatives' 3x3 matrices are tuples, which stay in registers
    where scratch arrays were stored and reloaded at every pair (their kernel took half the time so)."""
    return (0.0, -a2, a1, a2, 0.0, -a0, -a1, a0, 0.0)


@numba.njit(inline="always")
def _product_t(x, y):
    """``x y`` of row-major 9-tuples, each entry summed in :func:`_product`'s order."""
    return (x[0] * y[0] + x[1] * y[3] + x[2] * y[6], x[0] * y[1] + x[1] * y[4] + x[2] * y[7],
            x[0] * y[2] + x[1] * y[5] + x[2] * y[8],
            x[3] * y[0] + x[4] * y[3] + x[5] * y[6], x[3] * y[1] + x[4] * y[4] + x[5] * y[7],
            x[3] * y[2] + x[4] * y[5] + x[5] * y[8],
            x[6] * y[0] + x[7] * y[3] + x[8] * y[6], x[6] * y[1] + x[7] * y[4] + x[8] * y[7],
            x[6] * y[2] + x[7] * y[5] + x[8] * y[8])


@numba.njit(inline="always")
def _add_transposed_product_t(weight, x, y, out):
    """``out += weight xᵀ y`` (3, 3) for row-major 9-tuples ``x`` and ``y``."""
    for a in range(3):
        for b in range(3):
            out[a, b] += weight * (x[a] * y[b] + x[3 + a] * y[3 + b] + x[6 + a] * y[6 + b])


@numba.njit(cache=True, nogil=True, error_model="numpy")
def d2d_pose_derivatives(fixed_means, fixed_covariances, moved, rotated, moved_covariances, count, fixed_index,
                         moving_index, log_terms):
    """Gradient, Gauss-Newton matrix and exact Hessian of the D2D cost over ``(δ, ω)`` at the pose
    :func:`d2d_negative_overlap` left its kept pairs for (``rotated``: ``p = R (μⱼ - c)``); the formulas of
    :func:`dgmm.registration.d2d._derivatives`, pair by pair.

    Returns
    -------
    gradient : ndarray of shape (6,)
    gauss_newton : ndarray of shape (6, 6)
    exact : ndarray of shape (6, 6)
    """
    gradient = np.zeros(6)
    gauss_newton, spread = np.zeros((6, 6)), np.zeros((6, 6))
    second = np.zeros((3, 3))
    mixed, spin, across = np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3))
    for pair in range(count[0]):
        i, j = fixed_index[pair], moving_index[pair]
        f, cm = fixed_covariances[i], moved_covariances[j]
        c = (cm[0, 0], cm[0, 1], cm[0, 2], cm[1, 0], cm[1, 1], cm[1, 2], cm[2, 0], cm[2, 1], cm[2, 2])
        p0, p1, p2 = rotated[j, 0], rotated[j, 1], rotated[j, 2]
        y0, y1, y2 = fixed_means[i, 0] - moved[j, 0], fixed_means[i, 1] - moved[j, 1], fixed_means[i, 2] - moved[j, 2]
        # S⁻¹ by its adjugate, as _inverse_and_exponent (the cost's kernel)
        a, b, cc = f[0, 0] + cm[0, 0], f[1, 1] + cm[1, 1], f[2, 2] + cm[2, 2]
        d, e, g = f[0, 1] + cm[0, 1], f[0, 2] + cm[0, 2], f[1, 2] + cm[1, 2]
        axx, ayy, azz = b * cc - g * g, a * cc - e * e, a * b - d * d
        axy, axz, ayz = e * g - d * cc, d * g - b * e, d * e - a * g
        determinant = a * axx + d * axy + e * axz
        i00, i11, i22 = axx / determinant, ayy / determinant, azz / determinant
        i01, i02, i12 = axy / determinant, axz / determinant, ayz / determinant
        inverse = (i00, i01, i02, i01, i11, i12, i02, i12, i22)
        term = math.exp(log_terms[pair])
        v0 = i00 * y0 + i01 * y1 + i02 * y2
        v1 = i01 * y0 + i11 * y1 + i12 * y2
        v2 = i02 * y0 + i12 * y1 + i22 * y2
        cv0 = c[0] * v0 + c[1] * v1 + c[2] * v2
        cv1 = c[3] * v0 + c[4] * v1 + c[5] * v2
        cv2 = c[6] * v0 + c[7] * v1 + c[8] * v2
        arm0, arm1, arm2 = p0 + cv0, p1 + cv1, p2 + cv2
        grad_log = (v0, v1, v2, arm1 * v2 - arm2 * v1, arm2 * v0 - arm0 * v2, arm0 * v1 - arm1 * v0)
        for r in range(6):
            gradient[r] -= term * grad_log[r]
            for s in range(6):
                spread[r, s] += term * grad_log[r] * grad_log[s]
        skew_p = _skew_t(p0, p1, p2)
        cross = _product_t(inverse, skew_p)  # Σ term Jᵀ S⁻¹ J (J = [I, -[p]x]), as solvers.pose_matrices
        for r in range(3):
            for s in range(3):
                gauss_newton[r, s] += term * inverse[3 * r + s]
                gauss_newton[r, 3 + s] -= term * cross[3 * r + s]
                gauss_newton[3 + s, r] -= term * cross[3 * r + s]
                gauss_newton[3 + r, 3 + s] -= term * (skew_p[3 * r] * cross[s] + skew_p[3 * r + 1] * cross[3 + s]
                                                      + skew_p[3 * r + 2] * cross[6 + s])
        skew_v = _skew_t(v0, v1, v2)
        skew_cv = _skew_t(cv0, cv1, cv2)
        c_skew_v = _product_t(c, skew_v)
        u = (c_skew_v[0] - skew_cv[0], c_skew_v[1] - skew_cv[1], c_skew_v[2] - skew_cv[2],
             c_skew_v[3] - skew_cv[3], c_skew_v[4] - skew_cv[4], c_skew_v[5] - skew_cv[5],
             c_skew_v[6] - skew_cv[6], c_skew_v[7] - skew_cv[7], c_skew_v[8] - skew_cv[8])
        inverse_u = _product_t(inverse, u)
        _add_transposed_product_t(term, skew_v, c_skew_v, second)
        _add_transposed_product_t(-term, u, inverse_u, second)
        _add_transposed_product_t(term, inverse_u, skew_p, mixed)
        arm = (arm0, arm1, arm2)
        v = (v0, v1, v2)
        for r in range(3):
            for s in range(3):
                spin[r, s] += term * v[r] * arm[s]
                across[r, s] += term * inverse_u[3 * r + s]
    exact = gauss_newton - spread
    trace = spin[0, 0] + spin[1, 1] + spin[2, 2]
    for r in range(3):
        for s in range(3):
            exact[3 + r, 3 + s] -= (second[r, s] + mixed[r, s] + mixed[s, r] + 0.5 * (spin[r, s] + spin[s, r])
                                    - (trace if r == s else 0.0))
            exact[3 + r, s] += across[s, r]
            exact[s, 3 + r] += across[s, r]
    return gradient, gauss_newton, exact


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _d2d_pose_buffers(n_fixed, n_moving):
    """:func:`d2d_gauss_newton`'s buffers for one pose: ``(rotated (n_moving, 3), moved (n_moving, 3),
    moved_covariances (n_moving, 3, 3))`` and :func:`d2d_kept_pairs`' ``(count, fixed index, moving index, log
    terms)``."""
    size = n_fixed * n_moving
    return (np.empty((n_moving, 3)), np.empty((n_moving, 3)), np.empty((n_moving, 3, 3)), np.zeros(1, dtype=np.int64),
            np.empty(size, dtype=np.int64), np.empty(size, dtype=np.int64), np.empty(size))


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _d2d_cost_at(fixed_means, fixed_covariances, offsets, moving_covariances, centre, log_weights, screen, floor,
                 rotation, translation, buffers):
    """The D2D cost at the pose ``(R, t')`` (:func:`d2d_negative_overlap`), the moving mixture moved into
    ``buffers``: ``p = R (μⱼ - c)``, ``p + c + t'`` and ``R Σⱼ Rᵀ``."""
    rotated, moved, moved_covariances, count, fixed_index, moving_index, log_terms = buffers
    turned = np.empty((3, 3))
    for j in range(offsets.shape[0]):
        for a in range(3):
            rotated[j, a] = (rotation[a, 0] * offsets[j, 0] + rotation[a, 1] * offsets[j, 1]
                             + rotation[a, 2] * offsets[j, 2])
            moved[j, a] = rotated[j, a] + centre[a] + translation[a]
        _product(rotation, moving_covariances[j], turned)
        for a in range(3):
            for b in range(3):
                moved_covariances[j, a, b] = (turned[a, 0] * rotation[b, 0] + turned[a, 1] * rotation[b, 1]
                                              + turned[a, 2] * rotation[b, 2])
    return d2d_negative_overlap(fixed_means, fixed_covariances, moved, moved_covariances, log_weights, screen, floor,
                                count, fixed_index, moving_index, log_terms)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def d2d_gauss_newton(fixed_means, fixed_covariances, offsets, moving_covariances, centre, log_weights, screen, floor,
                     scale, max_iter, tol, damping, max_step, constants, rotations, translations, costs):
    """:func:`dgmm.registration.solvers.minimise_gauss_newton` on the D2D kernels, from the pose ``rotations[0]``,
    ``translations[0]`` (the moving means ``μⱼ -> R (μⱼ - c) + c + t'``): the steps of :func:`p2d_gauss_newton`,
    with no Python between the kernels.

    Parameters
    ----------
    fixed_means, fixed_covariances, log_weights, screen, floor
        As :func:`d2d_negative_overlap` takes them.
    offsets : ndarray of shape (n_moving, 3)
        ``μⱼ - c``.
    moving_covariances : ndarray of shape (n_moving, 3, 3)
    centre : ndarray of shape (3,)
        ``c``.
    scale, max_iter, tol, damping, max_step, constants, rotations, translations, costs
        As :func:`p2d_gauss_newton` takes them.

    Returns
    -------
    iterations, converged, status
        As :func:`p2d_gauss_newton`'s.
    """
    n_fixed, n_moving = fixed_means.shape[0], offsets.shape[0]
    buffers = _d2d_pose_buffers(n_fixed, n_moving), _d2d_pose_buffers(n_fixed, n_moving)
    return _gauss_newton_loop((fixed_means, fixed_covariances, offsets, moving_covariances, centre, log_weights, screen,
                               floor), *buffers, scale, max_iter, tol, damping, max_step, constants, rotations,
                              translations, costs)


P2D_PROBLEM = 6
"""The length of P2D's problem tuple, ``(local, shift, table, precisions, precision_means, screen)``; D2D's is
``(fixed_means, fixed_covariances, offsets, moving_covariances, centre, log_weights, screen, floor)``."""


def _cost_at(problem, rotation, translation, move, buffers):
    """The cost of a Gauss-Newton ``problem`` at the pose ``(R, t' + move[:3])``, leaving in ``buffers`` what
    :func:`_derivatives_at` reads; compiled code only (its overload picks P2D's or D2D's cost from the problem)."""
    raise NotImplementedError("compiled code only")


@overload(_cost_at, jit_options={"error_model": "numpy"})
def _cost_at_of(problem, rotation, translation, move, buffers):
    if len(problem) == P2D_PROBLEM:
        def p2d(problem, rotation, translation, move, buffers):
            local, shift, table, _, _, screen = problem
            offset = np.empty(3)
            for a in range(3):
                offset[a] = shift[a] + translation[a] + move[a]
            return p2d_negative_mean_log_likelihood(local, rotation, offset, table, screen, True, *buffers)
        return p2d

    def d2d(problem, rotation, translation, move, buffers):
        moved_by = np.empty(3)
        for a in range(3):
            moved_by[a] = translation[a] + move[a]
        return _d2d_cost_at(*problem, rotation, moved_by, buffers)
    return d2d


def _derivatives_at(problem, buffers):
    """The gradient, Gauss-Newton and exact Hessians of a Gauss-Newton ``problem`` at the pose whose
    :func:`_cost_at` filled ``buffers``; compiled code only."""
    raise NotImplementedError("compiled code only")


@overload(_derivatives_at, jit_options={"error_model": "numpy"})
def _derivatives_at_of(problem, buffers):
    if len(problem) == P2D_PROBLEM:
        return lambda problem, buffers: p2d_pose_derivatives(problem[3], problem[4], *buffers)
    return lambda problem, buffers: d2d_pose_derivatives(problem[0], problem[1], buffers[1], buffers[0], buffers[2],
                                                         *buffers[3:])


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _gauss_newton_loop(problem, kept, trial, scale, max_iter, tol, damping, max_step, constants, rotations,
                       translations, costs):
    """:func:`p2d_gauss_newton`'s and :func:`d2d_gauss_newton`'s loop (their arguments, their results): the
    solver's steps on ``problem``'s cost, ``kept`` and ``trial`` the buffers of the pose taken and the pose tried."""
    over_relaxation, contraction, min_damping, max_damping, backtracks = constants
    scratch, factor = np.empty((6, 6)), np.zeros((6, 6))
    step, move = np.empty(6), np.zeros(6)
    rotation, translation = rotations[0].copy(), translations[0].copy()
    new_rotation = np.empty((3, 3))
    cost = _cost_at(problem, rotation, translation, move, kept)
    costs[0] = cost
    iteration = 0
    converged = False
    while iteration < max_iter and not converged:
        gradient, gauss_newton, exact = _derivatives_at(problem, kept)
        if not (np.isfinite(cost) and np.all(np.isfinite(gradient)) and np.all(np.isfinite(gauss_newton))):
            return iteration, False, NOT_FINITE
        newton = _cholesky(exact, factor)
        hessian = exact if newton else gauss_newton
        slope, length, new_cost, capped = 0.0, 1.0, cost, False
        iteration += 1
        found = False
        while True:
            _damped_step(hessian, gradient, damping, scratch, factor, step)
            _capped(step, 1.0, scale, max_step, step)
            converged = _step_size(step, scale) < tol
            if converged:  # the pose moves by less than tol: no need to evaluate it
                break
            slope = gradient @ step
            length = 1.0 if newton else over_relaxation
            for attempt in range(backtracks + 1):  # the line search of solvers._line_search
                capped = _capped(step, length, scale, max_step, move)
                _turned(move[3:], rotation, new_rotation)
                new_cost = _cost_at(problem, new_rotation, translation, move, trial)
                if new_cost <= cost:
                    found = True
                    break
                if attempt < backtracks:
                    curvature = new_cost - cost - slope * length
                    length *= min(max(-slope * length / (2.0 * curvature), 0.1), 0.5) if curvature > 0 else 0.1
            if found or damping > max_damping:
                break
            damping *= 10.0
        if found:
            rotation[:, :] = new_rotation
            translation += move[:3]
            kept, trial = trial, kept
            if not newton:
                over_relaxation = _next_over_relaxation(cost, slope, length, new_cost)
            cost = new_cost
            damping = max(damping / 10.0, min_damping)
            converged = (newton and length == 1.0 and not capped
                         and contraction * _step_size(step, scale) ** 2 < tol)
        elif not converged:
            return iteration, False, SEARCH_FAILED
        rotations[iteration] = rotation
        translations[iteration] = translation
        costs[iteration] = cost
    return iteration, converged, ENDED
