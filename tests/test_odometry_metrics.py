"""Trajectory metrics (ATE, RPE) against evo on the real fr1/xyz files, and the per-camera intrinsics.

References are independent of the code under test: evo's APE and RPE (its own association, alignment, SE(3)
algebra and pair selection) on TUM files written here, TUM's published calibration table for the cameras.
"""
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from dgmm.errors import InputError
from dgmm.odometry.pixels import CAMERAS, parse_intrinsics, sequence_intrinsics
from dgmm.odometry.metrics import absolute_trajectory_error, relative_pose_error
from dgmm.odometry.tum import Trajectory, read_sequence, read_trajectory, write_trajectory

FR1_XYZ = Path(__file__).resolve().parents[2] / "shared" / "data" / "tum" / "rgbd_dataset_freiburg1_xyz"
needs_fr1 = pytest.mark.skipif(not (FR1_XYZ / "groundtruth.txt").is_file(), reason=f"{FR1_XYZ} is not mirrored")


def drifting_estimate(sequence, n_frames, seed):
    """Ground truth at the first depth frames, in another world frame, with random-walk drift in both parts."""
    frames, truth = sequence.groundtruth_at_frames()
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
