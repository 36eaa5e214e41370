"""Rigid registration with fitted Gaussian mixtures, point-to-point ICP and CPD (paper §V "Mesh Registration").

Conventions, shared by every function in this module:

- Points are rows: ``(n_points, 3)``.
- A rigid transform ``(R, t)`` maps ``x -> R x + t``; on rows, ``points @ R.T + t``.
- Quaternions are scalar-first, ``(w, x, y, z)``; the ones returned are unit with ``w >= 0``.
- Every method moves a **source** (points, or the moving mixture) onto a **target** (points, or the fixed
  mixture) and returns the transform that does so: ``result.apply(source)`` lies on the target.
- The optimisers work on a 7-vector ``(t', q)``: a translation and an unnormalised quaternion, rotating about a
  fixed centre ``c`` (the centroid of the source) so that rotation and translation are well decoupled:
  ``x -> R(q / |q|) (x - c) + c + t'``. Results are converted back to the global ``(R, t)``.
- A mixture is any object with scikit-learn's fitted attributes ``weights_ (n_components,)``,
  ``means_ (n_components, 3)``, ``covariances_ (n_components, 3, 3)`` and ``precisions_cholesky_
  (n_components, 3, 3)`` (upper-triangular ``U`` with precision ``U Uᵀ``), e.g. ``dgmm.GaussianMixture`` or
  ``sklearn.mixture.GaussianMixture(covariance_type="full")``.

Random trials follow the authors' protocol (leonidk/direct_gmm): Euler angles uniform in ±15° per axis and a
translation uniform in ±0.05 per axis for the bunny (bounding-box diagonal 0.24077), scaled by the model's
diagonal; the trial rotates about a centre (the source centroid). Errors compare the estimate with the inverse
of the trial: the rotation error is the geodesic angle of ``R_est R_trial`` and the translation error is how far
the trial followed by the estimate moves the centre, in percent of the bounding-box diagonal.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from functools import partial

import numpy as np
from scipy.optimize import minimize
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from dgmm.errors import InputError

BUNNY_DIAGONAL = 0.24077
"""Bounding-box diagonal of the Stanford bunny, the unit of the authors' trial translations."""

_LOG_2PI = np.log(2.0 * np.pi)
_IDENTITY_PARAMS = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])

# How the pose gradient reaches scipy: analytic (cost and gradient in one call, ``jac=True``) or, as in the
# paper, left to BFGS's forward differences (``jac=None``).
_GRADIENT_MODES = {"analytic": True, "numeric": False}


# --------------------------------------------------------------------------------------------------- checks
def _as_array(name, array, shape):
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


def _as_points(name, points):
    """Return ``points`` as a finite float64 array of shape (n_points, 3) with n_points >= 1, or raise."""
    return _as_array(name, points, (None, 3))


@dataclass(frozen=True)
class _Mixture:
    """The fitted arrays of a Gaussian mixture, checked once.

    Attributes
    ----------
    weights : ndarray of shape (n_components,)
    means : ndarray of shape (n_components, 3)
    covariances : ndarray of shape (n_components, 3, 3)
    precisions_cholesky : ndarray of shape (n_components, 3, 3)
        Upper-triangular ``U`` with precision ``U Uᵀ`` (scikit-learn's convention).
    """

    weights: np.ndarray
    means: np.ndarray
    covariances: np.ndarray
    precisions_cholesky: np.ndarray

    @classmethod
    def from_fitted(cls, name, mixture):
        """Read and check the fitted attributes of ``mixture``, naming it ``name`` in errors."""
        arrays = {}
        for attribute, shape in (("weights_", (None,)), ("means_", (None, 3)),
                                 ("covariances_", (None, 3, 3)), ("precisions_cholesky_", (None, 3, 3))):
            if not hasattr(mixture, attribute):
                raise InputError(f"{name} has no fitted attribute {attribute} (fit it, with full covariances)")
            arrays[attribute] = _as_array(f"{name}.{attribute}", getattr(mixture, attribute), shape)
        n_components = len(arrays["weights_"])
        if any(len(values) != n_components for values in arrays.values()):
            raise InputError(f"{name} attributes disagree on n_components: "
                             + ", ".join(f"{key} {values.shape}" for key, values in arrays.items()))
        if np.any(arrays["weights_"] <= 0):
            raise InputError(f"{name}.weights_ must be positive")
        return cls(arrays["weights_"], arrays["means_"], arrays["covariances_"], arrays["precisions_cholesky_"])

    @property
    def centroid(self):
        """Weighted mean of the component means, shape (3,)."""
        return self.weights @ self.means / self.weights.sum()


# ---------------------------------------------------------------------------------------------- rotations
def quaternion_to_matrix(quaternions):
    """Rotation matrices of unit quaternions.

    Parameters
    ----------
    quaternions : array-like of shape (4,) or (n_rotations, 4)
        Scalar-first ``(w, x, y, z)``; normalised here, so any non-zero quaternion is accepted.

    Returns
    -------
    rotations : ndarray of shape (3, 3) or (n_rotations, 3, 3)
    """
    q = np.asarray(quaternions, dtype=np.float64)
    if q.shape[-1:] != (4,) or q.ndim > 2 or not np.all(np.isfinite(q)):
        raise InputError(f"quaternions must be finite with shape (4,) or (n, 4), got {q.shape}")
    norms = np.linalg.norm(q, axis=-1, keepdims=True)
    if np.any(norms == 0):
        raise InputError("quaternions must be non-zero")
    w, x, y, z = np.moveaxis(q / norms, -1, 0)
    rows = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    return np.moveaxis(np.array(rows), (0, 1), (-2, -1))


def matrix_to_quaternion(rotations):
    """Unit quaternions ``(w, x, y, z)`` with ``w >= 0`` of rotation matrices.

    Parameters
    ----------
    rotations : array-like of shape (3, 3) or (n_rotations, 3, 3)

    Returns
    -------
    quaternions : ndarray of shape (4,) or (n_rotations, 4)
    """
    return Rotation.from_matrix(_as_rotations("rotations", rotations)).as_quat(canonical=True, scalar_first=True)


def rotvec_to_matrix(rotvecs):
    """Rotation matrices of rotation vectors ``theta * axis`` (radians).

    Parameters
    ----------
    rotvecs : array-like of shape (3,) or (n_rotations, 3)

    Returns
    -------
    rotations : ndarray of shape (3, 3) or (n_rotations, 3, 3)
    """
    return Rotation.from_rotvec(_as_vectors("rotvecs", rotvecs)).as_matrix()


def matrix_to_rotvec(rotations):
    """Rotation vectors ``theta * axis`` (radians, ``theta`` in [0, pi]) of rotation matrices.

    Parameters
    ----------
    rotations : array-like of shape (3, 3) or (n_rotations, 3, 3)

    Returns
    -------
    rotvecs : ndarray of shape (3,) or (n_rotations, 3)
    """
    return Rotation.from_matrix(_as_rotations("rotations", rotations)).as_rotvec()


def euler_to_matrix(angles_deg):
    """Rotation ``Rz(c) Ry(b) Rx(a)`` of static-axis Euler angles ``(a, b, c)`` in degrees.

    This is transforms3d's default ``"sxyz"`` (scipy's ``"xyz"``), the convention of the authors' trials.

    Parameters
    ----------
    angles_deg : array-like of shape (3,) or (n_rotations, 3)

    Returns
    -------
    rotations : ndarray of shape (3, 3) or (n_rotations, 3, 3)
    """
    return Rotation.from_euler("xyz", _as_vectors("angles_deg", angles_deg), degrees=True).as_matrix()


def _as_vectors(name, vectors):
    """Return ``vectors`` as finite float64 of shape (3,) or (n, 3), or raise."""
    values = np.asarray(vectors, dtype=np.float64)
    if values.shape[-1:] != (3,) or values.ndim > 2 or not np.all(np.isfinite(values)):
        raise InputError(f"{name} must be finite with shape (3,) or (n, 3), got {values.shape}")
    return values


def _as_rotations(name, rotations):
    """Return ``rotations`` as finite float64 of shape (3, 3) or (n, 3, 3), or raise."""
    values = np.asarray(rotations, dtype=np.float64)
    if values.shape[-2:] != (3, 3) or values.ndim > 3 or not np.all(np.isfinite(values)):
        raise InputError(f"{name} must be finite with shape (3, 3) or (n, 3, 3), got {values.shape}")
    return values


def rotation_distance_deg(rotation_a, rotation_b):
    """Geodesic distance between rotations: the angle of ``R_aᵀ R_b``, in degrees.

    Parameters
    ----------
    rotation_a, rotation_b : array-like of shape (3, 3)

    Returns
    -------
    angle : float
        In [0, 180].
    """
    relative = _as_array("rotation_a", rotation_a, (3, 3)).T @ _as_array("rotation_b", rotation_b, (3, 3))
    return float(np.degrees(Rotation.from_matrix(relative).magnitude()))


def _rotation_and_jacobian(quaternion):
    """Rotation of a normalised quaternion and its derivative with respect to the unnormalised one.

    Parameters
    ----------
    quaternion : ndarray of shape (4,)
        ``(w, x, y, z)``, any non-zero length.

    Returns
    -------
    rotation : ndarray of shape (3, 3)
        ``R(q / |q|)``.
    jacobian : ndarray of shape (4, 3, 3)
        ``d R(q / |q|) / d q_j``: the derivative of ``R`` at the unit quaternion ``u``, chained through the
        normalisation ``d u / d q = (I - u uᵀ) / |q|``.
    """
    norm = np.linalg.norm(quaternion)
    if norm == 0:
        raise InputError("quaternion must be non-zero")
    u = quaternion / norm
    w, x, y, z = u
    unit_jacobian = 2.0 * np.array([
        [[0, -z, y], [z, 0, -x], [-y, x, 0]],
        [[0, y, z], [y, -2 * x, -w], [z, w, -2 * x]],
        [[-2 * y, x, w], [x, 0, z], [-w, z, -2 * y]],
        [[-2 * z, -w, x], [w, -2 * z, y], [x, y, 0]],
    ])
    projection = (np.eye(4) - np.outer(u, u)) / norm
    return quaternion_to_matrix(u), np.einsum("ij,jab->iab", projection, unit_jacobian)


# ------------------------------------------------------------------------------------------------ results
@dataclass(frozen=True)
class Registration:
    """A rigid transform ``x -> rotation @ x + translation`` that moves a source onto a target.

    Attributes
    ----------
    rotation : ndarray of shape (3, 3)
    translation : ndarray of shape (3,)
    iterations : int
        Optimiser iterations (BFGS), ICP or CPD iterations.
    seconds : float
        Wall-clock time of the registration.
    objective : float
        Final value of the method's minimised cost: negative mean log-likelihood (P2D), the determinant-free
        D2D cost, mean matching distance (ICP), pycpd's objective ``q`` (CPD).
    converged : bool
        Whether the method's own stopping test was met before its iteration cap.
    method : str
        ``"p2d"``, ``"d2d"``, ``"icp"`` or ``"cpd"``.
    """

    rotation: np.ndarray
    translation: np.ndarray
    iterations: int
    seconds: float
    objective: float
    converged: bool
    method: str

    @property
    def quaternion(self):
        """Unit quaternion ``(w, x, y, z)`` with ``w >= 0`` of ``rotation``, shape (4,)."""
        return matrix_to_quaternion(self.rotation)

    def apply(self, points):
        """Move ``points`` of shape (n_points, 3) by this transform; returns shape (n_points, 3)."""
        return _as_points("points", points) @ self.rotation.T + self.translation


def _pose_from_params(params, centre):
    """Global ``(R, t)`` of the optimiser's ``(t', q)`` rotating about ``centre`` (both shape (3,))."""
    rotation = quaternion_to_matrix(params[3:])
    return rotation, params[:3] + centre - rotation @ centre


def _params_from_pose(rotation, translation, centre):
    """The optimiser's 7-vector ``(t', q)`` of the global pose ``(R, t)`` rotating about ``centre``."""
    rotation = _as_array("initial rotation", rotation, (3, 3))
    translation = _as_array("initial translation", translation, (3,))
    return np.concatenate([translation - centre + rotation @ centre, matrix_to_quaternion(rotation)])


# ------------------------------------------------------------------------------------------------- trials
@dataclass(frozen=True)
class RigidTrial:
    """A rigid motion about a centre: ``x -> rotation @ (x - centre) + centre + translation``.

    Attributes
    ----------
    rotation : ndarray of shape (3, 3)
    translation : ndarray of shape (3,)
    centre : ndarray of shape (3,)
    """

    rotation: np.ndarray
    translation: np.ndarray
    centre: np.ndarray

    def apply(self, points):
        """Move ``points`` of shape (n_points, 3) by the trial; returns shape (n_points, 3)."""
        return (_as_points("points", points) - self.centre) @ self.rotation.T + self.centre + self.translation


def random_trials(n_trials, seed, diagonal, centre, max_angle_deg=15.0, max_translation=0.05):
    """Random rigid trials of the authors' registration experiment.

    Each trial draws three static-axis Euler angles (``euler_to_matrix``) uniformly in
    ``±max_angle_deg``, then a translation uniformly in ``±max_translation * diagonal / BUNNY_DIAGONAL`` per
    axis, from one ``np.random.default_rng(seed)``.

    Parameters
    ----------
    n_trials : int
    seed : int or numpy.random.Generator
    diagonal : float
        Bounding-box diagonal of the model; the bunny's 0.24077 gives the authors' ±0.05.
    centre : array-like of shape (3,)
        Centre of rotation, normally the centroid of the source points.
    max_angle_deg, max_translation : float

    Returns
    -------
    trials : list of RigidTrial
    """
    if not (np.isfinite(diagonal) and diagonal > 0):
        raise InputError(f"diagonal must be a positive number, got {diagonal}")
    if int(n_trials) < 0:
        raise InputError(f"n_trials must be non-negative, got {n_trials}")
    centre = _as_array("centre", centre, (3,))
    rng = np.random.default_rng(seed)
    half_width = max_translation * diagonal / BUNNY_DIAGONAL
    trials = []
    for _ in range(int(n_trials)):
        rotation = euler_to_matrix(rng.uniform(-max_angle_deg, max_angle_deg, size=3))
        trials.append(RigidTrial(rotation, rng.uniform(-half_width, half_width, size=3), centre))
    return trials


def registration_errors(result, trial, diagonal):
    """Errors of a registration that should undo a trial.

    Parameters
    ----------
    result : Registration
        Estimated transform from the trial-moved source back onto the model.
    trial : RigidTrial
    diagonal : float
        Bounding-box diagonal of the model.

    Returns
    -------
    rotation_deg : float
        Geodesic angle of ``R_est R_trial`` (zero when the estimate undoes the trial's rotation).
    translation_pct : float
        ``|T_est(T_trial(c)) - c|`` for the trial's centre ``c``, in percent of ``diagonal`` (the authors'
        ``|t_est - t_trial|`` when both rotate about ``c``).
    """
    if not (np.isfinite(diagonal) and diagonal > 0):
        raise InputError(f"diagonal must be a positive number, got {diagonal}")
    rotation_deg = rotation_distance_deg(result.rotation.T, trial.rotation)
    moved_centre = result.rotation @ (trial.centre + trial.translation) + result.translation
    return rotation_deg, float(100.0 * np.linalg.norm(moved_centre - trial.centre) / diagonal)


# --------------------------------------------------------------------------------------- BFGS on the pose
# BFGS sees translations in units of this many RMS radii of the moving points (or components). It makes the
# optimiser's path independent of the model's length units, and large enough a unit keeps BFGS's first steps mostly
# translational, as optimising the bunny in metres does (RMS radius 0.065 m): the trials' initial error is mostly
# translation, and large early rotation steps end in wrong basins (1 radius: 5 of 20 bunny trials fail).
_TRANSLATION_UNIT = 20.0


def _minimise_pose(method, cost, centre, length, x0, gradient, callback, options):
    """Minimise ``cost(params, with_grad)`` over ``(t', q)`` with BFGS; return a Registration.

    BFGS works on ``(t' / length, q)``: with ``length`` proportional to the spread of the moving points, both parts
    are dimensionless, so the optimiser takes the same path whatever the model's units (metres or millimetres).

    Parameters
    ----------
    method : str
        Name stored in the result.
    cost : callable
        ``cost(params, with_grad) -> value`` or ``(value, gradient (7,))`` when ``with_grad``.
    centre : ndarray of shape (3,)
        Centre of rotation of the parameterisation.
    length : float
        Unit of the translation the optimiser sees.
    x0 : ndarray of shape (7,)
    gradient : {"analytic", "numeric"}
    callback : callable or None
        ``callback(iteration, registration)`` after every BFGS iteration, ``registration`` the current pose.
    options : dict or None
        Passed to ``scipy.optimize.minimize(method="BFGS")``.
    """
    if gradient not in _GRADIENT_MODES:
        raise InputError(f"gradient must be one of {sorted(_GRADIENT_MODES)}, got {gradient!r}")
    analytic = _GRADIENT_MODES[gradient]
    start = time.perf_counter()
    unit = np.array([length if length > 0 else 1.0] * 3 + [1.0] * 4)

    def scaled_cost(x, with_grad):
        if not with_grad:
            return cost(x * unit, with_grad=False)
        value, grad = cost(x * unit, with_grad=True)
        return value, grad * unit

    def snapshot(params, value, iterations, converged):
        rotation, translation = _pose_from_params(params * unit, centre)
        return Registration(rotation, translation, iterations, time.perf_counter() - start, float(value),
                            converged, method)

    iteration = 0

    def report(intermediate_result):
        nonlocal iteration
        iteration += 1
        callback(iteration, snapshot(intermediate_result.x, intermediate_result.fun, iteration, False))

    result = minimize(partial(scaled_cost, with_grad=analytic), x0 / unit, method="BFGS", jac=True if analytic else None,
                      callback=None if callback is None else report, options=options)
    return snapshot(result.x, result.fun, int(result.nit), bool(result.success))


def _p2d_cost(params, points, centre, mixture, with_grad):
    """Negative mean log-likelihood of the moved points, and its gradient (paper eq. 1 summed over points).

    Parameters
    ----------
    params : ndarray of shape (7,)
        ``(t', q)``: the points move to ``R(q/|q|) (x - centre) + centre + t'``.
    points : ndarray of shape (n_points, 3)
    centre : ndarray of shape (3,)
    mixture : _Mixture
    with_grad : bool

    Returns
    -------
    cost : float
    gradient : ndarray of shape (7,), only when ``with_grad``
    """
    rotation, jacobian = _rotation_and_jacobian(params[3:])
    n_points, n_components = len(points), len(mixture.weights)
    local = points - centre
    moved = local @ rotation.T + centre + params[:3]
    # z_nk = Uₖᵀ (y_n − μ_k) for every point and component with one GEMM: U stacked as (3, n_components * 3).
    stacked = mixture.precisions_cholesky.transpose(1, 0, 2).reshape(3, 3 * n_components)
    offsets = np.einsum("kd,kde->ke", mixture.means, mixture.precisions_cholesky).reshape(-1)
    z = (moved @ stacked - offsets).reshape(n_points, n_components, 3)
    log_norm = (np.log(mixture.weights) - 1.5 * _LOG_2PI
                + np.log(np.diagonal(mixture.precisions_cholesky, axis1=1, axis2=2)).sum(axis=1))
    log_prob = log_norm - 0.5 * np.einsum("nke,nke->nk", z, z)
    top = log_prob.max(axis=1, keepdims=True)
    resp = np.exp(log_prob - top)
    total = resp.sum(axis=1, keepdims=True)
    cost = -float(np.mean(np.log(total) + top))
    if not with_grad:
        return cost
    resp /= total
    # d cost / d y_n = Σ_k r_nk Uₖ z_nk / n_points  (= Σ_k r_nk Σₖ⁻¹ (y_n − μ_k) / n_points)
    weighted = (resp[:, :, None] * z).reshape(n_points, -1)
    grad_moved = weighted @ stacked.T / n_points
    grad_rotation = grad_moved.T @ local
    grad_quaternion = np.einsum("ab,jab->j", grad_rotation, jacobian)
    return cost, np.concatenate([grad_moved.sum(axis=0), grad_quaternion])


def register_p2d(source, mixture, gradient="analytic", callback=None, options=None):
    """Point-to-distribution registration: maximise the mean log-likelihood of the moved source points.

    BFGS from the identity over a translation and a quaternion normalised inside the objective, rotating
    about the source centroid (paper §V).

    Parameters
    ----------
    source : array-like of shape (n_points, 3)
        Points to move into the mixture's frame.
    mixture : fitted Gaussian mixture
        See the module docstring for the attributes used.
    gradient : {"analytic", "numeric"}, default="analytic"
        ``"numeric"`` lets BFGS take forward differences, the paper's setup; it usually ends on scipy's
        "precision loss" stop (``converged=False``) near the same optimum.
    callback : callable, optional
        ``callback(iteration, registration)`` after each BFGS iteration with the current pose (for logging the
        moving points: ``registration.apply(source)``).
    options : dict, optional
        Extra options for ``scipy.optimize.minimize(method="BFGS")`` (``gtol``, ``maxiter``, ...).

    Returns
    -------
    Registration
        ``objective`` is the final negative mean log-likelihood.
    """
    points = _as_points("source", source)
    mix = _Mixture.from_fitted("mixture", mixture)
    centre = points.mean(axis=0)
    cost = partial(_p2d_cost, points=points, centre=centre, mixture=mix)
    length = _TRANSLATION_UNIT * np.sqrt(np.mean(np.sum((points - centre) ** 2, axis=1)))
    return _minimise_pose("p2d", cost, centre, length, _IDENTITY_PARAMS, gradient, callback, options)


def _d2d_cost(params, fixed, moving, centre, with_grad):
    """Determinant-free distribution-to-distribution cost and its gradient.

    ``f = -Σᵢⱼ πᵢ πⱼ exp(-½ yᵢⱼᵀ Sᵢⱼ⁻¹ yᵢⱼ)`` with ``Sᵢⱼ = Σᵢ + R Σⱼ Rᵀ`` and
    ``yᵢⱼ = μᵢ - (R (μⱼ - c) + c + t')``: component ``i`` of the fixed mixture, ``j`` of the moving one.

    Parameters
    ----------
    params : ndarray of shape (7,)
        ``(t', q)``.
    fixed, moving : _Mixture
    centre : ndarray of shape (3,)
    with_grad : bool

    Returns
    -------
    cost : float
    gradient : ndarray of shape (7,), only when ``with_grad``
    """
    rotation, jacobian = _rotation_and_jacobian(params[3:])
    local = moving.means - centre
    y = fixed.means[:, None, :] - (local @ rotation.T + centre + params[:3])[None, :, :]
    rotated_covariances = rotation @ moving.covariances @ rotation.T
    sums = fixed.covariances[:, None] + rotated_covariances[None]
    v = np.linalg.solve(sums, y[..., None])[..., 0]  # Sᵢⱼ⁻¹ yᵢⱼ, shape (n_fixed, n_moving, 3)
    terms = np.outer(fixed.weights, moving.weights) * np.exp(-0.5 * np.einsum("ijd,ijd->ij", y, v))
    cost = -float(terms.sum())
    if not with_grad:
        return cost
    weighted = terms[..., None] * v
    # Through y: df/dy = w v, dy/dt' = -I, dy/dR = -(· ⊗ local). Through S: df/dS = -½ w v vᵀ, dS/dR gives
    # df/dR = 2 (df/dS) R Σⱼ summed over pairs.
    outer_sums = np.einsum("ija,ijb->jab", weighted, v)
    grad_rotation = -np.einsum("ija,jb->ab", weighted, local) - np.einsum(
        "jab,bc,jcd->ad", outer_sums, rotation, moving.covariances)
    grad_quaternion = np.einsum("ab,jab->j", grad_rotation, jacobian)
    return cost, np.concatenate([-weighted.sum(axis=(0, 1)), grad_quaternion])


def register_d2d(fixed, moving, initial_rotation=None, initial_translation=None, gradient="analytic",
                 callback=None, options=None):
    """Distribution-to-distribution registration of two mixtures, determinant-free cost (paper §V, VO).

    Minimises ``-Σᵢⱼ πᵢ πⱼ exp(-½ yᵀ (Σᵢ + R Σⱼ Rᵀ)⁻¹ y)``, ``y = μᵢ - t - R μⱼ``, with BFGS over a translation
    and a quaternion normalised inside the objective, rotating about the moving mixture's weighted centroid.

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
    callback : callable, optional
        ``callback(iteration, registration)`` after each BFGS iteration.
    options : dict, optional
        Extra options for ``scipy.optimize.minimize(method="BFGS")``.

    Returns
    -------
    Registration
        ``objective`` is the final D2D cost.
    """
    fixed_mix = _Mixture.from_fitted("fixed", fixed)
    moving_mix = _Mixture.from_fitted("moving", moving)
    centre = moving_mix.centroid
    x0 = _params_from_pose(np.eye(3) if initial_rotation is None else initial_rotation,
                           np.zeros(3) if initial_translation is None else initial_translation, centre)
    cost = partial(_d2d_cost, fixed=fixed_mix, moving=moving_mix, centre=centre)
    length = _TRANSLATION_UNIT * np.sqrt(moving_mix.weights @ np.sum((moving_mix.means - centre) ** 2, axis=1))
    return _minimise_pose("d2d", cost, centre, length, x0, gradient, callback, options)


# ------------------------------------------------------------------------------------------ ICP and CPD
def kabsch(source, target, weights=None):
    """Least-squares rigid transform between corresponding points (Kabsch/Umeyama, no scale).

    Parameters
    ----------
    source, target : array-like of shape (n_points, 3)
        Row ``n`` of ``source`` corresponds to row ``n`` of ``target``.
    weights : array-like of shape (n_points,), optional
        Non-negative pair weights, not all zero; equal when omitted.

    Returns
    -------
    rotation : ndarray of shape (3, 3)
    translation : ndarray of shape (3,)
        Minimisers of ``Σ w_n |R s_n + t - t_n|²``.
    """
    source, target = _as_points("source", source), _as_points("target", target)
    if len(source) != len(target):
        raise InputError(f"source and target must have as many rows, got {len(source)} and {len(target)}")
    w = np.ones(len(source)) if weights is None else _as_array("weights", weights, (len(source),))
    if np.any(w < 0) or w.sum() <= 0:
        raise InputError("weights must be non-negative and not all zero")
    w = w / w.sum()
    source_mean, target_mean = w @ source, w @ target
    cross = (source - source_mean).T @ ((target - target_mean) * w[:, None])
    u, _, vt = np.linalg.svd(cross)
    rotation = vt.T @ np.diag([1.0, 1.0, np.sign(np.linalg.det(vt.T @ u.T))]) @ u.T
    return rotation, target_mean - rotation @ source_mean


def register_icp(source, target, max_iter=50_000, tol=1e-9, callback=None):
    """Point-to-point ICP with nearest neighbours both ways, as the authors ran it.

    Every iteration pools source→target and target→source nearest-neighbour pairs (the target→source pairs
    weighted ``n_source / n_target`` so both directions count equally), takes the closed-form Kabsch step on
    them, and stops when the weighted mean matching distance changes by less than ``tol``.

    Parameters
    ----------
    source : array-like of shape (n_source, 3)
        Points moved onto the target.
    target : array-like of shape (n_target, 3)
    max_iter : int, default=50000
    tol : float, default=1e-9
    callback : callable, optional
        ``callback(iteration, registration)`` after every step with the current pose.

    Returns
    -------
    Registration
        ``objective`` is the last mean matching distance (of the pose before the final step).
    """
    source, target = _as_points("source", source), _as_points("target", target)
    if int(max_iter) < 1 or not tol >= 0:
        raise InputError(f"max_iter must be >= 1 and tol >= 0, got {max_iter} and {tol}")
    start = time.perf_counter()
    target_tree = cKDTree(target)
    back_weight = len(source) / len(target)
    weights = np.concatenate([np.ones(len(source)), np.full(len(target), back_weight)])
    rotation, translation = np.eye(3), np.zeros(3)
    moved = source
    previous = np.inf
    converged = False
    iteration = 0
    while iteration < max_iter:
        forward_dist, forward_idx = target_tree.query(moved)
        back_dist, back_idx = cKDTree(moved).query(target)
        error = (forward_dist.sum() + back_weight * back_dist.sum()) / (2 * len(source))
        if abs(previous - error) < tol:
            converged = True
            break
        previous = error
        step_rotation, step_translation = kabsch(np.vstack([moved, moved[back_idx]]),
                                                 np.vstack([target[forward_idx], target]), weights)
        moved = moved @ step_rotation.T + step_translation
        rotation, translation = step_rotation @ rotation, step_rotation @ translation + step_translation
        iteration += 1
        if callback is not None:
            callback(iteration, Registration(rotation, translation, iteration, time.perf_counter() - start,
                                             float(error), False, "icp"))
    return Registration(rotation, translation, iteration, time.perf_counter() - start, float(error), converged,
                        "icp")


def register_cpd(source, target, max_iter=150, tol=1e-9, callback=None):
    """Rigid Coherent Point Drift through pycpd, moving ``source`` onto ``target``.

    pycpd's rigid model also fits a scale; like the authors, the rigid part is read back as the Kabsch fit of
    the source to pycpd's moved source.

    Parameters
    ----------
    source : array-like of shape (n_source, 3)
        pycpd's ``Y`` (the moving GMM centroids).
    target : array-like of shape (n_target, 3)
        pycpd's ``X``.
    max_iter : int, default=150
    tol : float, default=1e-9
    callback : callable, optional
        ``callback(iteration, registration)`` after every EM iteration with the current rigid part.

    Returns
    -------
    Registration
        ``objective`` is pycpd's final ``q``.
    """
    from pycpd import RigidRegistration

    source, target = _as_points("source", source), _as_points("target", target)
    if int(max_iter) < 1 or not tol >= 0:
        raise InputError(f"max_iter must be >= 1 and tol >= 0, got {max_iter} and {tol}")
    start = time.perf_counter()
    cpd = RigidRegistration(X=target, Y=source, max_iterations=max_iter, tolerance=tol)

    def report(iteration, error, X, Y):
        rotation, translation = kabsch(source, Y)
        callback(iteration, Registration(rotation, translation, iteration, time.perf_counter() - start,
                                         float(error), False, "cpd"))

    moved, _ = cpd.register(None if callback is None else report)
    rotation, translation = kabsch(source, moved)
    return Registration(rotation, translation, int(cpd.iteration), time.perf_counter() - start, float(cpd.q),
                        bool(cpd.diff <= tol), "cpd")
