"""Gaussian mixture EM over geometric primitives (points, triangles, Gaussians, ...).

One EM serves every primitive kind (paper §III and eqs. 11–13): a primitive ``p`` with size ``alpha_p``,
mean ``mu_p`` and covariance ``Sigma_p`` enters only through ``alpha_p``, ``mu_p`` and its second moment
``E[x xᵀ] = mu_p mu_pᵀ + Sigma_p``. The E- and M-step are the point formulas with ``x xᵀ`` replaced by that
second moment, so both become one GEMM each over a (n_prims, d(d+1)/2 + d + 2) table of moment features (11
columns in 3-D):

* E-step: ``log rho_ip = log lambda_i + log N(mu_p; mu_i, Sigma_i) − ½ tr(Sigma_i⁻¹ Sigma_p)``
  (= ``log lambda_i + E_{x~p}[log N(x; mu_i, Sigma_i)]``), ``eta_ip = softmax_i(log rho_ip)``.
* M-step: ``w_ip = eta_ip alpha_p``, ``mu_i = Σ_p w_ip mu_p / W_i``,
  ``Sigma_i = Σ_p w_ip E_p[x xᵀ] / W_i − mu_i mu_iᵀ + reg_covar I`` (eqs. 12, 13).
* Bound: ``Σ_p alpha_p logsumexp_i(log rho_ip) / Σ_p alpha_p`` (eq. 11); the mean log-likelihood for points.

The M-step needs of the (n_components, n_prims) responsibilities only ``resp · moments`` (n_components, 10 in 3-D),
so each iteration streams over blocks of primitives (``dgmm.em_blocks``): memory is O(n_prims × 11 + block ×
n_components), and blocks may run on several threads without changing a bit of the result.

Any dimension ``d >= 1`` (the paper's §V-A update equations do not depend on it): the table's layout is
:class:`dgmm.gaussian.Layout`, the upper triangle diagonal first, so that the 3-D table is the paper sweep's, column for
column; its product with :func:`dgmm.gaussian.log_density_coefficients` is ``log rho``.
A screened fit runs a compiled kernel in 3-D (:mod:`dgmm.compiled.e_step`) and numpy products in other dimensions.

Read top to bottom: checks, moment features, E-step, M-step, initialisation, estimator (the EM variants are in
:mod:`dgmm.variants`).
Conventions follow ``sklearn.mixture.GaussianMixture`` (``covariance_type`` full, tied, diag, spherical: EM runs on
(K, d, d) matrices, constrained in the M-step, :func:`_constrained`), and so does the estimator's contract
(input validation, ``n_features_in_``, ``NotFittedError``): ``precisions_cholesky_`` is upper
triangular ``U`` with precision ``U Uᵀ``; ``reg_covar`` on the diagonal, absolute, in the data's squared units;
``10 eps`` on component masses.

Units do not matter: EM and scoring run on coordinates centred and divided by a ``unit``, the power of two
nearest below the RMS radius of the primitives (of the mixture, when scoring), with ``reg_covar / unit²``.
Multiplying by a power of two is exact, so the internal numbers are the data-unit numbers scaled exactly
(bit-identical results wherever data-unit arithmetic did not overflow), and the log-determinant is taken of the
data-unit precision so that ``log rho`` is the data-unit one. A fit either returns finite parameters or raises
(InputError for data or parameters, FitError naming the EM iteration).
"""
from __future__ import annotations

import functools
import numbers
from dataclasses import dataclass

import numpy as np
from sklearn.base import BaseEstimator, DensityMixin
from sklearn.cluster import KMeans
from sklearn.exceptions import NotFittedError as _SklearnNotFittedError
from sklearn.utils.validation import check_is_fitted, validate_data

from dgmm.em_blocks import DEFAULT_MEMORY_LIMIT, BlockPass
from dgmm.errors import FitError, InputError, InputTypeError
from dgmm.gaussian import SCREEN, layout, log_density_coefficients, quadratic_features, unpack
from dgmm.primitives import Primitives, as_primitives
from dgmm.variants import INITS, VARIANTS

_EPS = 10.0 * np.finfo(np.float64).eps
# Bytes of log rho per block when scoring: a block stays in the CPU cache from its product to its log-normalisers;
# rows are scored independently, so blocks change no bit
# (with the padding below).
_SCORE_BLOCK_BYTES = 1 << 20
# Scoring products are padded with zero rows to a multiple of this: BLAS computes the rows past the last full tile
# of a product with other kernels, which round differently on some CPUs (OpenBLAS's Haswell kernels on an AMD EPYC),
# so a primitive's score would depend on where its block ends; in full tiles every row is computed alike.
_SCORE_ROW_TILE = 8
_TABLE_CHUNK = 1 << 16  # rows per block when building a 3-D moment table, to bound its (rows, 3, 3) temporaries
_KMEANS_SAMPLE = 1 << 17  # k-means initialisation runs on at most this many primitives (a random subsample)
# Floor for log rho − max before exp. exp(−300) ≈ 5e−131 vanishes beside the row's largest term (1) exactly as
# 0 would, but keeps exp off its slow underflow path and keeps responsibility × moment products in the M-step
# GEMM from becoming subnormal (each ≈10× slower per element).
_LOG_FLOOR = -300.0
# RMS radius of the primitives about their centre that a fit accepts: beyond, covariances in squared data units
# are not normal float64 numbers (1e-152² = 1e-304; 1e152² = 1e304, max 1.8e308).
_RADIUS_RANGE = (1e-152, 1e152)


def _is_int(low):
    return lambda v: isinstance(v, numbers.Integral) and not isinstance(v, bool) and v >= low


def _is_real(low):
    return lambda v: isinstance(v, numbers.Real) and not isinstance(v, bool) and np.isfinite(v) and v >= low


COVARIANCE_TYPES = ("full", "tied", "diag", "spherical")
# Hyperparameters, checked once at the public boundary: name -> (check, what it must be).
_PARAMETERS = {
    "n_components": (_is_int(1), "an integer >= 1"),
    "covariance_type": (lambda v: v in COVARIANCE_TYPES, f"one of {COVARIANCE_TYPES}"),
    "init": (lambda v: v in INITS, f"one of {INITS}"),
    "max_iter": (_is_int(1), "an integer >= 1"),
    "tol": (lambda v: v is None or _is_real(0)(v), "None or a finite number >= 0"),
    "reg_covar": (_is_real(0), "a finite number >= 0"),
    "variant": (lambda v: v in VARIANTS, f"one of {tuple(VARIANTS)}"),
    "callback": (lambda v: v is None or callable(v), "None or a callable(iteration, model)"),
    "memory_limit": (_is_real(1), "a number of bytes >= 1"),
    "n_jobs": (lambda v: v is None or (_is_int(-(1 << 30))(v) and v != 0), "None or a nonzero integer"),
    "screen": (lambda v: v is None or _is_real(1)(v), "None or a finite number >= 1"),
}


_FITTED = ("weights_", "means_", "precisions_cholesky_", "covariances_")


class NotFittedError(InputError, _SklearnNotFittedError):
    """A model used before it was fitted: a :class:`dgmm.InputError` and scikit-learn's ``NotFittedError``."""


def _layout_of(n_columns):
    """The :class:`dgmm.gaussian.Layout` of a table of ``n_columns`` (``d(d+1)/2 + d + 2``) columns."""
    return layout(int(round((np.sqrt(8 * n_columns - 15) - 3) / 2)))


def _check_bound(bound):
    """FitError unless the EM bound is finite."""
    if not np.isfinite(bound):
        raise FitError(f"the bound is {bound}: a component collapsed or the primitives lie too far apart for "
                       f"float64; increase reg_covar or reduce n_components")


def _finite_mean(log_likelihoods, weights=None):
    """Their (weighted) mean as a float, or an InputError if it overflows float64."""
    with np.errstate(over="ignore"):
        mean = float(np.average(log_likelihoods, weights=weights))
    if not np.isfinite(mean):
        raise InputError(f"the mean log-likelihood is beyond float64 ({mean}): the input lies too far from the mixture")
    return mean


def _check_array(name, value, shape):
    """``value`` as a finite float64 array of ``shape``, or an InputError naming it."""
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} is not a numeric array: {exc}") from None
    if array.shape != shape:
        raise InputError(f"{name} must have shape {shape}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise InputError(f"{name} contains NaN or infinite values")
    return array


def _unit(deviations, covariances, weights):
    """The power of two at or below the RMS radius ``sqrt(mean_p(|mu_p − c|² + tr Sigma_p))``, and the radius.

    Parameters
    ----------
    deviations : ndarray of shape (n, d)
        Means minus their centre ``c``.
    covariances : ndarray of shape (n, d, d)
    weights : ndarray of shape (n,)

    Returns
    -------
    unit : float
        ``2**e`` with ``radius / 2 < unit <= radius``; 1 when the radius is 0 (every primitive one point).
    radius : float
    """
    variances = np.diagonal(covariances, axis1=1, axis2=2)
    peak = max(np.abs(deviations).max(), np.sqrt(np.abs(variances).max()))
    if peak == 0:
        return 1.0, 0.0
    _, exponent = np.frexp(peak)  # squares of values scaled by 2**-exponent neither overflow nor underflow
    scaled = np.ldexp(deviations, -exponent)
    squares = np.einsum("ij,ij->i", scaled, scaled)
    squares += np.ldexp(variances, -2 * exponent).sum(axis=1)  # the traces
    radius = np.ldexp(np.sqrt(np.average(squares, weights=weights)), exponent)
    return np.ldexp(1.0, np.frexp(radius)[1] - 1), radius


# ---------------------------------------------------------------------------------------------------------
# Moment features: one row per primitive, so that E- and M-step are single matrix products.
# ---------------------------------------------------------------------------------------------------------

def _moment_features(means, covariances, centre, scale, unit=1.0, out=None):
    """Feature table ``(n_prims, n_columns)`` of the centred moments of primitives given by means and covariances.

    The :func:`dgmm.gaussian.quadratic_features` of their means with the covariances added to ``x xᵀ`` (3-D: 11
    columns), all multiplied by the E-step ``scale`` (None: unscaled); the last column is an unscaled one that
    carries the per-component constant. Then ``features @ log_density_coefficients(...)ᵀ`` is ``log rho``. Moments
    are of ``(x − centre) / unit``, computed without forming the data-unit second moments (which overflow at
    1e155). Written into ``out`` when given.
    """
    shape = layout(means.shape[1])
    features = np.empty((len(means), shape.n_columns)) if out is None else out
    quadratic_features((means - centre) / unit, out=features[:, :shape.n_quadratic])
    second = np.divide(covariances[:, shape.rows, shape.cols], unit**2)
    second[:, shape.d:] *= 2.0  # off-diagonals doubled, as the features'
    features[:, :shape.n_second] += second
    if scale is not None:
        features[:, :shape.n_quadratic] *= np.reshape(scale, (-1, 1))
    features[:, shape.n_quadratic] = 1.0
    return features


def _moment_table(prims, centre, unit, compiled=False):
    """:func:`_moment_features` (unscaled) of all ``prims``, built chunk by chunk so that its (n_prims, d, d)
    temporaries never exist for all primitives at once; with ``compiled`` (3-D: the screened fits, which load numba
    anyway) in one compiled pass, the same values (:func:`dgmm.compiled.e_step.moment_table`)."""
    if compiled:
        from dgmm.compiled.e_step import moment_table  # numba loads only for screened fits
        return moment_table(prims.means, prims.covariances, np.asarray(centre, dtype=float), float(unit))
    d = prims.dimension
    table = np.empty((len(prims), layout(d).n_columns))
    chunk = max(1, _TABLE_CHUNK * 9 // d**2)
    for start in range(0, len(prims), chunk):
        rows = slice(start, start + chunk)
        _moment_features(prims.means[rows], prims.covariances[rows], centre, None, unit, out=table[rows])
    return table


# ---------------------------------------------------------------------------------------------------------
# E-step, M-step
# ---------------------------------------------------------------------------------------------------------

def _exp_shifted_in_place(log_rho):
    """Replace ``log rho`` by ``exp(max(log rho − peak, floor))`` in place; return ``peak`` and the column sums,
    both (n_rows,)."""
    peak = log_rho.max(axis=0)
    log_rho -= peak
    np.maximum(log_rho, _LOG_FLOOR, out=log_rho)
    np.exp(log_rho, out=log_rho)
    return peak, log_rho.sum(axis=0)


def _exp_shifted(log_rho, screen):
    """:func:`_exp_shifted_in_place`, or with a ``screen`` the terms below ``e^-screen`` set to 0
    (:mod:`dgmm.compiled.e_step`)."""
    if screen is None:
        return _exp_shifted_in_place(log_rho)
    from dgmm.compiled.e_step import exp_shifted_screened  # numba loads only for screened fits
    return exp_shifted_screened(log_rho, float(screen))


def _normalise_in_place(log_rho, screen=None):
    """Turn ``log rho`` into responsibilities in place; return ``logsumexp_i log rho`` per primitive (n_rows,)."""
    peak, total = _exp_shifted(log_rho, screen)
    log_rho /= total
    return peak + np.log(total)


def _scaled_table(table, scale):
    """The moment table with the E-step ``scale`` (n_rows,) on its columns but the last, made once per fit: the
    table itself when every scale is 1 (textbook EM)."""
    if np.all(scale == 1.0):
        return table
    scaled = table.copy()
    scaled[:, :-1] *= scale[:, None]
    return scaled


@dataclass(frozen=True)
class _FitInputs:
    """What EM's iterations read, made once per fit: the moment table in internal units (module docstring), its
    copy with the E-step scale (:func:`_scaled_table`), the M-step weights, the screen, and a buffer that each
    E-step fills with every primitive's log-normaliser."""

    table: np.ndarray
    features: np.ndarray
    mstep_weights: np.ndarray
    unit: float
    screen: float | None
    log_norm: np.ndarray


def _block_sums(inputs, coefficients, rows, out):
    """The E-step of the primitives ``rows`` and its M-step sums (:func:`_m_step_sums`); their log-normalisers
    into ``inputs.log_norm``.

    ``rho / max_i rho`` goes into ``out`` ((n_components, n_rows)); responsibilities are it over each primitive's
    sum, and the M-step divides its weights by the sums instead of dividing every responsibility.
    """
    rho = np.dot(coefficients, inputs.features[rows].T, out=out)  # the per-primitive passes run down its rows
    peak, total = _exp_shifted(rho, inputs.screen)
    inputs.log_norm[rows] = peak + np.log(total)
    return _m_step_sums(rho, inputs.table[rows, :-1], inputs.mstep_weights[rows] / total)


def _screened_block_sums(inputs, transposed_coefficients, rows, out):
    """:func:`_block_sums` of a screened 3-D fit, in one compiled kernel over the pairs within the screen
    (:func:`dgmm.compiled.e_step.screened_e_step_sums`)."""
    from dgmm.compiled.e_step import screened_e_step_sums  # numba loads only for screened fits
    return screened_e_step_sums(inputs.features[rows], transposed_coefficients, inputs.table[rows, :-1],
                                inputs.mstep_weights[rows], float(inputs.screen), inputs.log_norm[rows])


def _screened_sums(inputs, transposed_coefficients, blocks):
    """The M-step sums of a screened 3-D fit's E-step over every block: on ``blocks``' threads block by block, or
    on one thread in one compiled call over the blocks that adds their sums in the same order
    (:func:`dgmm.compiled.e_step.screened_e_step_block_sums`)."""
    if blocks.threaded:
        return blocks.run(functools.partial(_screened_block_sums, inputs, transposed_coefficients))
    from dgmm.compiled.e_step import screened_e_step_block_sums  # numba loads only for screened fits
    starts = np.array([rows.start for rows in blocks.blocks] + [blocks.blocks[-1].stop])
    return screened_e_step_block_sums(inputs.features, transposed_coefficients, inputs.table[:, :-1],
                                      inputs.mstep_weights, float(inputs.screen), inputs.log_norm, starts)


def _e_step(inputs, params, blocks):
    """EM's E-step under ``params`` (weights, means, precision Choleskys in internal units), block by block: the
    M-step sums of its responsibilities and the bound (the size-weighted mean of the log-normalisers)."""
    coefficients = log_density_coefficients(*params, unit=inputs.unit)
    if inputs.screen is not None and coefficients.shape[1] == layout(3).n_columns:
        sums = _screened_sums(inputs, np.ascontiguousarray(coefficients.T), blocks)
    else:
        sums = blocks.run(functools.partial(_block_sums, inputs, coefficients))
    return sums, np.dot(inputs.mstep_weights, inputs.log_norm) / inputs.mstep_weights.sum()


class EStep:
    """EM's E-step under one mixture given in data units, set up once (its internal units, module docstring, and
    its coefficient table) for any number of calls on any primitives.

    Parameters
    ----------
    weights, means, covariances, precisions_cholesky : ndarrays of shape (K,), (K, d), (K, d, d), (K, d, d)
        In data units (a fitted mixture's attributes, or its ``e_step_params_``).
    screen : float or None, default=None
        :class:`GaussianMixture`'s ``screen``, for responsibilities as a screened fit's E-step computes them.
    """

    def __init__(self, weights, means, covariances, precisions_cholesky, screen=None):
        self.screen = screen
        self.centre = weights @ means
        self.unit, _ = _unit(means - self.centre, covariances, weights)
        self.coefficients = log_density_coefficients(weights, (means - self.centre) / self.unit,
                                                    precisions_cholesky * self.unit, unit=self.unit)

    def log_rho_blocks(self, means, covariances, scale=1.0):
        """``log rho`` of the primitives ``(means, covariances)``, shape (n_components, n_rows) per cache-sized
        block of ``_SCORE_BLOCK_BYTES``, with the E-step ``scale`` on each primitive's expected log-density (a
        float, or one per primitive).

        Each block is a view of the (n_rows, n_components) product, its rows padded with zeros to a multiple of
        ``_SCORE_ROW_TILE`` and every block but the last a multiple of it: BLAS then computes each row the same
        whatever the other rows, so scores do not depend on how the primitives are split.
        """
        return (rows.T for rows in self._log_rho_rows(means, covariances, scale))

    def log_normalisers(self, means, covariances):
        """``logsumexp_i log rho`` of each primitive (n_rows,), the textbook E-step's, in one compiled pass a block,
        the terms below ``e^-SCREEN`` of a primitive's best left out (which changes no sum beyond rounding,
        :data:`dgmm.gaussian.SCREEN`): in 3-D from the moment table, ``log rho`` never written out
        (:func:`dgmm.compiled.e_step.table_log_normalisers`; the table, 11 floats a row, is about the size of the
        means and covariances it is made from, 12), else from BLAS's ``log rho`` blocks
        (:mod:`dgmm.compiled.scoring`). numba loads only where a mixture scores."""
        if means.shape[1] != 3:
            from dgmm.compiled.scoring import screened_log_normalisers

            blocks = self._log_rho_rows(means, covariances, 1.0)
            return np.concatenate([screened_log_normalisers(rows, SCREEN) for rows in blocks])
        from dgmm.compiled.e_step import moment_table, table_log_normalisers

        table = moment_table(means, covariances, np.asarray(self.centre, dtype=float), float(self.unit))
        return table_log_normalisers(table, np.ascontiguousarray(self.coefficients.T), SCREEN)

    def _log_rho_rows(self, means, covariances, scale):
        """:meth:`log_rho_blocks` as (n_rows, n_components) blocks, each C-contiguous."""
        scale = np.broadcast_to(np.asarray(scale, dtype=float), (len(means),))
        tile = _SCORE_ROW_TILE
        rows = max(tile, _SCORE_BLOCK_BYTES // (8 * len(self.coefficients)) // tile * tile)
        for start in range(0, len(means), rows):
            block = slice(start, start + rows)
            count = len(means[block])
            features = np.empty((-(-count // tile) * tile, self.coefficients.shape[1]))
            features[count:] = 0.0
            _moment_features(means[block], covariances[block], self.centre, scale[block], self.unit,
                             out=features[:count])
            yield np.dot(features, self.coefficients.T)[:count]

    def responsibilities(self, means, covariances, scale=1.0):
        """Responsibilities of the primitives ``(means, covariances)``, shape (n_rows, n_components)."""
        blocks = list(self.log_rho_blocks(means, covariances, scale))
        for block in blocks:
            _normalise_in_place(block, self.screen)
        return np.ascontiguousarray(np.concatenate(blocks, axis=1).T)


def responsibilities(prims, weights, means, covariances, precisions_cholesky, scale=1.0):
    """Responsibilities of ``prims`` under a mixture, shape (n_prims, n_components), as EM's E-step computes them.

    Parameters
    ----------
    prims : Primitives
    weights, means, covariances, precisions_cholesky : ndarrays of shape (K,), (K, d), (K, d, d), (K, d, d)
        In data units (a fitted mixture's attributes, or its ``e_step_params_``).
    scale : float or ndarray of shape (n_prims,), default=1.0
        The E-step's factor on each primitive's expected log-density (a variant's, :mod:`dgmm.variants`; 1 is
        the textbook E-step).
    """
    return EStep(weights, means, covariances, precisions_cholesky).responsibilities(prims.means, prims.covariances,
                                                                                    scale)


def _m_step_sums(resp, moments, row_weights):
    """``resp ·`` (``moments``, the moment table's rows but their last column, × ``row_weights``, their M-step
    weights): every component's second and first moment sums and mass (eqs. 12, 13), shape (n_components,
    n_quadratic), 10 in 3-D. ``resp`` is (n_components, n_rows)."""
    return resp @ (moments * row_weights[:, None])


def _m_step(sums, reg_covar, covariance_type="full"):
    """Mixture parameters (weights, centred means, precision Choleskys, covariances) from the M-step sums
    (:func:`_m_step_sums` added over all primitives); covariances and Choleskys as (K, d, d) matrices whatever the
    ``covariance_type`` (:func:`_constrained`)."""
    shape = _layout_of(sums.shape[1] + 1)
    d = shape.d
    mass = sums[:, shape.one] + _EPS
    means = sums[:, shape.mean] / mass[:, None]
    second = sums[:, :shape.n_second] / mass[:, None]
    second[:, d:] *= 0.5  # the features' doubled off-diagonals
    covariances = unpack(second) - means[:, :, None] * means[:, None, :]
    if covariance_type != "full":
        covariances = _constrained(covariances, mass, covariance_type)
    covariances[:, np.arange(d), np.arange(d)] += reg_covar
    return mass / mass.sum(), means, _precisions_cholesky(covariances), covariances


def _constrained(scatters, mass, covariance_type):
    """The M-step covariances of a ``covariance_type`` other than full, as (K, d, d) matrices, from each component's
    full-covariance scatter ``S_i = Σ_p w_ip E_p[(x − mu_i)(x − mu_i)ᵀ] / W_i`` (before ``reg_covar``).

    The bound's covariance terms are ``−½ W_i (log det C_i + tr(C_i⁻¹ S_i))``, and ``S_i = Σ_p w_ip (Sigma_p +
    (mu_p − mu_i)(mu_p − mu_i)ᵀ) / W_i``. Their maximiser over diagonal ``C_i`` is ``diag(S_i)`` (a primitive's
    covariance enters through its diagonal), over ``s_i I`` it is ``tr(S_i) / d`` (through its trace), and over one
    ``C`` shared by all components ``Σ_i W_i S_i / Σ_i W_i`` (pooled). In the E-step the term ``−½ tr(C_i⁻¹
    Sigma_p)`` of such a ``C_i`` likewise reads only the diagonal, the trace or all of ``Sigma_p``.
    """
    k, d = len(mass), scatters.shape[1]
    if covariance_type == "tied":
        return np.repeat((np.einsum("k,kij->ij", mass, scatters) / mass.sum())[None], k, axis=0)
    variances = np.diagonal(scatters, axis1=1, axis2=2)
    if covariance_type == "spherical":
        variances = np.repeat(variances.mean(axis=1, keepdims=True), d, axis=1)
    return variances[:, :, None] * np.eye(d)


def _typed(matrices, covariance_type):
    """(K, d, d) covariances or precision Choleskys in scikit-learn's shape of ``covariance_type``: (K, d, d),
    (d, d) tied, (K, d) diagonal, (K,) spherical."""
    if covariance_type == "tied":
        return matrices[0]
    if covariance_type == "diag":
        return np.diagonal(matrices, axis1=1, axis2=2).copy()
    if covariance_type == "spherical":
        return matrices[:, 0, 0].copy()
    return matrices


def _full(values, covariance_type, k, d):
    """:func:`_typed`'s inverse: (K, d, d) matrices from scikit-learn's shape of ``covariance_type``."""
    if covariance_type == "tied":
        return np.broadcast_to(values, (k, d, d))
    if covariance_type == "diag":
        return values[:, :, None] * np.eye(d)
    if covariance_type == "spherical":
        return values[:, None, None] * np.eye(d)
    return values


def _typed_shape(covariance_type, k, d):
    """scikit-learn's shape of ``covariances_`` and ``precisions_init`` for ``covariance_type``."""
    return {"full": (k, d, d), "tied": (d, d), "diag": (k, d), "spherical": (k,)}[covariance_type]


def _precisions_cholesky(covariances):
    """Upper-triangular ``U`` with ``U Uᵀ = Σ⁻¹`` for each component (scikit-learn's convention)."""
    try:
        lower = np.linalg.cholesky(covariances)  # NaN in, NaN out: checked below
        precisions_cholesky = np.swapaxes(np.linalg.inv(lower), 1, 2)
        failed = not np.all(np.isfinite(precisions_cholesky))
    except np.linalg.LinAlgError:
        failed = True
    if failed:
        bad = [k for k, c in enumerate(covariances) if not np.all(np.isfinite(c)) or np.linalg.eigvalsh(c)[0] <= 0]
        raise FitError(
            f"component {bad[0] if bad else '?'} collapsed (covariance not positive definite): duplicate or "
            f"coplanar primitives need reg_covar > 0; or increase reg_covar, or reduce n_components"
        )
    return precisions_cholesky


# ---------------------------------------------------------------------------------------------------------
# Initialisation: responsibilities from k-means or uniform random numbers (as scikit-learn).
# ---------------------------------------------------------------------------------------------------------

def _kmeans_resp(means, weights, n_components, rng):
    """Hard responsibilities from k-means on the primitive means, weighted by size: :func:`_hard_resp` of its labels.

    Above :data:`_KMEANS_SAMPLE` primitives, k-means runs on a uniform random subsample of that many (still
    weighted by size, so it estimates the same weighted objective) and every primitive takes the label of its
    nearest centre: time and memory of the initialisation stay bounded whatever the input size.
    """
    seed = int(rng.integers(np.iinfo(np.int32).max))
    kmeans = KMeans(n_clusters=n_components, n_init=1, random_state=seed)
    if len(means) <= _KMEANS_SAMPLE:
        labels = kmeans.fit(means, sample_weight=weights).labels_
    else:
        sample = np.sort(rng.choice(len(means), _KMEANS_SAMPLE, replace=False))
        labels = kmeans.fit(means[sample], sample_weight=weights[sample]).predict(means)
    return functools.partial(_hard_resp, labels)


def _hard_resp(labels, rows, out):
    """One-hot responsibilities (n_components, n_rows) of the primitives ``rows`` from their ``labels``, in ``out``."""
    out.fill(0.0)
    out[labels[rows], np.arange(out.shape[1])] = 1.0
    return out


def _random_resp(means, weights, n_components, rng):
    """Uniform random soft responsibilities, normalised per primitive: :func:`_uniform_resp` drawing from ``rng``."""
    return functools.partial(_uniform_resp, rng)


def _uniform_resp(rng, rows, out):
    """Responsibilities (n_components, n_rows) of the primitives ``rows``, uniform random numbers normalised per
    primitive, in ``out``; a row per primitive drawn in primitive order (blocks run in order on one thread)."""
    resp = rng.uniform(size=out.shape[::-1])
    return np.divide(resp.T, resp.sum(axis=1), out=out)


def _init_block_sums(inputs, resp, rows, out):
    """:func:`_m_step_sums` of the initial responsibilities ``resp(rows, out)`` of the primitives ``rows``."""
    return _m_step_sums(resp(rows, out), inputs.table[rows, :-1], inputs.mstep_weights[rows])


# init -> function(means, weights, n_components, rng) -> resp(rows, out): responsibilities of rows, in out
_INIT_RESP = {"kmeans": _kmeans_resp, "random": _random_resp}


# ---------------------------------------------------------------------------------------------------------
# The estimator
# ---------------------------------------------------------------------------------------------------------

def _one_line(exc):
    """A scikit-learn validation message on one line: its lines but those printing the array."""
    lines = [line.strip() for line in str(exc).splitlines()]
    return " ".join(line for line in lines if line and not line.startswith(("array=", "[")))


class GaussianMixture(DensityMixin, BaseEstimator):
    """A Gaussian mixture (full, tied, diagonal or spherical covariances) fitted by EM to points, triangles or any
    primitives, in any dimension.

    A scikit-learn estimator (its estimator checks pass): array input is validated by scikit-learn's
    ``validate_data`` (its messages, as :class:`dgmm.InputError`), ``n_features_in_`` is set by ``fit`` and checked
    by every method after it, and a method called before ``fit`` raises :class:`NotFittedError`. Points and
    Gaussians may have any dimension ``d >= 1``, triangles ``d >= 2``.

    Parameters
    ----------
    n_components : int, default=1
    covariance_type : {"full", "tied", "diag", "spherical"}, default="full"
        As scikit-learn's: each component's own full covariance, one full covariance shared by all, diagonal, or
        a multiple of the identity. The M-step takes the full scatter's diagonal, mean variance or
        mass-weighted pool (:func:`_constrained`, where the bound's maximiser is derived), so a primitive's
        covariance enters through its diagonal, trace or pooled form. ``covariances_``, ``precisions_cholesky_``
        and ``precisions_init`` take scikit-learn's shapes: (K, d, d), (d, d), (K, d), (K,).
    init : {"kmeans", "random"}, default="kmeans"
        "kmeans": hard labels from k-means on the primitive means weighted by size; "random": uniform random
        soft responsibilities.
    max_iter : int, default=25
    tol : float or None, default=1e-12
        EM stops when the bound changes by less than ``tol`` between iterations. None (as scikit-learn's SGD
        estimators take it): exactly ``max_iter`` iterations and no E-step after the last M-step, whose only use
        would be the bound (a third of the cost of a 2-iteration fit); ``lower_bound_`` is then the bound of the
        parameters before the last M-step, as scikit-learn's is, and ``history_`` has ``max_iter - 1`` entries.
    reg_covar : float, default=1e-6
        Added to the diagonal of every covariance: absolute, in the data's squared units, as scikit-learn
        does (fitting ``s · X`` with ``reg_covar · s²`` gives the mixture of ``X`` scaled by ``s``). Duplicate
        or coplanar primitives need ``reg_covar > 0``.
    random_state : int, numpy.random.Generator or None, default=None
        Seeds ``np.random.default_rng``; the same seed gives bit-identical fits.
    weights_init : array-like of shape (n_components,), optional
    means_init : array-like of shape (n_components, d), optional
    precisions_init : array-like, optional
        Of shape (n_components, d, d) for "full"; (d, d), (n_components, d), (n_components,) for "tied", "diag",
        "spherical".
        User starting values; those given replace the ones ``init`` computes.
    variant : {"textbook", "authors"}, default="textbook"
        "textbook" is EM for the bound above. "authors" reproduces the authors' published fitting code
        (E-step Mahalanobis-plus-trace term × ``alpha_p / min(alpha)``, M-step not weighted by size); it is
        what makes their mesh fits insensitive to random initialisation. Both are the same for points.
    callback : callable(iteration, model), optional
        Called after every EM iteration with the current parameters set on the model (logging hooks in here).
    memory_limit : int, default=128 MiB
        Bytes of responsibilities EM may hold at once. An input whose ``(n_prims, n_components)``
        responsibilities (8 (n_components + 24) bytes per primitive) fit is one block: exactly the unblocked
        EM. A larger one streams through blocks of 8 MiB (or ``memory_limit`` if smaller) per thread, which
        stay in the CPU cache; beside them a fit holds 12 floats per primitive (plus its input). Blocks
        depend on nothing else, so the result is the same for any ``n_jobs``; another block size changes it
        by rounding only (about 1e-14 of each parameter's scale per iteration).
    n_jobs : int or None, default=None
        Threads running the blocks of each EM iteration (BLAS runs one thread inside each): None is 1, -1
        every CPU, as in scikit-learn. Inputs of a single block use one thread. The k-means initialisation
        runs scikit-learn's k-means with its own (OpenMP) threads; above 131072 primitives it runs on a seeded
        random subsample of that many and labels every primitive by its nearest centre.
    screen : float or None, default=None
        None: every (component, primitive) pair enters the E-step, as in the paper. A number ``s`` (beyond the
        paper): pairs whose term is below ``e^-s`` of the primitive's largest get responsibility 0 and no
        exponential (:mod:`dgmm.compiled.e_step`); at ``s = 50`` the fit is the unscreened one to rounding, in a
        fraction of the E-step's time on surfaces (3-D; in other dimensions the exponentials alone are
        screened). The k-means start is not screened; scoring always leaves out the terms below ``e^-50``,
        which changes no score beyond rounding (:mod:`dgmm.compiled.scoring`).

    Attributes
    ----------
    weights_ : ndarray of shape (n_components,)
    means_ : ndarray of shape (n_components, d)
    covariances_ : ndarray of shape (n_components, d, d)
        Or (d, d), (n_components, d), (n_components,) for "tied", "diag", "spherical".
    precisions_cholesky_ : ndarray of shape (n_components, d, d)
        Upper triangular ``U`` with precision ``U Uᵀ``; shaped as ``covariances_``.
    n_features_in_ : int
        The dimension ``d`` of the input.
    n_iter_ : int
    converged_ : bool
    lower_bound_ : float
        The bound of the fitted parameters on the training primitives.
    history_ : list of float
        The bound after each iteration (but the last when ``tol`` is None); ``history_[-1] == lower_bound_``
        when it is not empty.
    e_step_params_ : tuple of ndarray
        ``(weights, means, covariances, precisions_cholesky)`` (the last two (K, d, d) matrices) whose E-step gave
        the responsibilities of the last M-step (the parameters before it): with ``dgmm.mixture.responsibilities``
        they take a primitive's share out of that M-step exactly, as :mod:`dgmm.odometry.measured_cut` does.
    """

    def __init__(self, n_components=1, *, covariance_type="full", init="kmeans", max_iter=25, tol=1e-12,
                 reg_covar=1e-6, random_state=None, weights_init=None, means_init=None, precisions_init=None,
                 variant="textbook", callback=None, memory_limit=DEFAULT_MEMORY_LIMIT, n_jobs=None, screen=None):
        self.n_components = n_components
        self.covariance_type = covariance_type
        self.init = init
        self.max_iter = max_iter
        self.tol = tol
        self.reg_covar = reg_covar
        self.random_state = random_state
        self.weights_init = weights_init
        self.means_init = means_init
        self.precisions_init = precisions_init
        self.variant = variant
        self.callback = callback
        self.memory_limit = memory_limit
        self.n_jobs = n_jobs
        self.screen = screen

    @classmethod
    def from_parameters(cls, weights, means, covariances, **params):
        """A fitted mixture holding the given parameters, ready to score, predict and sample.

        Parameters
        ----------
        weights : array-like of shape (n_components,)
        means : array-like of shape (n_components, d)
        covariances : array-like
            In scikit-learn's shape of ``covariance_type`` (a key of ``params``, default "full"): (n_components,
            d, d), (d, d) tied, (n_components, d) diagonal, (n_components,) spherical; positive definite, else
            FitError.
        **params
            Other estimator parameters (``covariance_type``, ``random_state``, ...).
        """
        k = len(weights)
        model = cls(n_components=k, **params)
        model.weights_ = _check_array("weights", weights, (k,))
        d = np.shape(means)[-1] if np.ndim(means) == 2 else 3
        model.means_ = _check_array("means", means, (k, d))
        model.covariances_ = _check_array("covariances", covariances, _typed_shape(model.covariance_type, k, d))
        model.n_features_in_ = d
        full = _full(model.covariances_, model.covariance_type, k, d)
        model.precisions_cholesky_ = _typed(_precisions_cholesky(full), model.covariance_type)
        return model

    def _check_parameters(self, prims):
        for name, (check, expected) in _PARAMETERS.items():
            value = getattr(self, name)
            if not check(value):
                raise InputError(f"GaussianMixture {name}={value!r}: must be {expected}")
        n_present = int(np.count_nonzero(prims.weights))
        if self.n_components > n_present:
            raise InputError(f"n_components={self.n_components} is larger than the {n_present} primitives of "
                             f"positive size (n_samples = {n_present})")

    def _initial_params(self, prims, centre, inputs, blocks, rng):
        """Starting (weights, means, precision Choleskys) in internal units: from ``init``, replaced by user
        values."""
        k, d, unit = self.n_components, prims.dimension, inputs.unit
        user = (self.weights_init, self.means_init, self.precisions_init)
        if any(value is None for value in user):
            resp = _INIT_RESP[self.init](prims.means / unit, inputs.mstep_weights, k, rng)
            sums = blocks.run(functools.partial(_init_block_sums, inputs, resp), threads=False)
            weights, means, prec_chol, _ = _m_step(sums, self.reg_covar / unit**2, self.covariance_type)
        if self.weights_init is not None:
            weights = _check_array("weights_init", self.weights_init, (k,))
            if np.any(weights < 0) or not np.isclose(weights.sum(), 1.0):
                raise InputError("weights_init must be non-negative and sum to 1")
        if self.means_init is not None:
            means = (_check_array("means_init", self.means_init, (k, d)) - centre) / unit
        if self.precisions_init is not None:
            shape = _typed_shape(self.covariance_type, k, d)
            precisions = _full(_check_array("precisions_init", self.precisions_init, shape), self.covariance_type,
                               k, d)
            try:  # any factor with U Uᵀ = precision serves; scikit-learn takes the lower Cholesky here too
                prec_chol = np.linalg.cholesky(precisions) * unit
            except np.linalg.LinAlgError:
                raise InputError("precisions_init must be symmetric positive definite") from None
        return weights, means, prec_chol

    def _frame(self, prims, mstep_weights):
        """Centre and unit of the internal coordinates (module docstring), or an InputError."""
        centre = np.average(prims.means, axis=0, weights=mstep_weights)
        unit, radius = _unit(prims.means - centre, prims.covariances, mstep_weights)
        low, high = _RADIUS_RANGE
        if radius > 0 and not low <= radius <= high:
            raise InputError(f"the input's RMS radius about its centre is {radius:.3g}; fits need it in "
                             f"[{low:.0e}, {high:.0e}] (covariances are squared units): rescale the input")
        if not np.isfinite(self.reg_covar / unit**2):
            raise InputError(f"reg_covar={self.reg_covar!r} is too large for an input of RMS radius {radius:.3g}")
        return centre, unit

    def _store(self, params, centre, unit):
        """Set the fitted attributes in data units from internal parameters; FitError if any is not finite."""
        weights, means, prec_chol, covariances = params
        self.weights_ = weights
        self.means_ = means * unit + centre
        self.precisions_cholesky_ = _typed(prec_chol, self.covariance_type) / unit
        self.covariances_ = _typed(covariances, self.covariance_type) * unit**2
        if not all(np.all(np.isfinite(getattr(self, name))) for name in _FITTED):
            raise FitError("a fitted parameter is not finite in data units")

    def fit(self, X, y=None):
        """Fit the mixture by EM.

        Parameters
        ----------
        X : array-like of shape (n_points, d), Primitives, or trimesh.Trimesh
            Points, any primitives, or a mesh (fitted as exact triangles).
        y : ignored

        Returns
        -------
        self
        """
        prims = self._primitives(X, reset=True)
        self._check_parameters(prims)
        scale, mstep_weights = VARIANTS[self.variant](prims.weights)
        centre, unit = self._frame(prims, mstep_weights)
        table = _moment_table(prims, centre, unit, compiled=self.screen is not None and prims.dimension == 3)
        inputs = _FitInputs(table, _scaled_table(table, scale), mstep_weights, unit, self.screen, np.empty(len(prims)))
        reg_covar = self.reg_covar / unit**2
        rng = np.random.default_rng(self.random_state)
        row_floats = 2 * table.shape[1] + 2
        with BlockPass(len(prims), self.n_components, self.memory_limit, self.n_jobs, row_floats) as blocks:
            try:
                params = self._initial_params(prims, centre, inputs, blocks, rng)
                del prims  # the loop needs only the moment table (the caller may still hold the input)
                sums, bound = _e_step(inputs, params, blocks)
                _check_bound(bound)
            except FitError as exc:
                raise FitError(f"EM initialisation ({self.init}): {exc}") from None
            self.history_, self.converged_ = [], False
            for iteration in range(1, self.max_iter + 1):
                previous = bound
                scored = self.tol is not None or iteration < self.max_iter
                e_step_params = params[:3]  # whose E-step gave ``sums``
                try:
                    params = _m_step(sums, reg_covar, self.covariance_type)
                    if scored:
                        sums, bound = _e_step(inputs, params[:3], blocks)
                        _check_bound(bound)
                    self._store(params, centre, unit)
                except FitError as exc:
                    raise FitError(f"EM iteration {iteration}: {exc}") from None
                if scored:
                    self.history_.append(float(bound))
                self.n_iter_ = iteration
                if self.callback is not None:
                    self.callback(iteration, self)
                if self.tol is not None and abs(bound - previous) < self.tol:
                    self.converged_ = True
                    break
        self.lower_bound_ = float(bound)
        weights, means, prec_chol = e_step_params
        prec_chol = prec_chol / unit
        self.e_step_params_ = (weights, means * unit + centre,
                               np.linalg.inv(prec_chol @ np.swapaxes(prec_chol, 1, 2)), prec_chol)
        return self

    # -- input -------------------------------------------------------------------------------------------

    def _primitives(self, X, reset):
        """``X`` as Primitives: an array through scikit-learn's ``validate_data`` (its messages, first line, as
        InputError), then the library's checks. ``reset``: set ``n_features_in_`` (fit), else check against it."""
        if isinstance(X, Primitives) or (hasattr(X, "faces") and hasattr(X, "vertices")):
            prims = as_primitives(X)
            if reset:
                self.n_features_in_ = prims.dimension
                return prims
        else:
            try:
                X = validate_data(self, X, reset=reset, dtype=np.float64)
            except TypeError as exc:  # a sparse matrix
                raise InputTypeError(_one_line(exc)) from None
            except ValueError as exc:
                raise InputError(_one_line(exc)) from None
            return Primitives.from_points(X)
        expected = getattr(self, "n_features_in_", self.means_.shape[1])  # a model set up by hand may lack it
        if prims.dimension != expected:
            raise InputError(f"X has {prims.dimension} features, but {type(self).__name__} is expecting "
                             f"{expected} features as input")
        return prims

    # -- evaluation -------------------------------------------------------------------------------------

    def _check_fitted(self):
        try:
            check_is_fitted(self, _FITTED)
        except _SklearnNotFittedError as exc:
            raise NotFittedError(_one_line(exc)) from None

    def _checked(self, X):
        """``X`` as Primitives for a method of the fitted mixture (NotFittedError before ``fit``)."""
        self._check_fitted()
        return self._primitives(X, reset=False)

    def _full_parameters(self):
        """The fitted (weights, means, covariances, precision Choleskys), the last two as (K, d, d) matrices."""
        k, d = self.means_.shape
        return (self.weights_, self.means_, _full(self.covariances_, self.covariance_type, k, d),
                _full(self.precisions_cholesky_, self.covariance_type, k, d))

    def _log_rho_blocks(self, prims):
        """``log rho`` of the fitted mixture (textbook E-step), block by block over the primitives."""
        return EStep(*self._full_parameters()).log_rho_blocks(prims.means, prims.covariances)

    def _log_norm(self, prims):
        log_norm = EStep(*self._full_parameters()).log_normalisers(prims.means, prims.covariances)
        if not np.all(np.isfinite(log_norm)):
            raise InputError(f"{np.count_nonzero(~np.isfinite(log_norm))} of {len(log_norm)} primitives have a "
                             f"log-likelihood beyond float64 under this mixture: they lie too far from it")
        return log_norm

    def score_samples(self, X):
        """Log-likelihood of each point, shape (n_points,).

        ``X``: points (n_points, d), or ``Primitives.from_points`` of them, so that a set scored under many mixtures
        is checked and laid out once.
        """
        if hasattr(X, "faces") and hasattr(X, "vertices"):
            raise InputError("score_samples takes points, and this is a mesh: use primitive_bounds or "
                             "score_primitives")
        prims = self._checked(X)
        if np.any(prims.covariances):
            raise InputError("score_samples takes points, and these primitives have covariances: use "
                             "primitive_bounds or score_primitives")
        return self._log_norm(prims)

    def score(self, X, y=None):
        """Mean log-likelihood of the points (``X`` as in :meth:`score_samples`)."""
        return _finite_mean(self.score_samples(X))

    def primitive_bounds(self, X):
        """Per-primitive bound ``logsumexp_i(log lambda_i + E_p[log N_i])``, shape (n_prims,).

        For a point it is its log-likelihood; for a triangle, a lower bound of its mean log-likelihood.
        """
        return self._log_norm(self._checked(X))

    def score_primitives(self, X):
        """Size-weighted mean of :meth:`primitive_bounds`.

        For points it is the mean log-likelihood; for a mesh it is the triangle bound of eq. 11, a lower bound
        of the surface-averaged log-likelihood.
        """
        prims = self._checked(X)
        return _finite_mean(self._log_norm(prims), prims.weights)

    def predict(self, X):
        """Index of the most responsible component for each point or primitive."""
        prims = self._checked(X)
        return np.concatenate([block.argmax(axis=0) for block in self._log_rho_blocks(prims)])

    def predict_proba(self, X):
        """Responsibilities ``eta`` of each component for each point or primitive, shape (n, n_components)."""
        return responsibilities(self._checked(X), *self._full_parameters())

    def sample(self, n_samples=1):
        """Draw ``n_samples`` points; returns (X of shape (n_samples, d), component labels)."""
        self._check_fitted()
        if not _is_int(1)(n_samples):
            raise InputError(f"n_samples={n_samples!r}: must be an integer >= 1")
        rng = np.random.default_rng(self.random_state)
        labels = np.sort(rng.choice(self.n_components, size=n_samples, p=self.weights_))
        lower = np.linalg.cholesky(self._full_parameters()[2])
        noise = rng.standard_normal((n_samples, self.means_.shape[1]))
        return self.means_[labels] + np.einsum("nij,nj->ni", lower[labels], noise), labels
