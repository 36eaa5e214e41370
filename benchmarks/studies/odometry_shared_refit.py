"""fr1/xyz odometry under the sweep's schedule, each pair registered again on a refit of the moving frame that
shares the fixed frame's tiling.

A study of the tiling noise, not a schedule: two frames' mixtures are fitted from different starts, so D2D matches
two different tilings of the same surfaces, and the mismatch is noise in the estimated motion. Here, after the
schedule's registration ``T`` of a pair, the moving frame is fitted again from the fixed frame's mixture moved into
its camera by ``T`` (its starved components restarted as the warm start does, ``dgmm.odometry.frame_model``) for
``--em-iter`` EM iterations, and registered again from ``T``: with ``--cut`` by the schedule's cut rounds, else by
one Gauss-Newton D2D. Each frame's own mixture (the schedule's) still serves as the fixed frame of the next pair.
Prints ATE, one-second RPE and CPU seconds per frame for the schedule alone and with the refit; one thread.

Usage: ``python benchmarks/studies/odometry_shared_refit.py [SEQUENCE_DIR] [--frames 300] [--seed 0]
[--variant textbook] [--em-iter 2 10] [--cut]``.
"""
import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

import dgmm.odometry.frame_model as frame_model  # noqa: E402
from dgmm.mixture import GaussianMixture  # noqa: E402
from dgmm.odometry import (CAMERAS, absolute_trajectory_error, first_frames, read_sequence,  # noqa: E402
                           relative_pose_error, run_odometry, sequence_intrinsics)
from dgmm.odometry.measured_cut import MeasuredFrame, register_cut_rounds  # noqa: E402
from dgmm.registration import register_d2d  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/: odometry_peers
from odometry_peers import FR1_XYZ  # noqa: E402


class _Moved:
    """A mixture's arrays in another camera: ``x -> Rᵀ (x - t)`` for the pose ``x_fixed = R x_moving + t``."""

    def __init__(self, mixture, rotation, translation):
        self.weights_ = mixture.weights_
        self.means_ = (mixture.means_ - translation) @ rotation
        self.covariances_ = rotation.T @ mixture.covariances_ @ rotation


def with_shared_refit(register, em_iter, cut):
    """``register(fixed, moving, options)`` followed by a registration on the moving frame refitted from the fixed
    frame's mixture at the first estimate."""
    def shared(fixed, moving, options):
        first = register(fixed, moving, options)
        start = _Moved(fixed, first.rotation, first.translation)
        weights, means, precisions = frame_model._warm_start(start, moving.primitives, np.random.default_rng(0))
        refit = GaussianMixture(len(weights), max_iter=em_iter, tol=None, weights_init=weights, means_init=means,
                                precisions_init=precisions, variant=options["variant"], reg_covar=frame_model.REG_COVAR,
                                memory_limit=frame_model.EM_BLOCK_BYTES).fit(moving.primitives)
        tol = {"tol": frame_model.ROUND_TOL}
        if not cut:
            return register_d2d(fixed, refit, first.rotation, first.translation, solver="gauss-newton", options=tol)
        frame = MeasuredFrame(refit, moving.primitives, moving.measured, moving.intrinsics, moving.step,
                              moving.variant)
        return register_cut_rounds(fixed, frame, first, 3, frame_model.CUT_TOL, "gauss-newton", tol)
    return shared


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sequence", nargs="?", default=str(FR1_XYZ))
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--variant", default="textbook")
    parser.add_argument("--em-iter", type=int, nargs="+", default=[2])
    parser.add_argument("--cut", action="store_true", help="register the refit by cut rounds")
    parser.add_argument("--intrinsics", default=None, help="CAMERAS key; default from the folder name")
    args = parser.parse_args()
    sequence = read_sequence(args.sequence)
    camera = args.intrinsics or sequence_intrinsics(Path(args.sequence).name)
    frames, _ = first_frames(sequence, args.frames)
    prepare, register = frame_model.METHODS["gmm-pixels"]
    print(f"{Path(args.sequence).name}: {len(frames)} frames, {args.variant} EM, seed {args.seed}, one thread")
    print("| registration | ATE RMSE (m) | RPE (m/s, deg/s) | CPU s/frame |\n|---|---|---|---|")
    runs = [("the schedule's (overlap)", register)] + [
        (f"+ refit sharing the fixed tiling, {n} EM iterations, {'cut rounds' if args.cut else 'one D2D'}",
         with_shared_refit(register, n, args.cut)) for n in args.em_iter]
    try:
        for name, registration in runs:
            frame_model.METHODS["gmm-pixels"] = (prepare, registration)
            with threadpool_limits(1):
                result = run_odometry(sequence, "gmm-pixels", frames, intrinsics=CAMERAS[camera],
                                      variant=args.variant, seed=args.seed)
            ate = absolute_trajectory_error(result.trajectory, sequence.groundtruth)
            rpe = relative_pose_error(result.trajectory, sequence.groundtruth)
            print(f"| {name} | {ate.rmse:.4f} | {rpe.translation_rmse:.4f}, {rpe.rotation_rmse_deg:.2f} | "
                  f"{result.cpu_seconds.mean():.3f} |", flush=True)
    finally:
        frame_model.METHODS["gmm-pixels"] = (prepare, register)


if __name__ == "__main__":
    main()
