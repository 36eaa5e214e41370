"""Distribution-to-distribution (D2D) registration of two mixtures, the determinant-free cost (paper §VI-D, odometry).

``f = -Σᵢⱼ πᵢ πⱼ exp(-½ yᵢⱼᵀ Sᵢⱼ⁻¹ yᵢⱼ)`` with ``Sᵢⱼ = Σᵢ + R Σⱼ Rᵀ`` and ``yᵢⱼ = μᵢ - (R (μⱼ - c) + c + t')``:
component ``i`` of the fixed mixture, ``j`` of the moving one. The cost is one pass over every pair at once (the
symmetric ``Sᵢⱼ`` as its 6 distinct entries, each an ``(n_fixed, n_moving)`` array, inverted by its adjugate).
The derivatives are a second pass over only the pairs whose term is within ``e^-50`` of the largest (mixtures of a
surface overlap little: a fifth of the pairs or fewer), each pair a row of ``(n_pairs, ...)`` arrays.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, partial

import numpy as np

from dgmm.gaussian import SCREEN, layout, quadratic_features, unpack
from dgmm.registration.fitted import EXP_FLOOR, FittedMixture
from dgmm.registration.pose import params_from_pose, pivot_pose
from dgmm.registration.rotations import LEVI_CIVITA, rotation_and_jacobian
from dgmm.registration.solvers import (TRANSLATION_UNIT, check_solver, compiled_gauss_newton, minimise_bfgs,
                                       minimise_gauss_newton, pose_matrices)

_ROWS, _COLS = layout(3).rows, layout(3).cols  # the 6 distinct entries of a symmetric 3x3
_SKEW = -np.transpose(LEVI_CIVITA, (2, 0, 1)).reshape(3, 9)
"""``a @ _SKEW`` is the cross-product matrix ``[a]x`` (``[a]x b = a x b``) of each row of ``a``, flattened to 9."""


@dataclass(frozen=True)
class PairTables:
    """What the D2D cost needs of two mixtures and the centre of rotation, computed once per registration.

    Attributes
    ----------
    fixed : FittedMixture
    fixed_means : ndarray of shape (3, n_fixed)
        Transposed, for gathering the pairs' columns.
    fixed_covariances : ndarray of shape (6, n_fixed)
        The 6 distinct entries of each ``Σᵢ``.
    offsets : ndarray of shape (n_moving, 3)
        ``μⱼ - c``.
    moving_covariances : ndarray of shape (n_moving, 3, 3)
    log_weights : ndarray of shape (n_fixed, n_moving)
        ``log πᵢ + log πⱼ``.
    centre : ndarray of shape (3,)

    The screen's bounds (:meth:`candidates`, the numpy cost's) read the eigen-decompositions, computed on first use:
    the compiled cost screens by the terms themselves and never needs them (:attr:`inverse_widths`,
    :attr:`normals`, :attr:`normal_outer`, :attr:`thickness`).
    """

    fixed: FittedMixture
    fixed_means: np.ndarray
    fixed_covariances: np.ndarray
    offsets: np.ndarray
    moving_covariances: np.ndarray
    log_weights: np.ndarray
    centre: np.ndarray

    @classmethod
    def of(cls, fixed, moving, centre):
        """The tables of two :class:`FittedMixture` and the centre of rotation ``c`` (3,)."""
        return cls(fixed=fixed, fixed_means=fixed.means.T.copy(),
                   fixed_covariances=fixed.covariances[:, _ROWS, _COLS].T.copy(), offsets=moving.means - centre,
                   moving_covariances=moving.covariances,
                   log_weights=np.log(fixed.weights)[:, None] + np.log(moving.weights)[None, :], centre=centre)

    @cached_property
    def _fixed_eigen(self):
        """Eigenvalues (ascending) and eigenvectors of every ``Σᵢ``."""
        return np.linalg.eigh(self.fixed.covariances)

    @cached_property
    def inverse_widths(self):
        """``1 / (λmax(Σᵢ) + λmax(Σⱼ))``, shape (n_fixed, n_moving)."""
        moving_widths = np.linalg.eigvalsh(self.moving_covariances)[:, 2]
        return 1.0 / (self._fixed_eigen[0][:, 2:] + moving_widths[None, :])

    @cached_property
    def normals(self):
        """Eigenvector ``nᵢ`` of the smallest eigenvalue of each ``Σᵢ``, shape (n_fixed, 3)."""
        return self._fixed_eigen[1][:, :, 0]

    @cached_property
    def normal_outer(self):
        """The 6 distinct entries of ``nᵢ nᵢᵀ``, the off-diagonal ones doubled, shape (n_fixed, 6):
        ``normal_outer @ C6`` is ``nᵀ C n``."""
        return quadratic_features(self.normals)[:, :6]

    @cached_property
    def thickness(self):
        """The smallest eigenvalue of each ``Σᵢ``, shape (n_fixed,)."""
        return self._fixed_eigen[0][:, 0]

    def candidates(self, moved, rotated_covariances):
        """Indices ``(i, j)`` of the pairs whose term may be within ``e^-SCREEN`` of the largest.

        Rigorous bounds, no exponent computed: ``S ≥ Σᵢ`` gives ``yᵀ S⁻¹ y ≤ yᵀ Σᵢ⁻¹ y`` (a lower bound of the largest
        term, every pair's at once from one product of P2D's :func:`quadratic_features` table); an upper bound of
        each term comes from ``yᵀ S⁻¹ y ≥ (uᵀ y)² / (uᵀ S u)`` for unit ``u``: ``|y|² / (λmax(Σᵢ) + λmax(Σⱼ))``
        along ``y`` and ``(nᵢᵀ y)² / (λmin(Σᵢ) + nᵢᵀ C nᵢ)`` along the normal of a flat ``Σᵢ``.
        """
        fixed = self.fixed
        floor = (quadratic_features(moved - fixed.origin) @ fixed.log_density_table
                 - fixed.log_normalisers + self.log_weights.T).max()
        squared = np.sum(fixed.means ** 2, axis=1)[:, None] + np.sum(moved ** 2, axis=1)[None, :]
        squared -= 2.0 * fixed.means @ moved.T
        squared *= self.inverse_widths
        along = np.sum(self.normals * fixed.means, axis=1)[:, None] - self.normals @ moved.T
        along *= along
        along /= self.thickness[:, None] + self.normal_outer @ rotated_covariances[:, _ROWS, _COLS].T
        bound = np.maximum(squared, along, out=squared)
        bound *= -0.5
        bound += self.log_weights
        return np.divmod(np.flatnonzero(bound >= floor - SCREEN), bound.shape[1])


@dataclass(frozen=True)
class _Pairs:
    """The candidate pairs at one pose: their indices, ``log_terms`` ``log πᵢ πⱼ - ½ yᵀ S⁻¹ y``, the adjugates
    (6, n_pairs) and determinants of ``S``, ``adj(S) y`` (3, n_pairs); ``R (μⱼ - c)`` and ``R Σⱼ Rᵀ`` per moving
    component."""

    cost: float
    moving_index: np.ndarray
    log_terms: np.ndarray
    adjugates: np.ndarray
    determinants: np.ndarray
    adjugate_y: np.ndarray
    rotated: np.ndarray
    rotated_covariances: np.ndarray


def _pairs(rotation, translation, tables):
    """The D2D cost at the pose ``(R, t')`` with the terms of the pairs that are not negligible."""
    rotated = tables.offsets @ rotation.T
    moved = rotated + tables.centre + translation
    rotated_covariances = rotation @ tables.moving_covariances @ rotation.T
    fixed_index, moving_index = tables.candidates(moved, rotated_covariances)
    y = np.take(tables.fixed_means, fixed_index, axis=1) - np.take(moved.T, moving_index, axis=1)
    a, b, c, d, e, f = (np.take(tables.fixed_covariances, fixed_index, axis=1)
                        + np.take(rotated_covariances[:, _ROWS, _COLS].T, moving_index, axis=1))
    adjugates = np.array([b * c - f * f, a * c - e * e, a * b - d * d, e * f - d * c, d * f - b * e, d * e - a * f])
    determinants = a * adjugates[0] + d * adjugates[3] + e * adjugates[4]
    (yx, yy, yz), (axx, ayy, azz, axy, axz, ayz) = y, adjugates
    adjugate_y = np.array([axx * yx + axy * yy + axz * yz, axy * yx + ayy * yy + ayz * yz,
                           axz * yx + ayz * yy + azz * yz])
    log_terms = yx * adjugate_y[0]
    log_terms += yy * adjugate_y[1]
    log_terms += yz * adjugate_y[2]
    log_terms /= determinants
    log_terms *= -0.5
    log_terms += np.take(tables.log_weights, fixed_index * len(moved) + moving_index)
    np.maximum(log_terms, EXP_FLOOR, out=log_terms)
    cost = -float(np.exp(log_terms).sum())
    return _Pairs(cost, moving_index, log_terms, adjugates, determinants, adjugate_y, rotated, rotated_covariances)


def _derivatives(pairs, hessians):
    """Gradient of the D2D cost over ``(δ, ω)`` (translation ``t' + δ``, left rotation ``exp([ω]x) R``), and with
    ``hessians`` its Gauss-Newton matrix and exact Hessian (6, 6), from the pairs that are not negligible.

    Per pair, with ``v = S⁻¹ y``, ``p = R (μⱼ - c)``, ``C = R Σⱼ Rᵀ`` and the exponent ``E = -½ yᵀ S⁻¹ y``:
    ``dy = -δ + [p]x ω``, ``dS/dω_a = [e_a]x C - C [e_a]x``, so ``∇E = (v, (p + C v) x v)``, and

    ``∇²E = -Jᵀ S⁻¹ J + (sym(v (p + Cv)ᵀ) - v·(p + Cv) I + [v]xᵀ C [v]x - Uᵀ S⁻¹ U)_ωω + (sym part of 2 Uᵀ S⁻¹ J)``

    with ``J = [-I, [p]x]`` and ``U = C [v]x - [C v]x`` (the columns ``dS/dω_a v``). The cost ``-Σ exp(E)`` has
    Hessian ``-Σ exp(E) (∇E ∇Eᵀ + ∇²E)``; its Gauss-Newton matrix keeps only ``Σ exp(E) Jᵀ S⁻¹ J`` (positive
    semi-definite).
    """
    keep = np.flatnonzero(pairs.log_terms >= pairs.log_terms.max() - SCREEN)
    terms = np.exp(pairs.log_terms[keep])
    determinants = pairs.determinants[keep]
    v = (pairs.adjugate_y[:, keep] / determinants).T
    moving_index = pairs.moving_index[keep]
    p, c = pairs.rotated[moving_index], pairs.rotated_covariances[moving_index]
    cv = np.einsum("nab,nb->na", c, v)
    grad_log = np.concatenate([v, np.cross(p + cv, v)], axis=1)  # ∇E, (n_pairs, 6)
    gradient = -(terms @ grad_log)
    if not hessians:
        return gradient
    inverse = unpack((pairs.adjugates[:, keep] / determinants).T)  # S⁻¹, (n_pairs, 3, 3)
    (gauss_newton,) = pose_matrices(p, terms[:, None, None] * inverse)
    skew_v = (v @ _SKEW).reshape(-1, 3, 3)
    c_skew_v = c @ skew_v
    u = c_skew_v - (cv @ _SKEW).reshape(-1, 3, 3)
    inverse_u = inverse @ u
    # Σ_n terms_n X_nᵀ Y_n for stacks of 3x3 matrices, as one product over the rows (n, k) of X_nkа and Y_nkb.
    weighted_rows = np.repeat(terms, 3)[:, None]

    def weighted_sum(x, y):
        return (weighted_rows * x.reshape(-1, 3)).T @ y.reshape(-1, 3)

    mixed = weighted_sum(inverse_u, (p @ _SKEW).reshape(-1, 3, 3))
    spin = (terms[:, None] * v).T @ (p + cv)
    second = np.zeros((6, 6))  # Σ exp(E) times ∇²E's parts beyond -Jᵀ S⁻¹ J
    second[3:, 3:] = (weighted_sum(skew_v, c_skew_v) - weighted_sum(u, inverse_u) + mixed + mixed.T
                      + 0.5 * (spin + spin.T) - np.trace(spin) * np.eye(3))
    second[3:, :3] = -(terms @ inverse_u.reshape(-1, 9)).reshape(3, 3).T
    second[:3, 3:] = second[3:, :3].T
    exact = gauss_newton - grad_log.T @ (terms[:, None] * grad_log) - second
    return gradient, gauss_newton, exact


def d2d_cost(params, tables, with_grad):
    """D2D cost of the BFGS pose vector, and its gradient.

    Parameters
    ----------
    params : ndarray of shape (7,)
        ``(t', q)``.
    tables : PairTables
    with_grad : bool

    Returns
    -------
    cost : float
    gradient : ndarray of shape (7,), only when ``with_grad``
    """
    rotation, jacobian = rotation_and_jacobian(params[3:])
    pairs = _pairs(rotation, params[:3], tables)
    if not with_grad:
        return pairs.cost
    gradient = _derivatives(pairs, hessians=False)
    # dR/dq_k = [ω_k]x R (R stays a rotation), and <½ [g]x R, [ω]x R> = g·ω: the quaternion gradient of ω's g.
    grad_rotation = 0.5 * (gradient[3:] @ _SKEW).reshape(3, 3) @ rotation
    return pairs.cost, np.concatenate([gradient[:3], np.einsum("ab,jab->j", grad_rotation, jacobian)])


def d2d_pose_cost(tables, compiled=True):
    """The D2D cost as :func:`~dgmm.registration.solvers.minimise_gauss_newton` evaluates it.

    Parameters
    ----------
    tables : PairTables
    compiled : bool, default=True
        The numba kernels of :mod:`~dgmm.compiled.registration`, or the numpy functions above (the reference
        in tests).

    Returns
    -------
    evaluate : callable
        ``evaluate(rotation, translation) -> (cost, derivatives)``; ``derivatives() -> (gradient (6,),
        gauss_newton (6, 6), exact Hessian (6, 6))`` (see :func:`_derivatives`).
    """
    if compiled:
        return _compiled_pose_cost(tables)

    def evaluate(rotation, translation):
        pairs = _pairs(rotation, translation, tables)
        return pairs.cost, partial(_derivatives, pairs, hessians=True)

    return evaluate


def _compiled_pose_cost(tables):
    """:func:`d2d_pose_cost` with the numba kernels."""
    from dgmm.compiled import registration as kernels  # numba loads only where Gauss-Newton D2D runs

    fixed_means, fixed_covariances = tables.fixed.means, tables.fixed.covariances
    shape = (len(fixed_means), len(tables.offsets))

    def evaluate(rotation, translation):
        rotated = tables.offsets @ rotation.T
        moved = rotated + tables.centre + translation
        moved_covariances = rotation @ tables.moving_covariances @ rotation.T
        pairs = kernels.d2d_kept_pairs(*shape)
        cost = kernels.d2d_negative_overlap(fixed_means, fixed_covariances, moved, moved_covariances,
                                            tables.log_weights, SCREEN, EXP_FLOOR, *pairs)
        return cost, partial(kernels.d2d_pose_derivatives, fixed_means, fixed_covariances, moved, rotated,
                             moved_covariances, *pairs)

    return evaluate


def _compiled_loop(tables):
    """:func:`dgmm.compiled.registration.d2d_gauss_newton` with the tables' arrays bound (the ``solve`` of
    :func:`~dgmm.registration.solvers.compiled_gauss_newton`)."""
    from dgmm.compiled import registration as kernels  # numba loads only where Gauss-Newton D2D runs

    return partial(kernels.d2d_gauss_newton, tables.fixed.means, tables.fixed.covariances, tables.offsets,
                   tables.moving_covariances, tables.centre, tables.log_weights, SCREEN, EXP_FLOOR)


def register_d2d(fixed, moving, initial_rotation=None, initial_translation=None, gradient="analytic",
                 callback=None, options=None, solver="bfgs", compiled=True):
    """Distribution-to-distribution registration of two mixtures, determinant-free cost (paper §VI-D, visual odometry).

    Minimises ``-Σᵢⱼ πᵢ πⱼ exp(-½ yᵀ (Σᵢ + R Σⱼ Rᵀ)⁻¹ y)``, ``y = μᵢ - t - R μⱼ``, rotating about the moving
    mixture's weighted centroid.

    Parameters
    ----------
    fixed : fitted Gaussian mixture
        The target (components ``i``).
    moving : fitted Gaussian mixture
        The source (components ``j``), moved by the returned transform.
    initial_rotation : array-like of shape (3, 3), optional
        Initial pose; the identity when omitted.
    initial_translation : array-like of shape (3,), optional
    gradient : {"analytic", "numeric"}, default="analytic"
        BFGS only.
    callback : callable, optional
        ``callback(iteration, registration)`` after each iteration.
    options : dict, optional
        Options of the solver (see :func:`dgmm.registration.register_p2d`).
    solver : {"bfgs", "gauss-newton"}, default="bfgs"
        The paper's BFGS, or damped Newton steps on 6 dof with the exact Hessian (Gauss-Newton where it is not
        positive definite): the same optimum, several times faster.
    compiled : bool, default=True
        Gauss-Newton only: the whole loop compiled (:func:`dgmm.compiled.registration.d2d_gauss_newton`), or
        :func:`~dgmm.registration.solvers.minimise_gauss_newton` on the numpy cost (the reference in tests).

    Returns
    -------
    Registration
        ``objective`` is the final D2D cost.
    """
    check_solver(solver, gradient)
    fixed_mix = FittedMixture.from_fitted("fixed", fixed)
    moving_mix = FittedMixture.from_fitted("moving", moving)
    centre = moving_mix.centroid
    tables = PairTables.of(fixed_mix, moving_mix, centre)
    rotation = np.eye(3) if initial_rotation is None else initial_rotation
    translation = np.zeros(3) if initial_translation is None else initial_translation
    radius = np.sqrt(moving_mix.weights @ np.sum((moving_mix.means - centre) ** 2, axis=1))
    if solver == "gauss-newton":  # on the pose itself: no quaternion
        start = pivot_pose(rotation, translation, centre)
        if compiled:
            return compiled_gauss_newton("d2d", _compiled_loop(tables), centre, radius, *start, callback, options)
        return minimise_gauss_newton("d2d", d2d_pose_cost(tables, compiled=False), centre, radius, *start, callback,
                                     options)
    x0 = params_from_pose(rotation, translation, centre)
    return minimise_bfgs("d2d", partial(d2d_cost, tables=tables), centre, TRANSLATION_UNIT * radius, x0, gradient,
                         callback, options)
