"""Odometry under fast rotation: real fr1/xyz frames turned about the optical centre at 110 °/s per axis
(``dgmm.odometry.synthetic.rotated_depth`` and ``write_spun_sequence``), the synthetic room under rotation-only
motion (``spinning_trajectory``), the fast schedule's EM start and D2D on the views' overlap
(``dgmm.odometry.overlap``).

References are independent of the code under test: the analytic depth of a plane seen from a turned camera,
closed-form cluster statistics of well-separated blobs, pixel coordinates chosen by the test, fr1/xyz's
motion-capture ground truth composed with the rotations the test applies itself, and the room's ray-cast ground
truth.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from threadpoolctl import threadpool_limits

from dgmm.odometry import (CAMERAS, first_frames, groundtruth_at_frames, pixel_primitives, read_sequence,
                           run_odometry)
from dgmm.odometry.em_start import lloyd_start
from dgmm.odometry.frame_model import REG_COVAR, SCHEDULES, _fit_mixture
from dgmm.odometry.schedule_studies import STUDY_SCHEDULES, schedule_named
from dgmm.odometry.measured_cut import register_cut_rounds, register_measured
from dgmm.odometry.overlap import register_d2d_overlap, seen_by
from dgmm.odometry.pixels import FR3
from dgmm.odometry.synthetic import (room_scene, rotated_depth, spin, spinning_trajectory, write_spun_sequence,
                                     write_synthetic_sequence)
from dgmm.odometry.tum import DEPTH_SCALE
from dgmm.primitives import Primitives
from dgmm.registration import register_d2d, rotation_distance_deg
from tests.test_odometry_metrics import FR1_XYZ, needs_fr1

ROS = CAMERAS["ros"]
PEAK_DEG_S = 110.0
"""Peak rate about each camera axis: with fr1/xyz's own motion, 1.5-6.5° between frames (30 Hz)."""
MAX_DEG, MAX_M = 2.0, 0.03
"""A frame-to-frame registration further off than this is a gross failure."""


def relative_error(registration, truth_rotation, truth_translation):
    """Rotation (deg) and translation (m) error of a registration against the true motion."""
    return (rotation_distance_deg(registration.rotation, truth_rotation),
            float(np.linalg.norm(registration.translation - truth_translation)))


# ------------------------------------------------------------------------------------------ turned depth
def test_rotated_depth_is_the_plane_seen_by_the_turned_camera():
    """A tilted plane ``n·X = d``: the turned camera sees depth ``d / (n'·ray)`` with ``n' = Rᵀ n``. The nearest old
    pixel is at most half a pixel diagonal off the turned ray (1.4e-3 rad), which moves the depth on this plane by
    less than 0.1%; pixels whose ray leaves the old view are 0."""
    normal = np.array([0.25, -0.2, 1.0]) / np.linalg.norm([0.25, -0.2, 1.0])
    rays = ROS.rays()
    depth = (1.6 / (rays @ normal)).reshape(ROS.height, ROS.width)
    turn = Rotation.from_euler("xyz", [3.0, -4.0, 2.0], degrees=True).as_matrix()
    turned = rotated_depth(depth, turn, ROS).ravel()
    expected = 1.6 / (rays @ (turn.T @ normal))
    seen = turned > 0
    assert 0.8 < seen.mean() < 0.99  # the turn pushes part of the view out of the old image
    np.testing.assert_allclose(turned[seen], expected[seen], rtol=1e-3)
    old = rays @ turn.T  # the turned rays in the old camera: outside its image -> no measurement
    u, v = ROS.fx * old[:, 0] / old[:, 2] + ROS.cx, ROS.fy * old[:, 1] / old[:, 2] + ROS.cy
    outside = (u < -0.5) | (u > ROS.width - 0.5) | (v < -0.5) | (v > ROS.height - 0.5)
    assert not np.any(seen & outside)
    wrong = 1.6 / (rays @ (turn @ normal))  # the test has power: the opposite turn does not match
    assert np.median(np.abs(turned[seen] / wrong[seen] - 1)) > 0.01


# --------------------------------------------------------------------------------------- the fast start
@pytest.mark.parametrize("variant", ["textbook", "authors"])
def test_fast_start_finds_separated_blobs(variant):
    """Three far-apart blobs of primitives with sizes and covariances, K=3: whatever the seeds, Lloyd's iterations
    end on the blobs, and the start is each blob's closed-form statistics under the variant's M-step weights
    (textbook: sizes; authors: one per primitive)."""
    rng = np.random.default_rng(0)
    centres = np.array([[0.0, 0, 2], [1.0, 0, 2], [0, 1.0, 3]])
    counts = [300, 500, 200]
    means = np.concatenate([c + 0.05 * rng.normal(size=(n, 3)) for c, n in zip(centres, counts)])
    covariances = np.einsum("n,ij->nij", rng.uniform(1e-5, 4e-5, len(means)), np.eye(3))
    sizes = rng.uniform(0.5, 2.0, len(means))
    prims = Primitives(means, covariances, sizes)
    weights, start_means, precisions = lloyd_start(prims, 3, 64, 5, variant, np.random.default_rng(1), REG_COVAR)
    blob = np.repeat(np.arange(3), counts)
    m_weights = sizes if variant == "textbook" else np.ones(len(means))
    order = np.argsort(start_means[:, 0] + 10 * start_means[:, 2])  # blobs 0, 1, 2 by x then z
    for component, b in zip(order, range(3)):
        w = m_weights[blob == b]
        x = means[blob == b]
        mean = w @ x / w.sum()
        spread = ((x - mean).T * w) @ (x - mean) / w.sum()
        covariance = spread + np.einsum("n,nij->ij", w, covariances[blob == b]) / w.sum() + REG_COVAR * np.eye(3)
        assert weights[component] == pytest.approx(w.sum() / m_weights.sum(), rel=1e-12)
        np.testing.assert_allclose(start_means[component], mean, rtol=1e-12)
        np.testing.assert_allclose(np.linalg.inv(precisions[component]), covariance, rtol=1e-9)


# ------------------------------------------------------------------------------------------- fast rotation
@needs_fr1
def test_gauss_newton_d2d_holds_where_bfgs_jumps_out_of_the_basin():
    """fr1/xyz frames 28 and 29 turned as frames 28, 29 of a 110 °/s spin (seed 1): the true motion is 5.1°. The
    fast schedule's mixtures (both EMs) register within 2° and 3 cm with Gauss-Newton D2D. The paper's BFGS from the
    identity, on the same textbook mixtures, is led by the gradient's translation part: its first step moves the
    pose by tens of centimetres and it ends in another basin (the case has power)."""
    sequence = read_sequence(FR1_XYZ)
    frames, truth = first_frames(sequence, 60)
    turns = spin(sequence.depth_timestamps[frames], PEAK_DEG_S, seed=1)
    poses = [(truth.rotations[i] @ turns[i], truth.translations[i]) for i in (28, 29)]
    truth_rotation = poses[0][0].T @ poses[1][0]
    truth_translation = poses[0][0].T @ (poses[1][1] - poses[0][1])
    # As write_spun_sequence stores them: 16-bit PNG depth, 1/5000 m.
    prims = [pixel_primitives(np.rint(rotated_depth(sequence.depth(i), turns[i], ROS) * DEPTH_SCALE) / DEPTH_SCALE,
                              ROS) for i in (28, 29)]
    schedule = STUDY_SCHEDULES["fast"]
    with threadpool_limits(1):
        for variant in ("textbook", "authors"):
            options = dict(schedule=schedule, n_components=100, variant=variant, warm_iter=None)
            fixed, moving = (_fit_mixture(p, np.random.default_rng([0, i]), None, options)
                             for p, i in zip(prims, (28, 29)))
            degrees, metres = relative_error(register_d2d(fixed, moving, solver="gauss-newton"), truth_rotation,
                                             truth_translation)
            print(f"\n{variant}: Gauss-Newton {degrees:.2f}° {100 * metres:.2f} cm", end="")
            assert degrees < MAX_DEG and metres < MAX_M
            if variant == "textbook":
                bfgs = relative_error(register_d2d(fixed, moving, solver="bfgs"), truth_rotation, truth_translation)
                print(f"; BFGS {bfgs[0]:.2f}° {100 * bfgs[1]:.2f} cm", end="")
                assert bfgs[0] > MAX_DEG or bfgs[1] > MAX_M


@needs_fr1
@pytest.mark.slow
@pytest.mark.parametrize("start, seed", [(0, 1), (300, 2), (600, 3)])
def test_no_gross_failure_on_spun_fr1_xyz(tmp_path, start, seed):
    """Two seconds of fr1/xyz from three places, spun at 110 °/s per axis: every frame-to-frame registration of
    gmm-pixels with the sweep's schedule is within 2° and 3 cm of the truth, with either EM."""
    sequence = write_spun_sequence(tmp_path / "spun", read_sequence(FR1_XYZ), np.arange(start, start + 60),
                                   PEAK_DEG_S, seed, ROS)
    _, truth = groundtruth_at_frames(sequence)
    for variant in ("textbook", "authors"):
        with threadpool_limits(1):
            result = run_odometry(sequence, "gmm-pixels", intrinsics=ROS, variant=variant)
        estimate = result.trajectory
        errors = np.array([relative_error(
            registration, truth.rotations[i].T @ truth.rotations[i + 1],
            truth.rotations[i].T @ (truth.translations[i + 1] - truth.translations[i]))
            for i, registration in enumerate(result.registrations)])
        steps = [rotation_distance_deg(truth.rotations[i].T @ truth.rotations[i + 1], np.eye(3))
                 for i in range(len(estimate) - 1)]
        print(f"\n{variant}: true steps up to {max(steps):.1f}°, worst error {errors[:, 0].max():.2f}° "
              f"{100 * errors[:, 1].max():.2f} cm", end="")
        assert max(steps) > 4.0
        assert errors[:, 0].max() < MAX_DEG and errors[:, 1].max() < MAX_M


# ------------------------------------------------------------------------------------------ the overlap
def test_seen_by_is_the_other_cameras_image():
    """Points placed by the test at chosen pixels and depths of a second camera (turned 20° about y and moved
    0.3 m): those at pixels inside its image and in front are seen, those half a pixel past an edge or behind
    it are not."""
    turn = Rotation.from_euler("y", 20, degrees=True).as_matrix()
    shift = np.array([0.3, -0.1, 0.2])  # x_other = turn @ x + shift
    pixels = np.array([[0.0, 0.0], [FR3.width - 0.6, FR3.height - 0.6], [320.0, 240.0], [-0.6, 100.0],
                       [100.0, FR3.height - 0.4], [FR3.width - 0.4, 10.0], [320.0, 240.0]])
    depths = np.array([1.0, 2.5, 4.0, 1.5, 3.0, 2.0, -2.0])
    in_other = np.column_stack([(pixels[:, 0] - FR3.cx) / FR3.fx, (pixels[:, 1] - FR3.cy) / FR3.fy,
                                np.ones(len(pixels))]) * depths[:, None]
    points = (in_other - shift) @ turn  # back into the first camera: x = turnᵀ (x_other - shift)
    np.testing.assert_array_equal(seen_by(points, turn, shift, FR3), [True, True, True, False, False, False, False])


def _spinning_room(folder, scene, n_frames):
    """The room with the bunny, the camera standing 2.4 m from the table and shaken at 110 °/s per axis (seed 0:
    the first frames are the same whatever ``n_frames``)."""
    with threadpool_limits(1):
        return write_synthetic_sequence(folder, scene, n_frames=n_frames, seed=0,
                                        path=lambda n, seed: spinning_trajectory(n, seed=seed, peak_deg_s=PEAK_DEG_S))


def _frame_errors(sequence, schedule, variant):
    """Every frame-to-frame registration's (deg, m) error against the rendered ground truth."""
    _, truth = groundtruth_at_frames(sequence)
    with threadpool_limits(1):
        result = run_odometry(sequence, "gmm-pixels", intrinsics=FR3, schedule=schedule, variant=variant)
    return np.array([relative_error(
        registration, truth.rotations[i].T @ truth.rotations[i + 1],
        truth.rotations[i].T @ (truth.translations[i + 1] - truth.translations[i]))
        for i, registration in enumerate(result.registrations)])


@pytest.mark.parametrize("variant", ["textbook", "authors"])
def test_registration_on_the_common_view_holds_where_whole_mixtures_slide(bunny_res4, tmp_path, variant):
    """The spinning room's first two frames (true motion 3.9°, no translation): D2D of the whole mixtures slides
    one frame's tiling of the walls along the other's (more than 3 cm off, the case has power). Within 2° and 3 cm
    of the rendered truth: the sweep's ``overlap`` (the components each camera sees, widened, then up to three
    rounds on the primitives each frame measures of the other; one round leaves it 6.5 cm off with textbook EM) and
    ``common-view`` (the overlap coarse to fine, then both frames refitted twice on their common view)."""
    sequence = _spinning_room(tmp_path / "spin", room_scene([bunny_res4.triangles]), 2)
    whole = _frame_errors(sequence, STUDY_SCHEDULES["fast"], variant)[0]
    print(f"\n{variant}: whole mixtures {whole[0]:.2f}° {100 * whole[1]:.2f} cm", end="")
    assert whole[0] > MAX_DEG or whole[1] > MAX_M
    for name in ("overlap", "common-view"):
        degrees, metres = _frame_errors(sequence, schedule_named(name), variant)[0]
        print(f", {name} {degrees:.2f}° {100 * metres:.2f} cm", end="")
        assert degrees < MAX_DEG and metres < MAX_M


def test_cut_rounds_stop_once_a_round_moves_the_pose_by_less_than_tol(bunny_res4, tmp_path):
    """The spinning room's first pair under ``overlap`` (its widened overlap round ends centimetres off, so the
    rounds have work to do): each round is :func:`register_measured` from the pose before, and the rounds stop
    after the first whose moving-mixture centroid moves by less than ``tol`` RMS radii and whose rotation moves by
    less than ``tol`` radians, both measured here from the poses themselves (scipy's rotation angle)."""
    sequence = _spinning_room(tmp_path / "spin", room_scene([bunny_res4.triangles]), 2)
    frames = []
    with threadpool_limits(1):
        run_odometry(sequence, "gmm-pixels", intrinsics=FR3, callback=lambda frame: frames.append(frame.model))
        fixed, moving = frames
        schedule = SCHEDULES["overlap"]
        first = register_d2d_overlap(fixed, moving, FR3, schedule.overlap_rounds, schedule.overlap_scales)
        poses = [first]
        for _ in range(4):
            poses.append(register_measured(fixed, moving, poses[-1]))
        weights, means = moving.weights_, moving.means_
        centroid = weights @ means
        radius = np.sqrt(weights @ np.sum((means - centroid) ** 2, axis=1))
        changes = [max(np.linalg.norm(after.rotation @ centroid + after.translation
                                      - before.rotation @ centroid - before.translation) / radius,
                       Rotation.from_matrix(after.rotation @ before.rotation.T).magnitude())
                   for before, after in zip(poses, poses[1:])]
        assert changes[0] > 0.01 and changes[0] > changes[1] > changes[2] > changes[3]  # each round leaves less
        for stop in (1, 2, 3):  # a tol just above round `stop`'s change, then just below it
            registration = register_cut_rounds(fixed, moving, first, 4, 1.01 * changes[stop - 1])
            np.testing.assert_array_equal(registration.translation, poses[stop].translation)
            registration = register_cut_rounds(fixed, moving, first, 4, 0.99 * changes[stop - 1])
            np.testing.assert_array_equal(registration.translation, poses[stop + 1].translation)
        registration = register_cut_rounds(fixed, moving, first, 2, 0.0)  # never settled: every round runs
        np.testing.assert_array_equal(registration.rotation, poses[2].rotation)


@pytest.mark.slow
def test_no_gross_failure_on_the_spinning_room(bunny_res4, tmp_path):
    """40 frames of the spinning room (true steps up to 7.3°): with the sweep's schedule (``overlap``) every
    frame-to-frame registration is within 2° and 3 cm of the rendered truth, with either EM; with the fast schedule
    some are not (walls 3-4.5 m away fill most of the view, and a tenth of it changes per frame)."""
    sequence = _spinning_room(tmp_path / "spin", room_scene([bunny_res4.triangles]), 40)
    for variant in ("textbook", "authors"):
        errors = _frame_errors(sequence, SCHEDULES["overlap"], variant)
        plain = _frame_errors(sequence, STUDY_SCHEDULES["fast"], variant)
        print(f"\n{variant}: overlap worst {errors[:, 0].max():.2f}° {100 * errors[:, 1].max():.2f} cm; fast: "
              f"{np.sum((plain[:, 0] > MAX_DEG) | (plain[:, 1] > MAX_M))} frames off", end="")
        assert errors[:, 0].max() < MAX_DEG and errors[:, 1].max() < MAX_M
        assert plain[:, 0].max() > MAX_DEG or plain[:, 1].max() > MAX_M
