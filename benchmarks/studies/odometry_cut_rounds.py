"""How the cut rounds of the ``overlap`` schedule converge, on the rotation-only synthetic room.

Each frame is fitted as the sweep's odometry fits it (its own seed, the schedule's start and EM), then every
consecutive pair is registered by the schedule's widened overlap round and by cut rounds one after another
(``dgmm.odometry.measured_cut.register_measured`` from the last pose, each to the solver's own tolerance); the
errors against the rendered truth after each round are printed (worst and median over the pairs, and the pair
``--pair`` alone). Last, the bias of the cut itself: both frames cut at the true motion and registered from it. One
BLAS thread.

Usage: ``python benchmarks/studies/odometry_cut_rounds.py [--seed 0] [--rounds 5] [--pair 0]
[--variants textbook authors]`` (the room sequence is written once under results/benchmarks, as ``benchmarks/studies/odometry_rotation_room.py`` does).
"""
import argparse
import sys
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from dgmm.odometry import frame_motions, groundtruth_at_frames
from dgmm.odometry.frame_model import SCHEDULES, _prepare_pixels
from dgmm.odometry.measured_cut import _cut_mixture, register_measured, unseen_primitives
from dgmm.odometry.overlap import register_d2d_overlap
from dgmm.odometry.pixels import FR3
from dgmm.registration import register_d2d

sys.path.insert(0, str(Path(__file__).resolve().parent))
from odometry_rotation_room import ROOT, errors, room_sequence  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--pair", type=int, default=0)
    parser.add_argument("--variants", nargs="+", default=["textbook", "authors"])
    args = parser.parse_args()
    sequence = room_sequence(ROOT / "results" / "benchmarks" / f"room-spin-110-seed{args.seed}-40", 40, args.seed,
                             110.0)
    _, truth = groundtruth_at_frames(sequence)
    schedule = SCHEDULES["overlap"]
    motions = list(zip(*frame_motions(truth)))
    print(f"room seed {args.seed}: {len(motions)} pairs; translation error (cm) after each stage: worst, median "
          f"(pair {args.pair})")
    for variant in args.variants:
        options = dict(schedule=schedule, n_components=100, variant=variant, warm_iter=None,
                       size="area", intrinsics=FR3)
        with threadpool_limits(1):
            frames = [_prepare_pixels(sequence.depth(i), FR3, np.random.default_rng([0, i]), None, options)
                      for i in range(len(sequence))]
            stages = []
            for (fixed, moving) in zip(frames[:-1], frames[1:]):
                registration = register_d2d_overlap(fixed, moving, FR3, schedule.overlap_rounds,
                                                    schedule.overlap_scales)
                row = [registration]
                for _ in range(args.rounds):
                    registration = register_measured(fixed, moving, registration)
                    row.append(registration)
                stages.append(row)
            at_truth = []
            for (fixed, moving), motion in zip(zip(frames[:-1], frames[1:]), motions):
                fixed_unseen, moving_unseen = unseen_primitives(fixed, moving, *motion)
                at_truth.append(register_d2d(_cut_mixture(fixed, fixed_unseen), _cut_mixture(moving, moving_unseen),
                                             *motion, solver="gauss-newton"))
        table = np.array([[100 * errors(r.rotation, r.translation, *motion)[1] for r in row]
                          for row, motion in zip(stages, motions)])
        names = ["widened overlap round"] + [f"cut round {n}" for n in range(1, args.rounds + 1)]
        for column, name in enumerate(names):
            print(f"{variant}: {name}: {table[:, column].max():.2f}, {np.median(table[:, column]):.2f} "
                  f"({table[args.pair, column]:.2f})")
        truth_errors = np.array([100 * errors(r.rotation, r.translation, *motion)[1]
                                 for r, motion in zip(at_truth, motions)])
        print(f"{variant}: cut at the true motion, registered from it: {truth_errors.max():.2f}, "
              f"{np.median(truth_errors):.2f} ({truth_errors[args.pair]:.2f})")


if __name__ == "__main__":
    main()
