"""
Visual odometry on the first frames of fr1/xyz
==============================================

The paper's visual odometry (§VI-D, Fig 7) on the first 15 depth frames of TUM's fr1/xyz (half a second of a
hand-held Kinect moving along its axes): every 4th pixel of each depth image becomes a rectangle primitive, a K=100
mixture is fitted to them and each frame's mixture is registered onto the previous one's with D2D, all under
``run_odometry``'s default per-frame schedule, ``overlap`` (its EM start, EM iterations and D2D rounds are printed
below from ``dgmm.odometry.SCHEDULES``; the paper does not state them, :doc:`/user_guide/odometry`). Point-to-point
ICP on 2,500 random points of each frame runs beside it. Both trajectories are scored against the ground truth (ATE
RMSE after a rigid alignment) and drawn top-down by the report's Fig 7 function. The workflow runs the same over all
798 frames.
"""

import inspect
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

import dgmm
from dgmm.odometry import (CAMERAS, SCHEDULES, absolute_trajectory_error, first_frames, read_sequence, run_odometry,
                           sequence_intrinsics)
from dgmm.odometry.figure import fig7

# The TUM sequence from the data mirror beside the repository.
root = Path(dgmm.__file__).resolve().parents[1]
folder = root / "../shared/data/tum/rgbd_dataset_freiburg1_xyz"
sequence = read_sequence(folder)
frames, groundtruth = first_frames(sequence, 15)
intrinsics = CAMERAS[sequence_intrinsics(folder.name)]  # fr1: the ROS default TUM recommends for its depth images
print(f"{len(sequence)} frames in {folder.name}; using {len(frames)}")
default = inspect.signature(run_odometry).parameters["schedule"].default
print(f"default schedule {default!r}: {SCHEDULES[default]}")

# %%
# One run per method, from the same seed (each frame's k-means start and ICP sample are drawn from it).
runs = {method: run_odometry(sequence, method, frames, intrinsics=intrinsics, seed=0)
        for method in ("gmm-pixels", "icp")}
for method, odometry in runs.items():
    ate = absolute_trajectory_error(odometry.trajectory, groundtruth)
    print(f"{method:10s} ATE RMSE {ate.rmse * 1000:.1f} mm, {odometry.cpu_seconds.mean():.2f} CPU s per frame")

# %%
# Fig 7 of the report for these frames. ``fig7`` returns a matplotlib ``Figure`` that is not tied to pyplot (the
# workflow draws it headless and saves it); here it is saved and shown.
figure = fig7({"fr1/xyz": (groundtruth, {"gmm-pixels-textbook": runs["gmm-pixels"].trajectory,
                                          "icp": runs["icp"].trajectory})})
png = Path(tempfile.mkdtemp()) / "fig7.png"
figure.savefig(png)
fig, ax = plt.subplots(figsize=(6, 5.5))
ax.imshow(plt.imread(png))
ax.set_axis_off()
fig.tight_layout()
