"""ATE, RPE and CPU cost per frame of odometry under per-frame schedules, to choose the sweep's by measurement.

On one BLAS thread (as the workflow's jobs run), over the first N depth frames of a TUM sequence (fr1/xyz from the
mirror by default, all 798 frames): each method and EM variant under each schedule, a name of
``dgmm.odometry.frame_model.SCHEDULES`` or ``dgmm.odometry.schedule_studies.STUDY_SCHEDULES``, or
``SEED_SAMPLE:LLOYD_ITER:EM_ITER:SOLVER`` (a ``Schedule``; SEED_SAMPLE ``all`` for scikit-learn's k-means on every
primitive), optionally followed by ``:OVERLAP_ROUNDS``, ``:SCALE,SCALE,...`` and ``:REFITS`` (the overlap fields),
and by ``+cutN`` (``cut_rounds``; ``+cut`` is one).
Prints one markdown row per run: ATE RMSE, the one-second RPE, the slope of the estimated on the true translation
over 10 frames (below 1: the motion is under-measured), CPU seconds per frame (fit + D2D; the machine may be shared,
so CPU time, not wall time) and the worst frame-to-frame error against the ground truth.

Usage: ``python benchmarks/studies/odometry_schedules.py [SEQUENCE_DIR] [--frames N] [--schedules fast reference ...]
[--variants textbook authors] [--methods gmm-pixels] [--seed S]``.
"""
import argparse
import dataclasses
import os
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from dgmm.odometry import CAMERAS, first_frames, frame_motions, read_sequence, relative_pose_error, run_odometry
from dgmm.odometry import absolute_trajectory_error, sequence_intrinsics
from dgmm.odometry.frame_model import SCHEDULES, Schedule
from dgmm.odometry.schedule_studies import STUDY_SCHEDULES
from dgmm.registration import rotation_distance_deg

FR1_XYZ = Path(__file__).resolve().parents[3] / "shared" / "data" / "tum" / "rgbd_dataset_freiburg1_xyz"


def parse_schedule(text):
    """A name of SCHEDULES or STUDY_SCHEDULES, or
    ``SEED_SAMPLE:LLOYD_ITER:EM_ITER:SOLVER[:OVERLAP_ROUNDS[:SCALE,...[:REFITS]]]``; the suffix ``+cutN`` sets
    ``cut_rounds`` to N (``+cut``: 1)."""
    text, _, rounds = text.partition("+cut")
    cut = int(rounds or 1) if _ else 0
    named = {**SCHEDULES, **STUDY_SCHEDULES}
    if text in named:
        return dataclasses.replace(named[text], cut_rounds=cut or named[text].cut_rounds)
    sample, lloyd_iter, em_iter, solver, *overlap = text.split(":")
    rounds = int(overlap[0]) if overlap else 0
    scales = tuple(float(scale) for scale in overlap[1].split(",")) if len(overlap) > 1 else (0.0,)
    return Schedule(None if sample == "all" else int(sample), int(lloyd_iter), int(em_iter), solver, rounds, scales,
                    int(overlap[2]) if len(overlap) > 2 else 0, cut)


def frame_errors(trajectory, groundtruth):
    """Rotation (deg) and translation (m) error of every frame-to-frame motion against the ground truth's."""
    (estimated, shifts), (true, true_shifts) = frame_motions(trajectory), frame_motions(groundtruth)
    rotation = np.array([rotation_distance_deg(e, g) for e, g in zip(estimated, true)])
    return rotation, np.linalg.norm(shifts - true_shifts, axis=1)


def translation_slope(trajectory, groundtruth, delta=10):
    """Least-squares slope of the estimated on the true translation over ``delta`` frames (camera frame): below
    1 the odometry under-measures the motion."""
    def relative(poses):
        first, second = slice(None, -delta), slice(delta, None)
        return np.einsum("nji,nj->ni", poses.rotations[first], poses.translations[second] - poses.translations[first])
    estimated, true = relative(trajectory), relative(groundtruth)
    return float(np.sum(estimated * true) / np.sum(true * true))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sequence", nargs="?", default=str(FR1_XYZ))
    parser.add_argument("--frames", type=int, default=10_000)
    parser.add_argument("--schedules", nargs="+", default=["reference"])
    parser.add_argument("--variants", nargs="+", default=["textbook", "authors"])
    parser.add_argument("--methods", nargs="+", default=["gmm-pixels"])
    parser.add_argument("--icp-tol", type=float, default=1e-9, help="ICP's stopping tolerance (m)")
    parser.add_argument("--intrinsics", default=None, help="CAMERAS key; default from the folder name")
    parser.add_argument("--seed", type=int, default=0, help="run_odometry's seed")
    args = parser.parse_args()
    sequence = read_sequence(args.sequence)
    camera = args.intrinsics or sequence_intrinsics(Path(args.sequence).name)
    frames, groundtruth = first_frames(sequence, args.frames)
    print(f"{Path(args.sequence).name}: {len(frames)} frames, intrinsics {camera}, load average "
          f"{' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(f"seed {args.seed}")
    print("| method | schedule | EM | ATE RMSE (m) | RPE (m/s, deg/s) | slope | CPU s/frame | worst frame (deg, cm) |")
    print("|---|---|---|---|---|---|---|---|")
    with threadpool_limits(1):
        for method in args.methods:
            for text in args.schedules:
                for variant in (args.variants if method != "icp" else [""]):
                    result = run_odometry(sequence, method, frames, intrinsics=CAMERAS[camera],
                                          schedule=parse_schedule(text), variant=variant or "textbook",
                                          icp_tol=args.icp_tol, seed=args.seed)
                    ate = absolute_trajectory_error(result.trajectory, sequence.groundtruth)
                    rpe = relative_pose_error(result.trajectory, sequence.groundtruth)
                    matched = result.trajectory.subset(np.searchsorted(result.trajectory.timestamps,
                                                                       groundtruth.timestamps))
                    rotation, translation = frame_errors(matched, groundtruth)
                    print(f"| {method} | {text} | {variant or '–'} | {ate.rmse:.4f} | {rpe.translation_rmse:.4f}, "
                          f"{rpe.rotation_rmse_deg:.2f} | {translation_slope(matched, groundtruth):.3f} | "
                          f"{result.cpu_seconds.mean():.3f} | "
                          f"{rotation.max():.2f}, {100 * translation.max():.2f} |", flush=True)


if __name__ == "__main__":
    main()
