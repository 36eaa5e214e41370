"""What a bias explains of a frame-to-frame trajectory's error on fr1/xyz, and what is left.

Reads the runs that ``odometry_rotation_drift.py --cases fr1xyz:10000 --save DIR`` wrote (every frame's pose and the
truth's frame-to-frame motion). Frame ``k``'s error against the truth's motion ``(R*, t*)`` is ``ω = log(R R*ᵀ)`` (a
rotation vector in camera ``k``) and ``δ = t - t*``.

*Growth*: the RMS error of ``W`` consecutive motions composed, against the truth's composed, over every start: noise
of each registration's own grows as ``√W``, a bias as ``W``; the ground truth's own pose noise enters once per window
whatever ``W`` (alone, differenced into motions, it gives a lag-1 autocorrelation of -0.5: printed per coordinate).

*Bias models*: each of the six error coordinates is regressed by least squares on features of the frame, the sums over
blocks of ``--block`` frames fitted (a window's ground-truth noise is that of one frame, its motion ``--block`` times
larger, so the fit is not diluted by it), and applied to every frame:

- ``direction``: a constant (an error of fixed direction in the camera frame);
- ``scale``: one factor on the true rotation and one on the true translation (the measured motion's scale);
- ``pull``: the true motion's six coordinates (a 6×6 map: a pull toward the identity per axis, and rotation read as
  translation or the reverse), and the constant;
- ``+ overlap``: ``1 - o`` and ``(1 - o) ×`` the motion, ``o`` the share of frame ``k+1``'s grid points that land on
  a measured pixel of frame ``k`` at the true motion;
- ``+ depth``: the frame's median depth (less its mean over the run), alone and × the motion.

Fits are two-fold over the two halves of the run (the first half's fit predicts the second and the reverse), so a
model explains only what carries from one part of the sequence to the other. Per model: the share of the blocks' error
sum of squares it explains out of fold, the ATE of the truth's motions with only the predicted error added (``bias
only``) and of the estimate with it taken out (``left``).

Usage: ``python benchmarks/studies/odometry_error_bias.py results/studies/rotation/fr1xyz_10000/*.npz [--block 10]``.
"""
import argparse
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from dgmm.odometry import CAMERAS, Trajectory, absolute_trajectory_error, read_sequence
from dgmm.odometry.pixels import PIXEL_STEP, backproject
from dgmm.registration import rotation_distance_deg

FR1_XYZ = Path(__file__).resolve().parents[3] / "shared" / "data" / "tum" / "rgbd_dataset_freiburg1_xyz"
WINDOWS = (1, 3, 10, 30, 100)


def compose(timestamps, rotations, translations):
    """The trajectory from the identity through the frame-to-frame motions."""
    poses_r, poses_t = [np.eye(3)], [np.zeros(3)]
    for rotation, translation in zip(rotations, translations):
        poses_t.append(poses_r[-1] @ translation + poses_t[-1])
        poses_r.append(poses_r[-1] @ rotation)
    return Trajectory(timestamps, np.array(poses_r), np.array(poses_t))


def frame_features(sequence, timestamps, truth_rotations, truth_translations, intrinsics):
    """Per motion ``k`` (frame k+1 onto frame k): the overlap ``o`` and frame k's median depth."""
    index = [int(np.argmin(np.abs(sequence.depth_timestamps - t))) for t in timestamps]
    overlap, depth, grids = [], [], {}
    for k in range(len(timestamps) - 1):
        for i in index[k:k + 2]:
            if i not in grids:
                grids[i] = sequence.depth(i)
        fixed, moving = grids.pop(index[k]), grids[index[k + 1]]
        points = backproject(moving, intrinsics) @ truth_rotations[k].T + truth_translations[k]
        u, v, front = intrinsics.project(points)
        col, row = np.rint(u / PIXEL_STEP), np.rint(v / PIXEL_STEP)
        measured = fixed[::PIXEL_STEP, ::PIXEL_STEP]
        inside = front & (col >= 0) & (col < measured.shape[1]) & (row >= 0) & (row < measured.shape[0])
        seen = np.zeros(len(points), bool)
        seen[inside] = measured[row[inside].astype(int), col[inside].astype(int)] > 0
        overlap.append(seen.mean())
        depth.append(float(np.median(measured[measured > 0])))
    return np.array(overlap), np.array(depth)


def window_errors(steps, shifts, true_steps, true_shifts, window):
    """RMS over every start of the error of ``window`` composed motions: (degrees, mm)."""
    angles, lengths = [], []
    for start in range(len(steps) - window + 1):
        rotation, translation, true_rotation, true_translation = np.eye(3), np.zeros(3), np.eye(3), np.zeros(3)
        for k in range(start, start + window):
            translation, rotation = rotation @ shifts[k] + translation, rotation @ steps[k]
            true_translation = true_rotation @ true_shifts[k] + true_translation
            true_rotation = true_rotation @ true_steps[k]
        angles.append(rotation_distance_deg(rotation, true_rotation))
        lengths.append(np.linalg.norm(translation - true_translation))
    return np.sqrt(np.mean(np.square(angles))), 1000 * np.sqrt(np.mean(np.square(lengths)))


def two_halves(features, target, block):
    """Out-of-fold per-frame predictions of ``target`` (n, 6) from ``features`` (n, f) or, for each output column
    ``c``, from ``features[c]`` (a list): fitted on the sums over blocks of ``block`` frames of each half."""
    n = len(target)
    halves = np.arange(n) >= n // 2
    predicted = np.zeros_like(target)
    for half in (False, True):
        train = np.flatnonzero(halves != half)
        train = train[:len(train) // block * block]
        for c in range(target.shape[1]):
            x = features[c] if isinstance(features, list) else features
            sums_x = x[train].reshape(-1, block, x.shape[1]).sum(axis=1)
            sums_y = target[train, c].reshape(-1, block).sum(axis=1)
            coefficients, *_ = np.linalg.lstsq(sums_x, sums_y, rcond=None)
            predicted[halves == half, c] = x[halves == half] @ coefficients
    return predicted


def block_explained(error, predicted, block):
    """Share of the blocks' error sum of squares taken out by ``predicted``, rotation and translation."""
    n = len(error) // block * block

    def sums(values):
        return values[:n].reshape(-1, block, 6).sum(axis=1)

    total, left = sums(error), sums(error - predicted)
    return [1 - np.sum(left[:, b] ** 2) / np.sum(total[:, b] ** 2) for b in (slice(0, 3), slice(3, 6))]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+")
    parser.add_argument("--sequence", default=str(FR1_XYZ))
    parser.add_argument("--block", type=int, default=10)
    args = parser.parse_args()
    sequence = read_sequence(args.sequence)
    features_cache, growth_rows, lag_rows, scales = None, [], [], []
    print("| run | model | parameters | explained, out of fold (rotation, translation) | ATE bias only (m) | "
          "ATE left (m) |")
    print("|---|---|---|---|---|---|")
    for path in args.runs:
        run = np.load(path)
        rotations, translations, timestamps = run["rotations"], run["translations"], run["timestamps"]
        steps = np.einsum("nji,njk->nik", rotations[:-1], rotations[1:])
        shifts = np.einsum("nji,nj->ni", rotations[:-1], translations[1:] - translations[:-1])
        true_steps, true_shifts = run["truth_rotations"], run["truth_translations"]
        if features_cache is None:
            features_cache = frame_features(sequence, timestamps, true_steps, true_shifts, CAMERAS["ros"])
        overlap, depth = features_cache
        omega = Rotation.from_matrix(steps @ np.transpose(true_steps, (0, 2, 1))).as_rotvec()
        error = np.concatenate([omega, shifts - true_shifts], axis=1)
        motion = np.concatenate([Rotation.from_matrix(true_steps).as_rotvec(), true_shifts], axis=1)
        one = np.ones((len(error), 1))
        lack, band = (1 - overlap)[:, None], (depth - depth.mean())[:, None]
        pull = np.hstack([motion, one])
        models = {
            "direction": (one, 6),
            "scale": (None, 2),  # one factor on the true rotation, one on the true translation: shared_scale
            "pull": (pull, 42),
            "+ overlap": (np.hstack([pull, lack, lack * motion]), 84),
            "+ depth": (np.hstack([pull, lack, lack * motion, band, band * motion]), 126),
        }
        name = Path(path).stem

        def ate(errors):
            turned = Rotation.from_rotvec(errors[:, :3]).as_matrix() @ true_steps
            return absolute_trajectory_error(compose(timestamps, turned, true_shifts + errors[:, 3:]),
                                             sequence.groundtruth).rmse

        print(f"| {name} | none (the run) | 0 | – | – | {ate(error):.4f} |")
        for model, (features, count) in models.items():
            if features is None:
                predicted, factors = shared_scale(error, motion, args.block)
                scales.append((name, factors))
            else:
                predicted = two_halves(features, error, args.block)
            explained = block_explained(error, predicted, args.block)
            print(f"| {name} | {model} | {count} | {explained[0]:.2f}, {explained[1]:.2f} | {ate(predicted):.4f} | "
                  f"{ate(error - predicted):.4f} |", flush=True)
        growth_rows.append((name, [window_errors(steps, shifts, true_steps, true_shifts, w) for w in WINDOWS]))
        lag_rows.append((name, [np.corrcoef(error[:-1, c], error[1:, c])[0, 1] for c in range(6)],
                         np.degrees(np.sqrt(np.mean(np.sum(error[:, :3] ** 2, axis=1)))),
                         1000 * np.sqrt(np.mean(np.sum(error[:, 3:] ** 2, axis=1)))))
    print()
    print("| run | " + " | ".join(f"W = {w}: RMS (°, mm)" for w in WINDOWS) + " |")
    print("|---|" + "---|" * len(WINDOWS))
    for name, values in growth_rows:
        print(f"| {name} | " + " | ".join(f"{r:.3f}, {t:.2f}" for r, t in values) + " |")
    print()
    print("| run | measured / true: rotation, translation fitted on the second half; the same fitted on the first |")
    print("|---|---|")
    for name, factors in scales:
        print(f"| {name} | {factors[0]:.3f}, {factors[1]:.3f}; {factors[2]:.3f}, {factors[3]:.3f} |")
    print()
    print("| run | one frame's error RMS (°, mm) | its lag-1 autocorrelation (ωx, ωy, ωz, δx, δy, δz) |")
    print("|---|---|---|")
    for name, lag, r, t in lag_rows:
        print(f"| {name} | {r:.3f}, {t:.2f} | {', '.join(f'{x:.2f}' for x in lag)} |")


def shared_scale(error, motion, block):
    """Out-of-fold predictions of one factor on the true rotation (all three coordinates) and one on the true
    translation, fitted on the blocks' sums of each half; and the measured / true factors of each half's fit
    (rotation, translation fitted on the second half, then on the first)."""
    n = len(error)
    halves = np.arange(n) >= n // 2
    predicted, factors = np.zeros_like(error), []
    for half in (False, True):
        train = np.flatnonzero(halves != half)
        train = train[:len(train) // block * block]
        for part in (slice(0, 3), slice(3, 6)):
            x = motion[train, part].reshape(-1, block, 3).sum(axis=1).ravel()
            y = error[train, part].reshape(-1, block, 3).sum(axis=1).ravel()
            predicted[halves == half, part] = motion[halves == half, part] * (x @ y / (x @ x))
            factors.append(1 + x @ y / (x @ x))
    return predicted, factors


if __name__ == "__main__":
    main()
