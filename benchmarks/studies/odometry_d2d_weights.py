"""fr1/xyz odometry under the sweep's schedule with D2D's component weights divided by each component's depth.

A study, not a schedule: the paper's D2D weighs component pairs by the mixtures' weights ``πᵢ πⱼ``. Textbook EM's
weights are footprint areas (a pixel at depth Z covers ∝ Z²), so the far surfaces, the noisiest (Kinect's depth
noise grows as Z²), weigh most; the authors' EM counts every pixel once. Here every mixture handed to D2D (the
overlap round's and the cut rounds', through the two call sites in ``dgmm.odometry.overlap`` and
``dgmm.odometry.measured_cut``) has its weights multiplied by ``Z^-POWER`` (``Z`` the depth of the component's mean)
and renormalised: POWER 1 with textbook EM and -1 with the authors' EM both weigh a component by its pixel count ×
its depth. Prints one row per (EM, seed): ATE, one-second RPE, CPU seconds per frame and the worst frame-to-frame
error against the ground truth; one thread. Any TUM folder: the rotation-only room of
``benchmarks/studies/odometry_rotation_room.py`` (written under results/benchmarks) with ``--intrinsics fr3``.

Usage: ``python benchmarks/studies/odometry_d2d_weights.py [SEQUENCE_DIR] [--power textbook=1 authors=-1] [--seeds 0 1]
[--intrinsics CAMERA]``.
"""
import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

import dgmm.odometry.measured_cut as measured_cut  # noqa: E402
import dgmm.odometry.overlap as overlap  # noqa: E402
from dgmm.odometry import (CAMERAS, absolute_trajectory_error, first_frames, read_sequence,  # noqa: E402
                           relative_pose_error, run_odometry, sequence_intrinsics)

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/: odometry_peers
from odometry_peers import FR1_XYZ  # noqa: E402
from odometry_schedules import frame_errors  # noqa: E402


class DepthWeighted:
    """A fitted mixture's arrays with its weights multiplied by the depth of each mean to the ``-power``."""

    def __init__(self, mixture, power):
        weights = np.asarray(mixture.weights_) * np.asarray(mixture.means_)[:, 2] ** -power
        self.weights_ = weights / weights.sum()
        self.means_, self.covariances_ = mixture.means_, mixture.covariances_
        self.precisions_cholesky_ = mixture.precisions_cholesky_


def depth_weighted(register_d2d, power):
    """``register_d2d`` on both mixtures depth-weighted."""
    def register(fixed, moving, *args, **kwargs):
        return register_d2d(DepthWeighted(fixed, power), DepthWeighted(moving, power), *args, **kwargs)
    return register


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sequence", nargs="?", default=str(FR1_XYZ))
    parser.add_argument("--power", nargs="+", default=["textbook=1", "authors=-1"], help="VARIANT=POWER")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--schedule", default="overlap")
    parser.add_argument("--intrinsics", default=None, help="CAMERAS key; default from the folder name")
    args = parser.parse_args()
    sequence = read_sequence(args.sequence)
    intrinsics = CAMERAS[args.intrinsics or sequence_intrinsics(Path(args.sequence).name)]
    frames, groundtruth = first_frames(sequence, len(sequence))
    plain = overlap.register_d2d, measured_cut.register_d2d
    print("| schedule | EM | D2D weights × Z^-power | seed | ATE (m) | RPE (m/s, °/s) | CPU s / frame | "
          "worst frame (deg, cm) |")
    print("|---|---|---|---|---|---|---|---|")
    for variant, power in (item.split("=") for item in args.power):
        overlap.register_d2d, measured_cut.register_d2d = (depth_weighted(f, float(power)) for f in plain)
        for seed in args.seeds:
            with threadpool_limits(1):
                result = run_odometry(sequence, "gmm-pixels", frames, intrinsics=intrinsics, schedule=args.schedule,
                                      variant=variant, seed=seed)
            ate = absolute_trajectory_error(result.trajectory, sequence.groundtruth)
            rpe = relative_pose_error(result.trajectory, sequence.groundtruth)
            matched = result.trajectory.subset(np.searchsorted(result.trajectory.timestamps, groundtruth.timestamps))
            rotation, translation = frame_errors(matched, groundtruth)
            print(f"| {args.schedule} | {variant} | {power} | {seed} | {ate.rmse:.4f} | {rpe.translation_rmse:.4f}, "
                  f"{rpe.rotation_rmse_deg:.2f} | {result.cpu_seconds.mean():.3f} | {rotation.max():.2f}, "
                  f"{100 * translation.max():.2f} |", flush=True)
    overlap.register_d2d, measured_cut.register_d2d = plain


if __name__ == "__main__":
    main()
