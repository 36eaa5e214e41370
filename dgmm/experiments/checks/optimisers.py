"""P2D with the optimisers and rotation parameters the paper tried (§VI-A, "Mesh Registration").

The paper: "we tried both Conjugate Gradients and BFGS ..., which produced similar results and we report the BFGS
results as it ran faster", and "our experiments using the rotation vector ... produced nearly identical results"
to the quaternion. Here each (optimiser, rotation) runs scipy's minimiser from the identity with forward-difference
gradients (the paper's setup) on the P2D cost of :mod:`dgmm.registration.p2d`, with the translation scaled as
:func:`dgmm.registration.solvers.minimise_bfgs` scales it.
"""
import time

import numpy as np
from scipy.optimize import minimize

from dgmm.registration.fitted import FittedMixture
from dgmm.registration.p2d import p2d_cost
from dgmm.registration.pose import IDENTITY_PARAMS, Registration, pose_from_params
from dgmm.registration.protocol import registration_errors
from dgmm.registration.solvers import TRANSLATION_UNIT


def _quaternion_params(x):
    return x


def _rotvec_params(x):
    """``(t', v)`` with ``v`` a rotation vector -> ``(t', q)``, ``q`` its scalar-first unit quaternion."""
    angle = np.linalg.norm(x[3:])
    return np.concatenate([x[:3], [np.cos(angle / 2)], 0.5 * np.sinc(angle / (2 * np.pi)) * x[3:]])


ROTATIONS = {"quaternion": (_quaternion_params, IDENTITY_PARAMS), "rotvec": (_rotvec_params, np.zeros(6))}
"""Rotation parameters: name -> (``x -> (t', q)``, the identity's ``x``)."""
SETTINGS = (("BFGS", "quaternion"), ("CG", "rotvec"), ("CG", "quaternion"), ("BFGS", "rotvec"))
"""(optimiser, rotation) pairs run; the paper's is ``("BFGS", "quaternion")``."""
COLUMNS = ("optimiser", "rotation", "trial", "rotation_error_deg", "translation_error_pct", "iterations",
           "evaluations")


def register(points, mixture, optimiser, rotation):
    """P2D registration of ``points`` (n_points, 3) to a fitted mixture from the identity.

    Returns
    -------
    registration : Registration
    evaluations : int
        Cost evaluations (forward differences included).
    """
    to_params, x0 = ROTATIONS[rotation]
    mix = FittedMixture.from_fitted("mixture", mixture)
    centre = points.mean(axis=0)
    length = TRANSLATION_UNIT * np.sqrt(np.mean(np.sum((points - centre) ** 2, axis=1)))
    unit = np.concatenate([[length] * 3, np.ones(len(x0) - 3)])

    def cost(x):
        return p2d_cost(to_params(x * unit), points, centre, mix, with_grad=False)

    result = minimize(cost, x0 / unit, method=optimiser)
    rotation_matrix, translation = pose_from_params(to_params(result.x * unit), centre)
    return (Registration(rotation_matrix, translation, int(result.nit), 0.0, float(result.fun), bool(result.success),
                         "p2d"), int(result.nfev))


def optimiser_rows(setups, mixture, diagonal):
    """Every trial of ``setups`` (:func:`dgmm.experiments.trials.make_trials`) registered under every :data:`SETTINGS`.

    Returns
    -------
    rows : list of dict
        Errors, iterations and cost evaluations, with the keys of :data:`COLUMNS` (deterministic).
    seconds : list of dict
        ``optimiser``, ``rotation``, ``trial`` and the registration's CPU ``seconds`` (machine dependent).
    """
    rows, seconds = [], []
    for setup in setups:
        for optimiser, rotation in SETTINGS:  # interleaved, so that a change of machine load hits every setting
            start = time.process_time()
            result, evaluations = register(setup.moved, mixture, optimiser, rotation)
            elapsed = time.process_time() - start
            rotation_error, translation_error = registration_errors(result, setup.trial, diagonal)
            key = {"optimiser": optimiser, "rotation": rotation, "trial": setup.index}
            rows.append({**key, "rotation_error_deg": rotation_error, "translation_error_pct": translation_error,
                         "iterations": result.iterations, "evaluations": evaluations})
            seconds.append({**key, "seconds": elapsed})
    return rows, seconds
