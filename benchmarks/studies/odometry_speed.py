"""Per-frame cost and ATE of gmm-pixels odometry: the reference schedule against the warm-started EM, in one run.

On one BLAS thread (as the workflow's jobs run), over the first N depth frames of a TUM sequence (fr1/xyz from
the mirror by default): gmm-pixels with every frame fitted from k-means (K=100, 25 EM iterations: the reference
schedule, the code before the warm start) and with every frame after the first started from the previous
frame's mixture (``--warm-iter`` iterations, starved components restarted), then ICP as the reference. Prints
CPU seconds per frame (model + D2D; the machine may be shared, so wall time is printed beside it), their ratio
and each run's ATE and RPE, with the load average.

Usage: ``python benchmarks/studies/odometry_speed.py [SEQUENCE_DIR] [--frames 100] [--warm-iter 5]``.
"""
import argparse
import os
from pathlib import Path

from threadpoolctl import threadpool_limits

from dgmm.odometry import run_odometry
from dgmm.odometry.pixels import CAMERAS, sequence_intrinsics
from dgmm.odometry.metrics import absolute_trajectory_error, relative_pose_error
from dgmm.odometry.tum import read_sequence

FR1_XYZ = Path(__file__).resolve().parents[3] / "shared" / "data" / "tum" / "rgbd_dataset_freiburg1_xyz"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sequence", nargs="?", default=str(FR1_XYZ))
    parser.add_argument("--frames", type=int, default=100)
    parser.add_argument("--warm-iter", type=int, default=5)
    parser.add_argument("--variant", default="textbook")
    parser.add_argument("--intrinsics", default=None, help="CAMERAS key; default from the folder name")
    args = parser.parse_args()
    sequence = read_sequence(args.sequence)
    camera = args.intrinsics or sequence_intrinsics(Path(args.sequence).name)
    runs = {"gmm-pixels, reference (k-means + 25 it.)": dict(method="gmm-pixels", schedule="reference"),
            f"gmm-pixels, warm start ({args.warm_iter} it.)": dict(method="gmm-pixels", schedule="reference",
                                                                   warm_iter=args.warm_iter),
            "icp": dict(method="icp")}
    print(f"{Path(args.sequence).name}: first {args.frames} frames, intrinsics {camera}, variant {args.variant}, "
          f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    seconds = {}
    with threadpool_limits(1):
        for name, options in runs.items():
            result = run_odometry(sequence, frames=range(min(args.frames, len(sequence))),
                                  intrinsics=CAMERAS[camera], variant=args.variant, **options)
            ate = absolute_trajectory_error(result.trajectory, sequence.groundtruth)
            rpe = relative_pose_error(result.trajectory, sequence.groundtruth)
            seconds[name] = result.cpu_seconds.mean()
            wall = result.prepare_seconds.mean() + result.registration_seconds.mean()
            print(f"  {name:45s} {seconds[name]:.3f} CPU s/frame (wall {wall:.3f}: model "
                  f"{result.prepare_seconds.mean():.3f}, registration {result.registration_seconds.mean():.3f}); "
                  f"ATE {ate.rmse:.4f} m, RPE {rpe.translation_rmse:.4f} m/s {rpe.rotation_rmse_deg:.3f} deg/s; "
                  f"load {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    paper, warm = list(seconds.values())[:2]
    print(f"  warm start is {paper / warm:.1f}x cheaper per frame (CPU); "
          f"load average now {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
