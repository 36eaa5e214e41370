"""Trajectory metrics (ATE, RPE) against evo on the real fr1/xyz files, and the per-camera intrinsics.

References are independent of the code under test: evo's APE and RPE (its own association, alignment, SE(3)
algebra and pair selection) on TUM files written here, TUM's published calibration table for the cameras.
"""
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from dgmm.errors import InputError
from dgmm.odometry import groundtruth_at_frames
from dgmm.odometry.pixels import CAMERAS, parse_intrinsics, sequence_intrinsics
from dgmm.odometry.metrics import absolute_trajectory_error, drift_metrics, frame_motions, relative_pose_error
from dgmm.odometry.tum import Trajectory, read_sequence, read_trajectory, write_trajectory

FR1_XYZ = Path(__file__).resolve().parents[2] / "shared" / "data" / "tum" / "rgbd_dataset_freiburg1_xyz"
needs_fr1 = pytest.mark.skipif(not (FR1_XYZ / "groundtruth.txt").is_file(), reason=f"{FR1_XYZ} is not mirrored")


def drifting_estimate(sequence, n_frames, seed):
    """Ground truth at the first depth frames, in another world frame, with random-walk drift in both parts."""
    frames, truth = groundtruth_at_frames(sequence)
    truth = truth.subset(np.arange(min(n_frames, len(frames))))
    rng = np.random.default_rng(seed)
    drift = Rotation.from_rotvec(np.cumsum(rng.normal(scale=0.004, size=(len(truth), 3)), axis=0)).as_matrix()
    frame = Rotation.from_rotvec([0.2, -0.4, 0.9]).as_matrix()
    rotations = frame @ truth.rotations @ drift
    translations = (truth.translations + np.cumsum(rng.normal(scale=0.002, size=(len(truth), 3)), axis=0)) @ frame.T
    return Trajectory(truth.timestamps, rotations, translations + [0.5, -1.0, 2.0])


@needs_fr1
@pytest.mark.parametrize("n_frames", [798, 100])
def test_ate_and_rpe_equal_evo_on_fr1_xyz_files(tmp_path, n_frames):
    from evo.core import metrics, sync
    from evo.tools import file_interface

    sequence = read_sequence(FR1_XYZ)
    write_trajectory(tmp_path / "est.txt", drifting_estimate(sequence, n_frames, seed=n_frames))
    estimate, groundtruth = read_trajectory(tmp_path / "est.txt"), sequence.groundtruth
    ate, rpe = absolute_trajectory_error(estimate, groundtruth), relative_pose_error(estimate, groundtruth)
    # fr1/xyz's depth runs at about 30 Hz: the window is the frame count nearest one second.
    assert abs(rpe.delta * np.median(np.diff(estimate.timestamps)) - 1.0) < 0.02 and 29 <= rpe.delta <= 32

    ref, est = sync.associate_trajectories(file_interface.read_tum_trajectory_file(FR1_XYZ / "groundtruth.txt"),
                                           file_interface.read_tum_trajectory_file(tmp_path / "est.txt"),
                                           max_diff=0.02)
    evo = {}
    for relation in (metrics.PoseRelation.translation_part, metrics.PoseRelation.rotation_angle_deg):
        rpe_metric = metrics.RPE(relation, delta=rpe.delta, delta_unit=metrics.Unit.frames, all_pairs=True)
        rpe_metric.process_data((ref, est))
        evo[relation] = rpe_metric.get_statistic(metrics.StatisticsType.rmse)
        assert len(rpe_metric.error) == rpe.n_pairs
    est.align(ref, correct_scale=False)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((ref, est))
    assert ate.rmse == pytest.approx(ape.get_statistic(metrics.StatisticsType.rmse), rel=1e-9)
    assert rpe.translation_rmse > 0.005 and rpe.rotation_rmse_deg > 0.5  # the drift is visible
    assert rpe.translation_rmse == pytest.approx(evo[metrics.PoseRelation.translation_part], rel=1e-9)
    assert rpe.rotation_rmse_deg == pytest.approx(evo[metrics.PoseRelation.rotation_angle_deg], rel=1e-9)


def test_rpe_of_the_ground_truth_itself_is_zero_and_too_short_runs_are_refused():
    stamps = 100 + np.arange(60) / 30
    rotations = Rotation.from_rotvec(np.outer(np.arange(60), [0.0, 0.02, 0.01])).as_matrix()
    truth = Trajectory(stamps, rotations, np.outer(np.arange(60), [0.01, 0.0, 0.003]))
    rpe = relative_pose_error(truth, truth)
    assert rpe.delta == 30 and rpe.n_pairs == 30
    assert rpe.translation_rmse < 1e-12 and rpe.rotation_rmse_deg < 1e-6
    with pytest.raises(InputError, match="RPE needs more than one"):
        relative_pose_error(truth.subset(np.arange(25)), truth)


def test_tum_camera_table_and_sequence_names():
    # TUM's "Intrinsic Camera Calibration of the Kinect" table (depth = rgb after registration).
    assert (CAMERAS["fr1"].fx, CAMERAS["fr1"].fy, CAMERAS["fr1"].cx, CAMERAS["fr1"].cy) == (517.3, 516.5, 318.6, 255.3)
    assert (CAMERAS["fr2"].fx, CAMERAS["fr2"].fy, CAMERAS["fr2"].cx, CAMERAS["fr2"].cy) == (520.9, 521.0, 325.1, 249.7)
    assert (CAMERAS["fr3"].fx, CAMERAS["fr3"].fy, CAMERAS["fr3"].cx, CAMERAS["fr3"].cy) == (535.4, 539.2, 320.1, 247.6)
    assert (CAMERAS["ros"].fx, CAMERAS["ros"].fy, CAMERAS["ros"].cx, CAMERAS["ros"].cy) == (525.0, 525.0, 319.5, 239.5)
    assert sequence_intrinsics("rgbd_dataset_freiburg1_xyz") == "ros"
    assert sequence_intrinsics("rgbd_dataset_freiburg2_desk") == "ros"
    assert sequence_intrinsics("rgbd_dataset_freiburg3_long_office_household") == "fr3"
    with pytest.raises(InputError, match="my_room"):
        sequence_intrinsics("my_room")
    assert parse_intrinsics("fr1") is CAMERAS["fr1"]
    custom = parse_intrinsics("500,501.5,320,240")
    assert (custom.fx, custom.fy, custom.cx, custom.cy, custom.width, custom.height) == (500, 501.5, 320, 240, 640, 480)
    for bad in ("fr4", "1,2,3", "0,500,320,240", "a,b,c,d"):
        with pytest.raises(InputError, match="intrinsics"):
            parse_intrinsics(bad)


# ------------------------------------------------------------------------------------- hand-made trajectories
def square_path(n=40, dt=1 / 30):
    """A camera circling the corners of a 1 m square in the xy-plane, turning as it goes: (timestamps, R, t)."""
    angles = np.linspace(0, 2 * np.pi, n, endpoint=False)
    translations = np.column_stack([np.cos(angles), np.sin(angles), 0.1 * np.sin(3 * angles)])
    rotations = Rotation.from_rotvec(np.outer(angles, [0.0, 0.0, 1.0])).as_matrix()
    return 50.0 + dt * np.arange(n), rotations, translations


def test_ate_aligns_a_rigidly_moved_copy_exactly_and_scores_a_scaled_one_in_closed_form():
    """A copy moved by a known rigid transform has ATE 0 and the inverse transform as its alignment (a translation-
    only alignment leaves 1.1 m, an alignment applied the wrong way round 4.0 m). A copy scaled by 1.2 about its
    centroid aligns by the identity (the cross-covariance is symmetric positive definite) and scores 0.2 times the
    positions' RMS spread (an alignment with a scale would score 0)."""
    stamps, rotations, translations = square_path()
    truth = Trajectory(stamps, rotations, translations)
    moved_by = Rotation.from_rotvec([0.3, -0.5, 1.1]).as_matrix()
    offset = np.array([2.0, -1.0, 0.5])
    moved = Trajectory(stamps, moved_by @ rotations, translations @ moved_by.T + offset)
    ate = absolute_trajectory_error(moved, truth)
    assert ate.rmse < 1e-12
    np.testing.assert_allclose(ate.rotation, moved_by.T, atol=1e-12)
    np.testing.assert_allclose(ate.translation, -moved_by.T @ offset, atol=1e-12)

    centroid = translations.mean(axis=0)
    scaled = Trajectory(stamps, rotations, centroid + 1.2 * (translations - centroid))
    ate = absolute_trajectory_error(scaled, truth)
    spread = np.sqrt(np.mean(np.sum((translations - centroid) ** 2, axis=1)))
    np.testing.assert_allclose(ate.rotation, np.eye(3), atol=1e-12)
    assert ate.rmse == pytest.approx(0.2 * spread, rel=1e-12)
    np.testing.assert_allclose(ate.errors, 0.2 * np.linalg.norm(translations - centroid, axis=1), rtol=1e-12)


def test_ate_refuses_fewer_than_three_paired_poses():
    stamps, rotations, translations = square_path(n=10)
    truth = Trajectory(stamps, rotations, translations)
    late = Trajectory(stamps[[0, 1, 2]] + np.array([0.0, 0.0, 0.5]), rotations[:3], translations[:3])
    with pytest.raises(InputError, match="only 2 estimated poses have a ground-truth pose within 0.02 s"):
        absolute_trajectory_error(late, truth)


def test_rpe_window_is_the_rounded_frame_count_and_measures_drift_per_second():
    """Frames every 1/9.6 s: a 1 s window is round(9.6) = 10 frames (floor would give 9). An estimate that adds a
    constant velocity v and a constant turn rate w to a still ground truth drifts by |v| 10/9.6 m and w 10/9.6 rad
    per window, in every window."""
    n, dt = 40, 1 / 9.6
    stamps = 10.0 + dt * np.arange(n)
    velocity, turn_rate = np.array([0.03, -0.04, 0.0]), 0.05  # m/s, rad/s about z
    truth = Trajectory(stamps, np.broadcast_to(np.eye(3), (n, 3, 3)), np.zeros((n, 3)))
    drifting = Trajectory(stamps, Rotation.from_rotvec(np.outer(dt * np.arange(n), [0, 0, turn_rate])).as_matrix(),
                          np.outer(dt * np.arange(n), velocity))
    rpe = relative_pose_error(drifting, truth)
    assert rpe.delta == 10 and rpe.n_pairs == n - 10
    # E_i = P_i⁻¹ P_{i+Δ}: its translation is R_iᵀ v Δ dt, of length |v| Δ dt (R_i turns about z, v lies in xy).
    assert rpe.translation_rmse == pytest.approx(np.linalg.norm(velocity) * 10 * dt, rel=1e-12)
    assert rpe.rotation_rmse_deg == pytest.approx(np.degrees(turn_rate * 10 * dt), rel=1e-9)


def test_drift_metrics_fall_back_to_no_rpe_below_one_window():
    """8 frames at 30 Hz span 0.23 s: the ATE is reported, the RPE entries are None (not an error, not zeros)."""
    stamps, rotations, translations = square_path(n=40)
    truth = Trajectory(stamps, rotations, translations)
    short = truth.subset(np.arange(8))
    metrics = drift_metrics(Trajectory(short.timestamps, short.rotations, 1.1 * short.translations), truth)
    assert metrics["ate_rmse_m"] > 0
    assert metrics["rpe_translation_m_s"] is None and metrics["rpe_rotation_deg_s"] is None
    full = drift_metrics(Trajectory(stamps, rotations, 1.1 * translations), truth)
    assert full["rpe_translation_m_s"] > 0 and full["rpe_rotation_deg_s"] < 1e-6


class _HandMadeSequence:
    """Just what ``run_odometry`` reads of a sequence (``dgmm.odometry.sequence.DepthSequence``): frame count,
    depth images (filled with the frame index, so the stand-in method below knows which frame it sees),
    timestamps."""

    def __init__(self, n_frames, intrinsics):
        self.depth_timestamps = 1.0 + np.arange(n_frames) / 30
        self._shape = (intrinsics.height, intrinsics.width)

    def __len__(self):
        return len(self.depth_timestamps)

    def depth_frames(self, indices):
        return (np.full(self._shape, float(index)) for index in indices)

    def frame_source(self, index):
        return f"frame {index}"


def test_odometry_composes_relative_poses_in_order(monkeypatch):
    """A stand-in method registers frame k+1 onto frame k by the exact relative pose ``T_k⁻¹ T_{k+1}`` of a
    hand-made trajectory of large turns; the loop must return ``T_0⁻¹ T_k`` for every frame. Composing the other
    way round (``T_rel T_k``), or rotating the relative translation by the new rotation, fails (tried)."""
    from dgmm.odometry import loop
    from dgmm.odometry.pixels import FR3
    from dgmm.registration import Registration

    rng = np.random.default_rng(4)
    n = 6
    rotations = Rotation.random(n, random_state=5).as_matrix()
    translations = rng.normal(size=(n, 3))

    def prepare(depth, intrinsics, rng, previous, options):
        return int(depth[0, 0])

    def register(fixed, moving, options):
        relative_rotation = rotations[fixed].T @ rotations[moving]
        relative_translation = rotations[fixed].T @ (translations[moving] - translations[fixed])
        return Registration(relative_rotation, relative_translation, 1, 0.0, 0.0, True, "stand-in")

    monkeypatch.setitem(loop.METHODS, "stand-in", (prepare, register))
    result = loop.run_odometry(_HandMadeSequence(n, FR3), "stand-in", intrinsics=FR3)
    expected_rotations = rotations[0].T @ rotations
    expected_translations = (translations - translations[0]) @ rotations[0]
    np.testing.assert_allclose(result.trajectory.rotations, expected_rotations, atol=1e-12)
    np.testing.assert_allclose(result.trajectory.translations, expected_translations, atol=1e-12)
    np.testing.assert_allclose(result.trajectory.timestamps, 1.0 + np.arange(n) / 30)


def test_frame_motions_are_the_motions_a_trajectory_was_composed_from():
    """A trajectory composed here from random motions, one frame at a time (``T_{k+1} = T_k M_k``), gives back
    those motions."""
    rng = np.random.default_rng(3)
    steps = Rotation.random(6, random_state=rng).as_matrix()
    shifts = rng.normal(size=(6, 3))
    rotations, translations = [Rotation.random(random_state=rng).as_matrix()], [rng.normal(size=3)]
    for step, shift in zip(steps, shifts):
        translations.append(rotations[-1] @ shift + translations[-1])
        rotations.append(rotations[-1] @ step)
    trajectory = Trajectory(np.arange(7.0), np.array(rotations), np.array(translations))
    got_rotations, got_translations = frame_motions(trajectory)
    np.testing.assert_allclose(got_rotations, steps, atol=1e-12)
    np.testing.assert_allclose(got_translations, shifts, atol=1e-12)
