"""Rigid registration with fitted Gaussian mixtures, point-to-point ICP and CPD (paper §VI-A "Mesh Registration").

The public namespace; one concept per module:

- :mod:`~dgmm.registration.rotations`: quaternions, matrices, rotation vectors, Euler angles, distances;
- :mod:`~dgmm.registration.pose`: the :class:`Registration` result and the BFGS pose vector;
- :mod:`~dgmm.registration.protocol`: the authors' random trials and the errors of a registration;
- :mod:`~dgmm.registration.fitted`: a fitted mixture checked once, with its pose-independent caches;
- :mod:`~dgmm.registration.p2d` and :mod:`~dgmm.registration.d2d`: the two GMM costs and their registrations;
- :mod:`~dgmm.registration.coarse_to_fine`: P2D over a schedule of widened covariances (beyond the paper);
- :mod:`~dgmm.registration.solvers`: the paper's BFGS and a damped Gauss-Newton on the 6-dof pose;
- :mod:`~dgmm.registration.pointsets`: Kabsch and the authors' both-ways ICP;
- :mod:`~dgmm.registration.cpd`: rigid Coherent Point Drift, pycpd's algorithm operation for operation.

Conventions, shared by every function here:

- Points are rows: ``(n_points, 3)``.
- A rigid transform ``(R, t)`` maps ``x -> R x + t``; on rows, ``points @ R.T + t``.
- Quaternions are scalar-first, ``(w, x, y, z)``; the ones returned are unit with ``w >= 0``.
- Every method moves a **source** (points, or the moving mixture) onto a **target** (points, or the fixed
  mixture) and returns the transform that does so: ``result.apply(source)`` lies on the target.
- The optimisers rotate about a fixed centre ``c`` (the centroid of the source) so that rotation and translation
  are well decoupled: ``x -> R (x - c) + c + t'``. Results are converted back to the global ``(R, t)``.
"""
from dgmm.registration.coarse_to_fine import register_p2d_coarse_to_fine
from dgmm.registration.cpd import register_cpd
from dgmm.registration.d2d import register_d2d
from dgmm.registration.fitted import FittedMixture
from dgmm.registration.p2d import register_p2d
from dgmm.registration.pointsets import kabsch, register_icp
from dgmm.registration.pose import Registration
from dgmm.registration.protocol import BUNNY_DIAGONAL, RigidTrial, random_trials, registration_errors
from dgmm.registration.rotations import (euler_to_matrix, matrix_to_quaternion, matrix_to_rotvec, quaternion_to_matrix,
                                         rotation_distance_deg, rotvec_to_matrix)
from dgmm.registration.solvers import SOLVERS

__all__ = ["BUNNY_DIAGONAL", "FittedMixture", "Registration", "RigidTrial", "SOLVERS", "euler_to_matrix", "kabsch",
           "matrix_to_quaternion", "matrix_to_rotvec", "quaternion_to_matrix", "random_trials", "register_cpd",
           "register_d2d", "register_icp", "register_p2d", "register_p2d_coarse_to_fine", "registration_errors",
           "rotation_distance_deg", "rotvec_to_matrix"]
