"""Our odometry protocol beside the authors' (paper §VI-D, Fig 7): ATE, RPE and CPU per frame, and the ATE of every
frame prefix, on fr1/xyz, the synthetic room and the rotation cases.

Runs (``--runs``): ``ours:EM:SIZE`` (the sweep's ``overlap`` schedule, textbook or authors EM, pixel size area or
unit, flat patch covariances) and the authors' protocols ``authors-patch``, ``authors-disparity``
(:mod:`dgmm.odometry.protocols`: sizes of 1, the notebooks' covariance, scikit-learn's ``GaussianMixture(100)`` at its
defaults, BFGS D2D from the identity; one EM, both variants being one algorithm on sizes of 1), and
``authors-points``, the plain points fitted and registered as ``authors-patch`` fits its pixels (``gen_gmm.ipynb``).
Every run is ``gmm-pixels`` (``gmm-points`` for ``authors-points``) over the same frames, frame to frame from the
identity, one thread, each seed of ``--seeds``.

Cases (``--cases``): ``odometry_rotation_drift.py``'s (``fr1xyz:N``, ``spun:START:N:RATE:SEED``, ``room:SEED:N``:
rotation only), and ``synthetic:SEED:N``, the synthetic room on its hand-held path (``write_synthetic_sequence``'s
default, the bunny on the furniture as ``odometry_rotation_room.py`` places it), written once under ``--cache``.
A case's ``N`` is its longest prefix; ``--prefixes`` adds the ATE of shorter ones, each the run itself stopped
there (frame ``k``'s fit is seeded ``[seed, k]`` and registered onto frame ``k - 1`` only, so the first ``n`` poses of
a run are the run of ``n`` frames).

Prints a markdown row per (case, run, seed): ATE, RPE, the worst frame-to-frame error and how many frames are more
than 2° or 3 cm off, CPU s per frame, the prefixes' ATEs; then per case, every run's mean and range over the seeds
and, per prefix, whether each pair of runs separates (the ranges over seeds do not overlap).

Usage: ``python benchmarks/studies/odometry_protocols.py --cases fr1xyz:200 room:0:40 [--runs ours:textbook:area
ours:authors:area ours:textbook:unit authors-patch authors-disparity] [--seeds 0 1 2 3 4] [--prefixes 25 50 100]``.
"""
import argparse
import os
import sys
from itertools import combinations
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from dgmm.odometry import (CAMERAS, drift_metrics, first_frames, frame_motions, groundtruth_at_frames,  # noqa: E402
                           read_sequence, run_odometry)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from odometry_rotation_drift import MAX_DEG, MAX_M, ROOT, case_sequence, frame_errors  # noqa: E402

RUNS = ["ours:textbook:area", "ours:authors:area", "ours:textbook:unit", "authors-patch", "authors-disparity"]


def sequence_of(case, cache):
    """(sequence, intrinsics, frame count or None) of a case; ``synthetic:SEED:N`` here, the others as
    ``odometry_rotation_drift.case_sequence``."""
    kind, *fields = case.split(":")
    if kind != "synthetic":
        return case_sequence(case, cache)
    import trimesh
    from odometry_rotation_room import BUNNY

    from dgmm.odometry.synthetic import room_scene, write_synthetic_sequence

    seed, n = int(fields[0]), int(fields[1])
    folder = Path(cache) / f"room-handheld-seed{seed}-{n}"
    if folder.exists():
        return read_sequence(folder), CAMERAS["fr3"], None
    bunny = trimesh.load(BUNNY, process=False)
    return write_synthetic_sequence(folder, room_scene([bunny.triangles]), n_frames=n, seed=seed), CAMERAS["fr3"], None


def run_options(run):
    """``run_odometry``'s method and keywords of a run spec."""
    if run.startswith("ours"):
        _, variant, size = run.split(":")
        return "gmm-pixels", dict(protocol="ours", schedule="overlap", variant=variant, size=size)
    if run == "authors-points":
        return "gmm-points", dict(protocol="authors-patch", variant="authors")
    return "gmm-pixels", dict(protocol=run, variant="authors")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", required=True)
    parser.add_argument("--runs", nargs="+", default=RUNS)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--prefixes", type=int, nargs="*", default=[])
    parser.add_argument("--cache", default=str(ROOT / "results" / "benchmarks"))
    args = parser.parse_args()
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    for case in args.cases:
        sequence, intrinsics, count = sequence_of(case, args.cache)
        matched, truth_poses = groundtruth_at_frames(sequence)
        frames = matched if count is None else first_frames(sequence, count)[0]
        rows = np.flatnonzero(np.isin(frames, matched))
        truth = frame_motions(truth_poses.subset(np.flatnonzero(np.isin(matched, frames))))
        prefixes = [n for n in args.prefixes if n < len(frames)] + [len(frames)]
        print(f"\n{case}: {len(frames)} frames\n")
        print("| run | seed | ATE (m) | RPE (m/s, °/s) | worst frame (°, cm) | off (> 2° or 3 cm) | CPU s / frame | "
              + " | ".join(f"ATE {n}" for n in prefixes[:-1]) + " |")
        print("|---|---|---|---|---|---|---|" + "---|" * len(prefixes[:-1]))
        ates = {}
        for run in args.runs:
            for seed in args.seeds:
                method, options = run_options(run)
                with threadpool_limits(1):
                    result = run_odometry(sequence, method, frames, intrinsics=intrinsics, seed=seed, **options)
                trajectory = result.trajectory
                errors = frame_errors(frame_motions(trajectory.subset(rows)), truth)
                metrics = drift_metrics(trajectory, sequence.groundtruth)
                ates[run, seed] = [drift_metrics(trajectory.subset(np.arange(n)), sequence.groundtruth)["ate_rmse_m"]
                                   for n in prefixes]
                off = int(np.sum((errors[:, 0] > MAX_DEG) | (errors[:, 1] > MAX_M)))
                rpe = (f"{metrics['rpe_translation_m_s']:.4f}, {metrics['rpe_rotation_deg_s']:.2f}"
                       if metrics["rpe_translation_m_s"] is not None else "–")
                print(f"| {run} | {seed} | {metrics['ate_rmse_m']:.4f} | {rpe} | {errors[:, 0].max():.2f}, "
                      f"{100 * errors[:, 1].max():.2f} | {off} of {len(errors)} | {result.cpu_seconds.mean():.3f} | "
                      + " | ".join(f"{a:.4f}" for a in ates[run, seed][:-1]) + " |", flush=True)
        print(f"\n{case}: mean (range) of the ATE over seeds {args.seeds}, per prefix\n")
        print("| run | " + " | ".join(f"{n} frames" for n in prefixes) + " |")
        print("|---|" + "---|" * len(prefixes))
        table = {run: np.array([ates[run, seed] for seed in args.seeds]) for run in args.runs}
        for run, values in table.items():
            print(f"| {run} | " + " | ".join(f"{v.mean():.4f} ({v.min():.4f}-{v.max():.4f})" for v in values.T) + " |")
        print(f"\n{case}: pairs of runs whose ATE ranges over the seeds do not overlap, per prefix\n")
        for i, n in enumerate(prefixes):
            apart = [f"{a} < {b}" if table[a][:, i].max() < table[b][:, i].min() else f"{b} < {a}"
                     for a, b in combinations(args.runs, 2)
                     if table[a][:, i].max() < table[b][:, i].min() or table[b][:, i].max() < table[a][:, i].min()]
            print(f"- {n} frames: {'; '.join(apart) or 'none'}")


if __name__ == "__main__":
    main()
