"""Drift under fast rotation: the ATE of our odometry and the peers' on the rotation cases that can be built here.

Cases (``--cases``): ``spun:START:N:RATE:SEED``, fr1/xyz frames START..START+N-1 (those with a ground-truth pose)
turned about the optical centre at a peak of RATE °/s per axis (``dgmm.odometry.synthetic.write_spun_sequence``,
spin seed SEED; with fr1/xyz's own motion), ``ros`` intrinsics; ``room:SEED:N``, the synthetic room under
rotation-only motion at 110 °/s (``spinning_trajectory``, as ``odometry_rotation_room.py`` writes it), ``fr3``
intrinsics; ``fr1xyz:N``, fr1/xyz itself (its first N frames, as the benchmarks run it). Each case is written once
under ``--cache``. Runs (``--runs``): ``gmm-pixels:EM[:SIZE]`` (EM textbook or authors, pixel size area or unit),
``gmm-points``, ``icp`` (ours, the sweep's ``overlap`` schedule unless ``--schedule``; every seed of ``--seeds``),
and the peers of ``benchmarks/odometry_peers.py`` (``gicp-0.02``, ``gicp-0.05``: small_gicp GICP at that voxel;
``open3d``: Open3D point-to-plane ICP, voxel 0.02 m). All frame to frame from the identity, one thread.

Prints a markdown row per (case, run, seed): ATE RMSE, one-second RPE, the worst frame-to-frame error against the
truth and how many are more than 2° or 3 cm off, CPU s per frame. ``--save DIR`` writes every run's poses at the
frames with a ground-truth pose and the truth's frame-to-frame motions (``DIR/CASE/RUN-seedS.npz``) for
``odometry_error_bias.py``.

Usage: ``python benchmarks/studies/odometry_rotation_drift.py --cases spun:0:300:90:1 room:0:40
[--runs gmm-pixels:textbook gmm-pixels:authors gmm-points icp gicp-0.02 gicp-0.05 open3d] [--seeds 0 1 2]
[--save results/studies/rotation]``.
"""
import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from dgmm.odometry import (CAMERAS, drift_metrics, first_frames, frame_motions, groundtruth_at_frames,  # noqa: E402
                           read_sequence, run_odometry, sequence_intrinsics)
from dgmm.registration import rotation_distance_deg  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))  # odometry_peers
sys.path.insert(0, str(Path(__file__).resolve().parent))  # odometry_rotation_room
from odometry_peers import FR1_XYZ, open3d_method, run_peer, small_gicp_method  # noqa: E402

MAX_DEG, MAX_M = 2.0, 0.03
PEERS = {"gicp-0.02": lambda: small_gicp_method(0.02), "gicp-0.05": lambda: small_gicp_method(0.05),
         "open3d": lambda: open3d_method(0.02)}


def case_sequence(case, cache):
    """(sequence, intrinsics, frame count or None for all) of a case, written under ``cache`` once."""
    kind, *fields = case.split(":")
    if kind == "spun":
        start, n, rate, seed = int(fields[0]), int(fields[1]), float(fields[2]), int(fields[3])
        folder = Path(cache) / f"fr1xyz-spun-{start}-{n}-{rate:g}-seed{seed}"
        if not folder.exists():
            from dgmm.odometry.synthetic import write_spun_sequence

            source = read_sequence(FR1_XYZ)
            matched, _ = groundtruth_at_frames(source)  # the frames with a ground-truth pose
            write_spun_sequence(folder, source, matched[(matched >= start) & (matched < start + n)], rate, seed,
                                CAMERAS["ros"])
        return read_sequence(folder), CAMERAS["ros"], None
    if kind == "fr1xyz":  # the sequence itself, its first N frames with a ground-truth pose (a reference)
        source = read_sequence(FR1_XYZ)
        return source, CAMERAS[sequence_intrinsics(FR1_XYZ.name)], int(fields[0])
    if kind == "room":
        from odometry_rotation_room import room_sequence

        seed, n = int(fields[0]), int(fields[1])
        return room_sequence(Path(cache) / f"room-spin-110-seed{seed}-{n}", n, seed, 110.0), CAMERAS["fr3"], None
    raise SystemExit(f"unknown case {case!r}")


def frame_errors(motions, truth):
    """(n, 2) errors (deg, m) of frame-to-frame motions against the truth's."""
    return np.array([(rotation_distance_deg(r, tr), float(np.linalg.norm(t - tt)))
                     for r, t, tr, tt in zip(*motions, *truth)])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", required=True)
    parser.add_argument("--runs", nargs="+", default=["gmm-pixels:textbook", "gmm-pixels:authors", "gmm-points", "icp",
                                                      "gicp-0.02", "gicp-0.05", "open3d"])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--schedule", default="overlap")
    parser.add_argument("--cache", default=str(ROOT / "results" / "benchmarks"))
    parser.add_argument("--save", default=None)
    args = parser.parse_args()
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print("| case | run | seed | ATE (m) | RPE (m/s, °/s) | worst frame (°, cm) | off (> 2° or 3 cm) | "
          "CPU s / frame |")
    print("|---|---|---|---|---|---|---|---|")
    for case in args.cases:
        sequence, intrinsics, count = case_sequence(case, args.cache)
        matched, truth_poses = groundtruth_at_frames(sequence)
        frames = matched if count is None else first_frames(sequence, count)[0]  # fr1xyz: as the benchmarks run it
        rows = np.flatnonzero(np.isin(frames, matched))  # the run's frames with a ground-truth pose
        truth = frame_motions(truth_poses.subset(np.flatnonzero(np.isin(matched, frames))))
        for run in args.runs:
            for seed in (args.seeds if run.startswith("gmm") or run == "icp" else [0]):
                with threadpool_limits(1):
                    if run in PEERS:
                        trajectory, cpu = run_peer(sequence, frames, intrinsics, *PEERS[run]())
                    else:
                        fields = run.split(":")
                        method, variant, size = fields[0], *(fields[1:] + ["textbook", "area"][len(fields) - 1:])
                        result = run_odometry(sequence, method, frames, intrinsics=intrinsics, schedule=args.schedule,
                                              variant=variant, size=size, seed=seed)
                        trajectory, cpu = result.trajectory, result.cpu_seconds
                motions = frame_motions(trajectory.subset(rows))
                errors = frame_errors(motions, truth)
                metrics = drift_metrics(trajectory, sequence.groundtruth)
                off = int(np.sum((errors[:, 0] > MAX_DEG) | (errors[:, 1] > MAX_M)))
                print(f"| {case} | {run} | {seed} | {metrics['ate_rmse_m']:.4f} | "
                      f"{metrics['rpe_translation_m_s']:.4f}, {metrics['rpe_rotation_deg_s']:.2f} | "
                      f"{errors[:, 0].max():.2f}, {100 * errors[:, 1].max():.2f} | {off} of {len(errors)} | "
                      f"{cpu.mean():.3f} |", flush=True)
                if args.save:
                    out = Path(args.save) / case.replace(":", "_")
                    out.mkdir(parents=True, exist_ok=True)
                    kept = trajectory.subset(rows)
                    np.savez(out / f"{run.replace(':', '_')}-seed{seed}.npz", timestamps=kept.timestamps,
                             rotations=kept.rotations, translations=kept.translations,
                             cpu=cpu, truth_rotations=truth[0], truth_translations=truth[1])


if __name__ == "__main__":
    main()
