"""CPU per frame of each stage of gmm-pixels odometry under a schedule (the docs' per-frame cost table).

On one BLAS thread (as the workflow's jobs run), over the first N depth frames of a TUM sequence (fr1/xyz from the
mirror by default): the odometry runs once with each stage's function wrapped by a CPU timer
(``time.process_time``): the EM (``GaussianMixture.fit``), the k-means++ and Lloyd start (``lloyd_start``), the
overlap round (``register_d2d_overlap``), the cut rounds' D2D and their cuts and visibility tests
(``dgmm.odometry.measured_cut``). Prints one markdown row per stage in ms per frame, and the whole frame's CPU
(fit + registration, PNG decoding excluded, as ``run_odometry`` counts it). The machine may be shared: run it on an
idle one.

Usage: ``python benchmarks/studies/odometry_stages.py [SEQUENCE_DIR] [--frames 200] [--schedule overlap]
[--variant textbook] [--seed 0]``.
"""
import argparse
import time
from functools import wraps
from pathlib import Path

from threadpoolctl import threadpool_limits

import dgmm.odometry.frame_model as frame_model
import dgmm.odometry.measured_cut as measured_cut
from dgmm.odometry import first_frames, read_sequence, run_odometry
from dgmm.odometry.pixels import CAMERAS, sequence_intrinsics

FR1_XYZ = Path(__file__).resolve().parents[3] / "shared" / "data" / "tum" / "rgbd_dataset_freiburg1_xyz"

STAGES = {  # stage -> (module or class, function names whose CPU time it counts)
    "EM iterations": (frame_model.GaussianMixture, ["fit"]),
    "k-means++ and Lloyd start": (frame_model, ["lloyd_start"]),
    "overlap round (widened D2D)": (frame_model, ["register_d2d_overlap"]),
    "cut rounds: D2D": (measured_cut, ["register_d2d"]),
    "cut rounds: cuts and visibility": (measured_cut, ["_cut_mixture", "unseen_primitives"]),
}


def timed(function, totals, stage):
    """``function`` adding its CPU seconds to ``totals[stage]``."""
    @wraps(function)
    def wrapper(*args, **kwargs):
        start = time.process_time()
        try:
            return function(*args, **kwargs)
        finally:
            totals[stage] += time.process_time() - start
    return wrapper


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sequence", nargs="?", default=str(FR1_XYZ))
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--schedule", default="overlap")
    parser.add_argument("--variant", default="textbook")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    totals = dict.fromkeys(STAGES, 0.0)
    for stage, (owner, names) in STAGES.items():
        for name in names:
            setattr(owner, name, timed(getattr(owner, name), totals, stage))
    sequence = read_sequence(args.sequence)
    frames, _ = first_frames(sequence, args.frames)
    intrinsics = CAMERAS[sequence_intrinsics(Path(args.sequence).name)]
    with threadpool_limits(1):
        result = run_odometry(sequence, "gmm-pixels", frames, intrinsics=intrinsics, schedule=args.schedule,
                              variant=args.variant, seed=args.seed)
    print(f"{Path(args.sequence).name}, first {len(frames)} frames, schedule {args.schedule}, {args.variant} EM, "
          f"seed {args.seed}, one thread, CPU ms per frame:\n\n| stage | ms / frame |\n|---|---|")
    for stage, seconds in totals.items():
        print(f"| {stage} | {1e3 * seconds / len(frames):.1f} |")
    print(f"| all of a frame (CPU) | {1e3 * result.cpu_seconds.mean():.1f} |")


if __name__ == "__main__":
    main()
