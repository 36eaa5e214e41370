"""Same-run CPU-time ratios for the paper's speed claims that no sweep table times, by interleaved repeats.

Every check times two or more settings on the same cases, each repeat running every setting back to back in an
order that alternates from repeat to repeat (:mod:`~dgmm.experiments.checks.interleaved`), so that a claim's ratio
comes as one paired sample per repeat: its median and an interval from the order statistics. Times are CPU seconds
of one thread (``time.process_time``); only their ratios within one run mean anything.

:data:`TIMING_CHECKS` names the checks as ``config.yaml``'s ``checks.timing`` does; a check's ``check`` column is
its name with spaces for underscores:

- :mod:`~.timing_meshes`: ``approximation`` (exact, approx, centroids EM), ``decimation`` (clustering, quadric),
  ``sampling`` (random, poisson);
- :mod:`~.timing_registration`: ``d2d_determinant`` (determinant-free, with determinant), ``cpd_vs_p2d`` (cpd,
  cpd dgmm, p2d, p2d numerical);
- :mod:`~.timing_odometry`: ``d2d_primitives`` (pixels, points, pixels bfgs, points bfgs), ``odometry_frame``
  (gmm-pixels, icp).
"""
from dgmm.experiments.checks.timing_meshes import approximation_times, decimation_times, sampling_times
from dgmm.experiments.checks.timing_odometry import d2d_primitives_times, odometry_frame_times
from dgmm.experiments.checks.timing_registration import cpd_p2d_times, d2d_determinant_times

TIMING_CHECKS = {
    "approximation": approximation_times,
    "decimation": decimation_times,
    "sampling": sampling_times,
    "d2d_determinant": d2d_determinant_times,
    "cpd_vs_p2d": cpd_p2d_times,
    "d2d_primitives": d2d_primitives_times,
    "odometry_frame": odometry_frame_times,
}
"""Check name -> ``function(**inputs, repeats=..., **settings) -> rows`` (``dgmm.experiments.checks.interleaved``'s
columns); the inputs and settings each takes are in its docstring."""
