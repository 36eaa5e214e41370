"""Frame-to-frame visual odometry with Gaussian mixtures on depth sequences (paper §VI-D "Visual Odometry"): TUM
RGB-D folders and ROS 2 recordings (MCAP).

The public namespace; one concept per module:

- :mod:`~dgmm.odometry.sequence`: the one interface both kinds of sequence are read through, opening either kind,
  and their ground truth at the frames;
- :mod:`~dgmm.odometry.tum`: TUM RGB-D files (depth PNGs, trajectories, sequences) and timestamp association;
- :mod:`~dgmm.odometry.ros2_mcap`: ROS 2 recordings in MCAP (depth images, camera info), read streaming and
  written (imported on its own: mcap);
- :mod:`~dgmm.odometry.depth_png`: fast decoding of TUM's 16-bit depth PNGs (ISA-L's inflate, PIL for the rest);
- :mod:`~dgmm.odometry.pixels`: camera intrinsics, back-projection and pixel-rectangle primitives;
- :mod:`~dgmm.odometry.pixel_covariance`: a pixel primitive's covariance, the flat patch or the authors' disparity box;
- :mod:`~dgmm.odometry.protocols`: ours or the authors' per-frame protocol (pixel sizes, covariance, schedule);
- :mod:`~dgmm.odometry.sklearn_em`: a frame's mixture fitted as scikit-learn's ``GaussianMixture`` at its defaults;
- :mod:`~dgmm.odometry.frame_model`: each method's per-frame model (a GMM, or ICP's points), the per-frame
  schedules of the GMMs (EM start, EM iterations, D2D solver) and the registration of two frames;
- :mod:`~dgmm.odometry.schedule_studies`: the experimental schedules the studies measured the sweep's against;
- :mod:`~dgmm.odometry.em_start`: a frame's EM start under a sampled schedule (k-means++ seeds, Lloyd iterations);
- :mod:`~dgmm.odometry.overlap`: D2D of two frames' mixtures on what both cameras see (robust to fast rotation);
- :mod:`~dgmm.odometry.measured_cut`: D2D of two frames on the primitives each measures of the other;
- :mod:`~dgmm.odometry.loop`: the odometry loop composing frame-to-frame registrations into a trajectory;
- :mod:`~dgmm.odometry.metrics`: ATE and RPE of TUM's benchmark;
- :mod:`~dgmm.odometry.synthetic`: a ray-cast TUM-format sequence of a room (imported on its own: trimesh);
- :mod:`~dgmm.odometry.figure`: Fig 7, the top-down trajectories (imported on its own: matplotlib).

Conventions: poses map camera to world, ``x_w = R x_c + t``; a trajectory holds one row per frame; pixels are
``(u, v)`` = (column, row) of an optical camera frame (x right, y down, z forward); depth in metres, 0 = none.
"""
from dgmm.odometry.frame_model import METHODS, MIXTURE_METHODS, SCHEDULES, UNSIZED_METHODS, Schedule, odometry_runs
from dgmm.odometry.loop import Odometry, OdometryFrame, frame_seconds, run_odometry, seconds_summary
from dgmm.odometry.metrics import absolute_trajectory_error, drift_metrics, frame_motions, relative_pose_error
from dgmm.odometry.pixels import (CAMERAS, Intrinsics, backproject, parse_intrinsics, pixel_primitives,
                                  sequence_intrinsics)
from dgmm.odometry.sequence import DepthSequence, first_frames, groundtruth_at_frames, open_sequence
from dgmm.odometry.tum import Trajectory, TumSequence, read_sequence, read_trajectory, write_trajectory

__all__ = ["CAMERAS", "METHODS", "MIXTURE_METHODS", "SCHEDULES", "UNSIZED_METHODS", "DepthSequence", "Intrinsics",
           "Odometry", "OdometryFrame", "Schedule", "Trajectory", "TumSequence", "absolute_trajectory_error",
           "backproject", "drift_metrics", "first_frames", "frame_motions", "frame_seconds", "groundtruth_at_frames",
           "odometry_runs", "open_sequence", "parse_intrinsics", "pixel_primitives", "read_sequence",
           "read_trajectory", "relative_pose_error", "run_odometry", "seconds_summary", "sequence_intrinsics",
           "write_trajectory"]
