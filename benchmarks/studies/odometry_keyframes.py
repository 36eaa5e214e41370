"""Frame-to-keyframe odometry: does registering onto a keyframe kept for N frames lower fr1/xyz's ATE?

Beyond the paper (its odometry is frame to frame). Every frame's model is built as ``run_odometry`` builds it
(``METHODS["gmm-pixels"]``, the frame's seed ``[seed, index]``, the ``overlap`` schedule); frame ``k`` is registered
onto the current keyframe, and becomes the keyframe once it is ``N`` frames past it. Its pose is the keyframe's pose
composed with the registration, ``T_k = T_key (T_key⁻¹ T_k)``. ``--start identity``: the schedule's registration
from the identity (as the frame-to-frame odometry); ``--start previous``: the schedule's cut rounds started from
the previous frame's pose relative to the keyframe (the baseline grows with N, the identity is then further off).
N=1 is the frame-to-frame odometry (the same trajectory as ``run_odometry`` with the identity start).

Prints one markdown row per (N, seed): ATE, one-second RPE, CPU s per frame (fit + registration). One thread.

``--spans N …`` measures instead, from every ``--span-every``-th frame ``k`` (frames with a ground-truth pose), frame
``k+N`` registered onto frame ``k`` directly (the schedule from the identity: what a keyframe N frames back gives)
against the N frame-to-frame registrations between them composed, both against the truth's motion from ``k`` to
``k+N``: if each registration's error were noise of its own that does not grow with the baseline, the direct one
would be about ``√N`` times smaller than the composed ones.

Usage: ``python benchmarks/studies/odometry_keyframes.py [--every 1 3] [--start identity previous] [--seeds 0]
[--variant textbook] [--frames 10000] [--spans 1 2 4 8 --span-every 20]``.
"""
import argparse
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from dgmm.odometry import (CAMERAS, METHODS, SCHEDULES, Trajectory, drift_metrics, first_frames,  # noqa: E402
                           frame_motions, read_sequence, sequence_intrinsics)
from dgmm.odometry.frame_model import CUT_TOL, ROUND_TOL  # noqa: E402
from dgmm.odometry.measured_cut import register_cut_rounds  # noqa: E402
from dgmm.registration import Registration, rotation_distance_deg  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/: odometry_peers
from odometry_peers import FR1_XYZ  # noqa: E402


def keyframe_odometry(sequence, frames, intrinsics, every, start, variant, seed):
    """(trajectory, CPU seconds per frame) of frame-to-keyframe odometry, a new keyframe every ``every`` frames."""
    prepare, register = METHODS["gmm-pixels"]
    schedule = SCHEDULES["overlap"]
    options = {"n_components": 100, "warm_iter": None, "schedule": schedule, "variant": variant, "size": "area",
               "intrinsics": intrinsics}
    rotations, translations, cpu = [np.eye(3)], [np.zeros(3)], []
    key, key_pose, relative = None, (np.eye(3), np.zeros(3)), (np.eye(3), np.zeros(3))
    for position, index in enumerate(frames):
        depth = sequence.depth(index)
        clock = time.process_time()
        model = prepare(depth, intrinsics, np.random.default_rng([seed, int(index)]), None, options)
        if key is None:
            key, key_position = model, position
            cpu.append(time.process_time() - clock)
            continue
        if start == "identity" or position - 1 == key_position:
            registration = register(key, model, options)
        else:  # from the previous frame's pose relative to the keyframe
            first = Registration(relative[0], relative[1], 0, 0.0, 0.0, True, "previous")
            registration = register_cut_rounds(key, model, first, schedule.cut_rounds, CUT_TOL, schedule.solver,
                                               {"tol": ROUND_TOL})
        relative = registration.rotation, registration.translation
        rotation = key_pose[0] @ relative[0]  # T_k = T_key (T_key⁻¹ T_k)
        translation = key_pose[0] @ relative[1] + key_pose[1]
        rotations.append(rotation)
        translations.append(translation)
        if position - key_position >= every:
            key, key_position, key_pose = model, position, (rotation, translation)
            relative = (np.eye(3), np.zeros(3))
        cpu.append(time.process_time() - clock)
    return (Trajectory(sequence.depth_timestamps[frames], np.array(rotations), np.array(translations)),
            np.array(cpu))


def span_errors(sequence, intrinsics, spans, every, variant, seed):
    """Per span N: RMS errors (deg, mm) of the direct registration k+N onto k and of the composed frame-to-frame
    ones, over the starts k."""
    prepare, register = METHODS["gmm-pixels"]
    options = {"n_components": 100, "warm_iter": None, "schedule": SCHEDULES["overlap"], "variant": variant,
               "size": "area", "intrinsics": intrinsics}
    matched, truth = sequence.groundtruth_at_frames()
    longest = max(spans)
    models, steps = {}, {}

    def model(position):
        if position not in models:
            index = int(matched[position])
            models[position] = prepare(sequence.depth(index), intrinsics, np.random.default_rng([seed, index]), None,
                                       options)
        return models[position]

    def step(position):  # frame position+1 onto frame position
        if position not in steps:
            registration = register(model(position), model(position + 1), options)
            steps[position] = registration.rotation, registration.translation
        return steps[position]

    rows = {span: [] for span in spans}
    for k in range(0, len(matched) - longest, every):
        if matched[k + longest] != matched[k] + longest:  # a frame without ground truth in between
            continue
        for span in spans:
            truth_r, truth_t = (m[0] for m in frame_motions(truth.subset([k, k + span])))
            direct = register(model(k), model(k + span), options)
            rotation, translation = np.eye(3), np.zeros(3)
            for position in range(k, k + span):
                r, t = step(position)
                rotation, translation = rotation @ r, rotation @ t + translation
            rows[span].append([rotation_distance_deg(direct.rotation, truth_r),
                               np.linalg.norm(direct.translation - truth_t), rotation_distance_deg(rotation, truth_r),
                               np.linalg.norm(translation - truth_t), np.linalg.norm(truth_t)])
        for position in [p for p in models if p < k + 1]:  # frames behind every later start
            del models[position]
    return {span: np.sqrt(np.mean(np.square(values), axis=0)) * [1, 1000, 1, 1000, 1000]
            for span, values in rows.items()}, len(rows[spans[0]])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sequence", nargs="?", default=str(FR1_XYZ))
    parser.add_argument("--every", type=int, nargs="+", default=[1, 3])
    parser.add_argument("--start", nargs="+", default=["identity"], choices=["identity", "previous"])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--variant", default="textbook")
    parser.add_argument("--frames", type=int, default=10_000)
    parser.add_argument("--spans", type=int, nargs="*", default=[])
    parser.add_argument("--span-every", type=int, default=20)
    args = parser.parse_args()
    sequence = read_sequence(args.sequence)
    intrinsics = CAMERAS[sequence_intrinsics(Path(args.sequence).name)]
    if args.spans:
        print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
        print("| span N (frames) | EM | seed | starts | direct k+N onto k: RMS (°, mm) | N frame-to-frame composed: "
              "RMS (°, mm) | true motion RMS (mm) |")
        print("|---|---|---|---|---|---|---|")
        for seed in args.seeds:
            with threadpool_limits(1):
                table, starts = span_errors(sequence, intrinsics, args.spans, args.span_every, args.variant, seed)
            for span, (dr, dt, cr, ct, true) in table.items():
                print(f"| {span} | {args.variant} | {seed} | {starts} | {dr:.3f}, {dt:.2f} | {cr:.3f}, {ct:.2f} | "
                      f"{true:.1f} |", flush=True)
        return
    frames, _ = first_frames(sequence, args.frames)
    print(f"{len(frames)} frames, load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print("| keyframe every N | start | EM | seed | ATE (m) | RPE (m/s, °/s) | CPU s / frame |")
    print("|---|---|---|---|---|---|---|")
    for every in args.every:
        for start in (args.start if every > 1 else ["identity"]):
            for seed in args.seeds:
                with threadpool_limits(1):
                    trajectory, cpu = keyframe_odometry(sequence, frames, intrinsics, every, start, args.variant,
                                                        seed)
                metrics = drift_metrics(trajectory, sequence.groundtruth)
                print(f"| {every} | {start} | {args.variant} | {seed} | {metrics['ate_rmse_m']:.4f} | "
                      f"{metrics['rpe_translation_m_s']:.4f}, {metrics['rpe_rotation_deg_s']:.2f} | "
                      f"{cpu.mean():.3f} |", flush=True)


if __name__ == "__main__":
    main()
