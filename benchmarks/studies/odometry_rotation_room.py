"""Frame-to-frame errors of gmm-pixels on the synthetic room under rotation-only motion, by D2D strategy.

The camera stands 2.4 m from the table and is shaken about its optical centre at a peak of 110 °/s per axis
(``dgmm.odometry.synthetic.spinning_trajectory``), 40 frames at 30 Hz, the room with the bunny on the table. Each
frame's mixture is fitted once per EM variant with the fast schedule's start (the odometry's own ``_fit_mixture``
and seeds), then every consecutive pair is registered by each strategy; point-to-point ICP on 2,500 points and
Gauss-Newton D2D started from the true motion are diagnostics. Strategies: ``identity`` (the fast schedule's
D2D), ``overlapN`` (:func:`dgmm.odometry.overlap.register_d2d_overlap`, N rounds), ``c2f-overlapN`` (the same,
N rounds at each of ``--overlap-scales``), ``c2f`` (both mixtures'
covariances widened by ``s² I`` over ``--scales``, each stage's Gauss-Newton from the last pose), ``truth``
(from the true motion), ``fov-truth`` (an oracle: both frames refitted on their common view under the true
motion), ``refit-STRATEGY`` (both frames refitted on their common view at STRATEGY's pose, then registered from
it), ``icp``. ``--schedules`` then runs the odometry itself (``run_odometry``, each frame fitted by the schedule from
its own seed) under each schedule (a name or a spec of ``odometry_schedules.py``). ``--noise-free`` renders the same
frames without the Kinect noise model.
One BLAS thread, CPU time.

Prints per strategy and EM: registrations more than 2° or 3 cm off (of 39), the worst and median errors, CPU ms
per registration; with ``--frames-table`` every frame's errors.

Usage: ``python benchmarks/studies/odometry_rotation_room.py [--seed 0] [--peak 110] [--n-frames 40]
[--strategies identity overlap2 c2f truth fov-truth icp] [--schedules overlap common-view]
[--variants textbook authors] [--frames-table] [--noise-free]``.
"""
import argparse
import time
from pathlib import Path

import numpy as np
import trimesh
from threadpoolctl import threadpool_limits

from dgmm.odometry import frame_motions, groundtruth_at_frames, pixel_primitives, read_sequence, run_odometry
from dgmm.odometry.frame_model import _fit_mixture
from dgmm.odometry.schedule_studies import STUDY_SCHEDULES
from dgmm.odometry.overlap import register_d2d_overlap, seen_by
from dgmm.odometry.pixels import FR3, PIXEL_STEP, backproject
from dgmm.odometry.synthetic import (MAX_INCIDENCE_DEG, MAX_RANGE, MIN_RANGE, render_depth, room_scene,
                                     spinning_trajectory, write_synthetic_sequence)
from dgmm.primitives import Primitives
from dgmm.registration import register_d2d, register_icp, rotation_distance_deg
from dgmm.registration.coarse_to_fine import WidenedMixture
from odometry_schedules import parse_schedule  # this folder's script: schedule names and specs alike

ROOT = Path(__file__).resolve().parents[2]
BUNNY = ROOT.parent / "shared" / "data" / "stanford" / "bunny_res4.ply"
MAX_DEG, MAX_M = 2.0, 0.03


def room_sequence(folder, n_frames, seed, peak):
    """The rotation-only room sequence, written once into ``folder`` (reused when it exists)."""
    if folder.exists():
        return read_sequence(folder)
    bunny = trimesh.load(BUNNY, process=False)
    return write_synthetic_sequence(folder, room_scene([bunny.triangles]), n_frames=n_frames, seed=seed,
                                    path=lambda n, seed: spinning_trajectory(n, seed=seed, peak_deg_s=peak))


def errors(rotation, translation, truth_rotation, truth_translation):
    return rotation_distance_deg(rotation, truth_rotation), float(np.linalg.norm(translation - truth_translation))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--peak", type=float, default=110.0)
    parser.add_argument("--n-frames", type=int, default=40)
    parser.add_argument("--strategies", nargs="+", default=["identity", "overlap2", "c2f", "truth", "fov-truth", "icp"])
    parser.add_argument("--schedules", nargs="*", default=[],
                        help="run by run_odometry: schedule names or odometry_schedules.py's specs")
    parser.add_argument("--variants", nargs="+", default=["textbook", "authors"])
    parser.add_argument("--scales", type=float, nargs="+", default=[0.3, 0.15, 0.08, 0.04, 0.0],
                        help="c2f: standard deviations (m) added to every component, stage by stage, ending 0")
    parser.add_argument("--overlap-scales", type=float, nargs="+", default=[0.25, 0.125, 0.0625, 0.03125, 0.0],
                        help="c2f-overlap: widening in RMS radii of the moving mixture, ending 0")
    parser.add_argument("--frames-table", action="store_true")
    parser.add_argument("--noise-free", action="store_true", help="the same frames ray-cast without Kinect noise")
    parser.add_argument("--cache", default=str(ROOT / "results" / "benchmarks"), help="where the sequence is written")
    args = parser.parse_args()
    folder = Path(args.cache) / f"room-spin-{args.peak:g}-seed{args.seed}-{args.n_frames}"
    sequence = room_sequence(folder, args.n_frames, args.seed, args.peak)
    _, truth = groundtruth_at_frames(sequence)
    n = len(sequence)
    motions = list(zip(*frame_motions(truth)))
    steps = [rotation_distance_deg(r, np.eye(3)) for r, _ in motions]
    print(f"{folder.name}{' noise-free' if args.noise_free else ''}: {n} frames, true steps {min(steps):.1f}-"
          f"{max(steps):.1f}° (median {np.median(steps):.1f})")
    print("| strategy | EM | off (>2° or >3 cm) | worst (deg, cm) | median (deg, cm) | CPU ms per registration "
          "(schedules: per frame, fits included) |")
    print("|---|---|---|---|---|---|")
    schedule = STUDY_SCHEDULES["fast"]
    table = {}
    with threadpool_limits(1):
        depths = noise_free_depths(truth, n) if args.noise_free else [sequence.depth(i) for i in range(n)]
        primitives = [pixel_primitives(depth, FR3) for depth in depths]
        for variant in args.variants:
            options = dict(schedule=schedule, n_components=100, variant=variant, warm_iter=None)
            mixtures = [_fit_mixture(prims, np.random.default_rng([0, i]), None, options)
                        for i, prims in enumerate(primitives)]
            ctx = dict(mixtures=mixtures, primitives=primitives, depths=depths, motions=motions, options=options,
                       scales=args.scales, overlap_scales=args.overlap_scales)
            for strategy in args.strategies:
                if strategy == "icp" and variant != args.variants[0]:
                    continue
                result, cpu = [], 0.0
                for i in range(n - 1):
                    start = time.process_time()
                    rotation, translation = register(strategy, i, ctx)
                    cpu += time.process_time() - start
                    result.append(errors(rotation, translation, *motions[i]))
                table[strategy, variant] = print_row(strategy, variant if strategy != "icp" else "–", result,
                                                     cpu / (n - 1))
            for name in args.schedules:
                odometry = run_odometry(sequence, "gmm-pixels", intrinsics=FR3, schedule=parse_schedule(name),
                                        variant=variant)
                result = [errors(r.rotation, r.translation, *motion)
                          for r, motion in zip(odometry.registrations, motions)]
                table[f"schedule {name}", variant] = print_row(f"schedule {name}", variant, result,
                                                               odometry.cpu_seconds.mean())
    if args.frames_table:
        keys = list(table)
        print("frame step° | " + " | ".join(f"{s}/{v[:4]}" for s, v in keys))
        for i in range(n - 1):
            print(f"{i:3d} {steps[i]:4.1f} | " + " | ".join(
                f"{table[k][i, 0]:5.2f}° {100 * table[k][i, 1]:5.1f}cm" for k in keys))


def print_row(name, variant, result, cpu_seconds):
    """Print one strategy's markdown row; return its (n, 2) errors (deg, m)."""
    result = np.array(result)
    off = (result[:, 0] > MAX_DEG) | (result[:, 1] > MAX_M)
    worst = np.argmax(result[:, 1])
    print(f"| {name} | {variant} | {off.sum()} of {len(result)} | "
          f"{result[:, 0].max():.2f}, {100 * result[:, 1].max():.1f} (frame {worst}) | "
          f"{np.median(result[:, 0]):.2f}, {100 * np.median(result[:, 1]):.2f} | {1000 * cpu_seconds:.0f} |",
          flush=True)
    return result


def register(strategy, i, ctx):
    """(rotation, translation) of frame ``i + 1`` onto frame ``i`` by ``strategy``."""
    fixed, moving, motion = ctx["mixtures"][i], ctx["mixtures"][i + 1], ctx["motions"][i]
    if strategy == "identity":
        r = register_d2d(fixed, moving, solver="gauss-newton")
    elif strategy == "truth":
        r = register_d2d(fixed, moving, motion[0], motion[1], solver="gauss-newton")
    elif strategy == "c2f":  # both mixtures widened by (s m)^2 I, s over the scales, each stage from the last pose
        rotation, translation = None, None
        for scale in ctx["scales"]:
            r = register_d2d(WidenedMixture(fixed, scale ** 2) if scale else fixed,
                             WidenedMixture(moving, scale ** 2) if scale else moving, rotation, translation,
                             solver="gauss-newton")
            rotation, translation = r.rotation, r.translation
    elif strategy.startswith("overlap"):  # overlapN: N rounds on the components the other camera sees
        r = register_d2d_overlap(fixed, moving, FR3, rounds=int(strategy[len("overlap"):]))
    elif strategy.startswith("c2f-overlap"):  # c2f-overlapN: N rounds at each of --overlap-scales
        r = register_d2d_overlap(fixed, moving, FR3, rounds=int(strategy[len("c2f-overlap"):]),
                                 scales=ctx["overlap_scales"])
    elif strategy == "fov-truth":  # oracle: both frames' primitives cut to their common view under the true motion
        r = register_d2d(*common_view_mixtures(i, *motion, ctx), solver="gauss-newton")
    elif strategy.startswith("refit-"):  # refit-STRATEGY: both frames refitted on their common view at its pose
        first = register(strategy[len("refit-"):], i, ctx)
        r = register_d2d(*common_view_mixtures(i, *first, ctx), *first, solver="gauss-newton")
    elif strategy == "icp":
        rng = np.random.default_rng([0, i])
        a, b = backproject(ctx["depths"][i], FR3), backproject(ctx["depths"][i + 1], FR3)
        r = register_icp(b[rng.choice(len(b), 2500, replace=False)], a[rng.choice(len(a), 2500, replace=False)])
    else:
        raise SystemExit(f"unknown strategy {strategy}")
    return r.rotation, r.translation


def common_view_mixtures(i, rotation, translation, ctx):
    """Frames ``i`` and ``i + 1`` refitted on the primitives the other camera sees at the pose (rotation, translation)
    of ``i + 1`` in ``i``, each from its own seed."""
    fitted = []
    for j, (turn, shift) in ((i, (rotation.T, -rotation.T @ translation)), (i + 1, (rotation, translation))):
        prims = ctx["primitives"][j]
        keep = seen_by(prims.means, turn, shift, FR3)
        fitted.append(_fit_mixture(Primitives(prims.means[keep], prims.covariances[keep], prims.weights[keep]),
                                   np.random.default_rng([0, j]), None, ctx["options"]))
    return fitted


def noise_free_depths(truth, n_frames):
    """Each frame's exact ray-cast depth with the generator's returns (range, incidence) and no noise."""
    triangles = room_scene([trimesh.load(BUNNY, process=False).triangles])
    depths = []
    for rotation, translation in zip(truth.rotations[:n_frames], truth.translations[:n_frames]):
        exact, cosine = render_depth(triangles, rotation, translation, FR3, PIXEL_STEP)
        valid = (np.isfinite(exact) & (exact >= MIN_RANGE) & (exact <= MAX_RANGE)
                 & (cosine >= np.cos(np.radians(MAX_INCIDENCE_DEG))))
        image = np.where(valid, exact, 0.0).reshape(-(-FR3.height // PIXEL_STEP), -(-FR3.width // PIXEL_STEP))
        depths.append(np.repeat(np.repeat(image, PIXEL_STEP, axis=0), PIXEL_STEP, axis=1))
    return depths

if __name__ == "__main__":
    main()
