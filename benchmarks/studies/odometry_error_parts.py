"""Where a frame-to-frame trajectory's ATE comes from: its rotations, its translations, or how they combine.

Runs gmm-pixels under a schedule (and small_gicp GICP at voxel 0.02 m, the peers' row, when the ``peers`` extra is
installed) over fr1/xyz, then recomposes each trajectory from its frame-to-frame motions with either part replaced
by the ground truth's: the ATE with the true rotations and the estimated translations (what the translations cost),
with the estimated rotations and the true translations (what the rotations cost), and with every translation scaled
(a scale bias would lower it). Frames with a ground-truth pose only; one thread.

Usage: ``python benchmarks/studies/odometry_error_parts.py [SEQUENCE_DIR] [--schedule overlap] [--variant textbook]
[--seed 0] [--no-peers]``.
"""
import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from dgmm.odometry import (CAMERAS, Trajectory, absolute_trajectory_error, first_frames, frame_motions,  # noqa: E402
                           read_sequence, run_odometry, sequence_intrinsics)
from dgmm.odometry.tum import associate  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/: odometry_peers
from odometry_peers import FR1_XYZ, run_peer, small_gicp_method  # noqa: E402


def compose(timestamps, steps, shifts):
    """The trajectory from the identity through the motions."""
    rotations, translations = [np.eye(3)], [np.zeros(3)]
    for step, shift in zip(steps, shifts):
        translations.append(rotations[-1] @ shift + translations[-1])
        rotations.append(rotations[-1] @ step)
    return Trajectory(timestamps, np.array(rotations), np.array(translations))


def parts(name, estimate, groundtruth):
    """Print the ATE of ``estimate`` and of its recompositions with true rotations, translations, scaled shifts."""
    rows, truth_rows = associate(estimate.timestamps, groundtruth.timestamps)
    timestamps = estimate.timestamps[rows]
    steps, shifts = frame_motions(estimate.subset(rows))
    true_steps, true_shifts = frame_motions(groundtruth.subset(truth_rows))

    def ate(*motion):
        return absolute_trajectory_error(compose(timestamps, *motion), groundtruth).rmse

    scaled = " / ".join(f"{ate(steps, factor * shifts):.4f}" for factor in (1.01, 1.02, 1.03))
    print(f"| {name} | {ate(steps, shifts):.4f} | {ate(true_steps, shifts):.4f} | {ate(steps, true_shifts):.4f} | "
          f"{scaled} |", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sequence", nargs="?", default=str(FR1_XYZ))
    parser.add_argument("--schedule", default="overlap")
    parser.add_argument("--variant", default="textbook")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--no-peers", action="store_true")
    args = parser.parse_args()
    sequence = read_sequence(args.sequence)
    intrinsics = CAMERAS[sequence_intrinsics(Path(args.sequence).name)]
    frames, _ = first_frames(sequence, 10_000)
    print("| trajectory | ATE (m) | true rotations, its translations | its rotations, true translations | "
          "translations × 1.01 / 1.02 / 1.03 |")
    print("|---|---|---|---|---|")
    with threadpool_limits(1):
        result = run_odometry(sequence, "gmm-pixels", frames, intrinsics=intrinsics, schedule=args.schedule,
                              variant=args.variant, seed=args.seed)
        parts(f"gmm-pixels, {args.schedule}, {args.variant}, seed {args.seed}", result.trajectory,
              sequence.groundtruth)
        if not args.no_peers:
            trajectory, _ = run_peer(sequence, frames, intrinsics, *small_gicp_method(0.02))
            parts("small_gicp GICP, voxel 0.02 m", trajectory, sequence.groundtruth)


if __name__ == "__main__":
    main()
