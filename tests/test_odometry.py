"""Visual odometry (paper §V): TUM I/O, back-projection, the synthetic sequence, odometry and ATE.

References are independent of the code under test: evo's APE for the ATE, scipy's scalar-last quaternions for the
TUM column order, Pillow for the PNG bit depth, plane geometry for back-projection, brute-force nearest stamps
for association, and the scene itself (exact ray casts along arbitrary rays) for the synthetic ground truth.
"""
import numpy as np
import pytest
from PIL import Image
from scipy.spatial.transform import Rotation
from threadpoolctl import threadpool_limits

from dgmm.errors import DataError
from dgmm.odometry import groundtruth_at_frames, odometry_runs, run_odometry
from dgmm.odometry.pixels import FR3, backproject, pixel_primitives
from dgmm.odometry.metrics import absolute_trajectory_error
from dgmm.odometry.tum import (DEPTH_SCALE, Trajectory, associate, read_depth, read_sequence, read_trajectory,
                               write_depth, write_trajectory)
from dgmm.odometry.synthetic import _nearest_hits, handheld_trajectory, room_scene, write_synthetic_sequence
from tests.test_odometry_metrics import FR1_XYZ, needs_fr1

N_FRAMES = 16


@pytest.fixture(scope="module")
def scene(bunny_res4):
    return room_scene([bunny_res4.triangles])


@pytest.fixture(scope="module")
def sequence(scene, tmp_path_factory):
    """A short synthetic sequence (16 frames, 0.5 s) with the bunny on the table."""
    with threadpool_limits(1):
        return write_synthetic_sequence(tmp_path_factory.mktemp("tum") / "seq", scene, n_frames=N_FRAMES, seed=3)


def _noise_sigma(z):
    """Nguyen et al. 2012 axial noise, the model the generator claims to use."""
    return 0.0012 + 0.0019 * (z - 0.4) ** 2


# ------------------------------------------------------------------------------------------------- TUM I/O
def test_trajectory_round_trip_and_tum_quaternion_order(tmp_path):
    rng = np.random.default_rng(0)
    rotations = Rotation.random(20, random_state=1)
    trajectory = Trajectory(1341847980.0 + np.arange(20) / 30, rotations.as_matrix(), rng.normal(size=(20, 3)))
    path = tmp_path / "traj.txt"
    write_trajectory(path, trajectory)
    rows = np.loadtxt(path, comments="#")
    # TUM columns: timestamp tx ty tz qx qy qz qw (scalar last, scipy's own order), up to the quaternion sign.
    expected = rotations.as_quat()
    signs = np.sign(np.sum(rows[:, 4:] * expected, axis=1))
    np.testing.assert_allclose(rows[:, 4:], expected * signs[:, None], atol=1e-8)
    np.testing.assert_allclose(rows[:, 1:4], trajectory.translations, atol=1e-8)
    back = read_trajectory(path)
    np.testing.assert_allclose(back.timestamps, trajectory.timestamps, rtol=0, atol=1e-6)
    np.testing.assert_allclose(back.rotations, trajectory.rotations, atol=1e-8)
    np.testing.assert_allclose(back.translations, trajectory.translations, atol=1e-8)


def test_associate_matches_brute_force_nearest():
    first = np.array([0.0, 0.1, 0.2, 0.5])
    second = np.array([0.005, 0.099, 0.12, 0.215, 0.9])
    i, j = associate(first, second)
    assert i.tolist() == [0, 1, 2] and j.tolist() == [0, 1, 3]
    rng = np.random.default_rng(2)
    first, second = np.sort(rng.uniform(0, 10, 300)), np.sort(rng.uniform(0, 10, 1000))
    gaps = np.abs(first[:, None] - second[None])
    expected = np.flatnonzero(gaps.min(axis=1) < 0.02)
    i, j = associate(first, second)
    assert i.tolist() == expected.tolist()
    assert j.tolist() == gaps[expected].argmin(axis=1).tolist()


def test_depth_png_is_16_bit_scaled_by_5000(tmp_path):
    depth = np.zeros((FR3.height, FR3.width))
    depth[0, :4] = [0.0002, 1.0, 5.0002, 65535 / DEPTH_SCALE]  # raw 1, 5000, 25001, 65535: beyond 8 bits
    write_depth(tmp_path / "d.png", depth)
    with Image.open(tmp_path / "d.png") as image:
        assert image.mode == "I;16" and image.size == (FR3.width, FR3.height)
        raw = np.asarray(image)
    assert raw[0, :4].tolist() == [1, 5000, 25001, 65535]
    np.testing.assert_array_equal(read_depth(tmp_path / "d.png"), raw / 5000.0)


@pytest.mark.slow
def test_synthetic_sequence_round_trip(sequence):
    assert len(sequence) == N_FRAMES
    listed = np.array([line.split() for line in (sequence.folder / "depth.txt").read_text().splitlines()
                       if not line.startswith("#")])
    assert [str(sequence.folder / name) for name in listed[:, 1]] == [str(path) for path in sequence.depth_files]
    np.testing.assert_array_equal(sequence.depth_timestamps, listed[:, 0].astype(float))
    # Ground truth at 100 Hz, depth at 30 Hz on average: every frame finds its exact ground-truth row.
    assert np.all(np.diff(sequence.groundtruth.timestamps) == pytest.approx(0.01, abs=1e-6))
    assert 1 / np.mean(np.diff(sequence.depth_timestamps)) == pytest.approx(30, rel=0.05)
    frames, poses = groundtruth_at_frames(sequence)
    assert frames.tolist() == list(range(N_FRAMES))
    nearest = np.abs(sequence.depth_timestamps[:, None] - sequence.groundtruth.timestamps[None]).argmin(axis=1)
    np.testing.assert_array_equal(poses.translations, sequence.groundtruth.translations[nearest])
    depth = sequence.depth(0)
    with Image.open(sequence.depth_files[0]) as image:
        assert image.mode == "I;16"
        np.testing.assert_array_equal(depth, np.asarray(image) / 5000.0)
    assert depth.shape == (480, 640) and 0.5 < np.mean(depth > 0) < 1.0


# ------------------------------------------------------------------------------------------- back-projection
def test_backprojection_of_a_plane_and_pixel_covariances():
    normal, offset = np.array([0.2, -0.3, 1.0]) / np.linalg.norm([0.2, -0.3, 1.0]), 1.8  # n·X = d
    v, u = np.mgrid[0:480, 0:640]
    rays = np.stack([(u - 320.1) / 535.4, (v - 247.6) / 539.2, np.ones_like(u, dtype=float)], axis=-1)
    depth = offset / (rays @ normal)
    depth[100:140, 200:260] = 0.0  # a hole
    points = backproject(depth)
    expected_count = 160 * 120 - (len(range(100, 140, 4)) * len(range(200, 260, 4)))
    assert points.shape == (expected_count, 3)
    np.testing.assert_allclose(points @ normal, offset, atol=1e-12)
    np.testing.assert_allclose(points[0], depth[0, 0] * np.array([-320.1 / 535.4, -247.6 / 539.2, 1.0]))

    # A fronto-parallel wall at Z = 2.5: neighbouring grid points are one pixel footprint apart.
    wall = np.full((480, 640), 2.5)
    grid = backproject(wall).reshape(120, 160, 3)
    step_x, step_y = grid[0, 1, 0] - grid[0, 0, 0], grid[1, 0, 1] - grid[0, 0, 1]
    prims = pixel_primitives(wall)
    expected = np.diag([step_x ** 2 / 12, step_y ** 2 / 12, 0.0])  # uniform on an interval of width w: w²/12
    np.testing.assert_allclose(prims.covariances, np.broadcast_to(expected, (19200, 3, 3)), rtol=1e-12, atol=0)
    np.testing.assert_allclose(prims.weights, step_x * step_y, rtol=1e-12)
    np.testing.assert_array_equal(pixel_primitives(wall, size="unit").weights, 1.0)
    np.testing.assert_array_equal(prims.means, grid.reshape(-1, 3))


# ------------------------------------------------------------------------------------------------ synthetic
@pytest.mark.slow
def test_synthetic_generator_is_deterministic(scene, tmp_path):
    with threadpool_limits(1):
        runs = [write_synthetic_sequence(tmp_path / name, scene, n_frames=3, seed=seed)
                for name, seed in (("a", 7), ("b", 7), ("c", 8))]
    files = sorted(path.relative_to(runs[0].folder) for path in runs[0].folder.rglob("*") if path.is_file())
    assert len(files) == 5  # depth.txt, groundtruth.txt, three PNGs
    for name in files:
        assert (runs[0].folder / name).read_bytes() == (runs[1].folder / name).read_bytes()
    assert (runs[0].folder / "groundtruth.txt").read_bytes() != (runs[2].folder / "groundtruth.txt").read_bytes()


@pytest.mark.slow
def test_synthetic_groundtruth_agrees_with_depth(sequence, scene):
    """Back-project frame j, move it into frame i by the ground-truth relative pose, and cast a ray from camera
    i through each point: the point lies on the scene surface that ray hits, up to the depth noise."""
    frames, poses = groundtruth_at_frames(sequence)
    i, j = 0, N_FRAMES - 1
    points_j = backproject(sequence.depth(j))
    r_i, t_i, r_j, t_j = poses.rotations[i], poses.translations[i], poses.rotations[j], poses.translations[j]

    def normalised_residuals(rotation, translation):
        in_i = points_j @ rotation.T + translation  # camera j -> camera i
        world_rays = in_i @ r_i.T
        surface, _ = _nearest_hits(world_rays, t_i, scene)  # hit at surface * ray, the ray ending at the point
        return (1.0 - surface) * in_i[:, 2] / _noise_sigma(in_i[:, 2])

    relative = (r_i.T @ r_j, r_i.T @ (t_j - t_i))
    residuals = normalised_residuals(*relative)
    # |N(0, 1)| has median 0.674; occluded points and 1/5000 m quantisation move it little.
    assert 0.55 < np.median(np.abs(residuals)) < 0.8
    assert np.mean(np.abs(residuals) < 4) > 0.97
    # The test has power: the inverse relative motion does not fit.
    wrong = normalised_residuals(relative[0].T, -relative[0].T @ relative[1])
    assert np.median(np.abs(wrong)) > 5


# ------------------------------------------------------------------------------------------------------ ATE
def test_ate_equals_evo(tmp_path):
    from evo.core import metrics, sync
    from evo.tools import file_interface

    reference = handheld_trajectory(300, seed=4)  # 3 s at 100 Hz
    rng = np.random.default_rng(5)
    rows = np.rint(np.arange(80) * 10 / 3).astype(int)
    # An estimate at 30 Hz, 3 ms after its ground truth, in another frame, with drift and noise.
    frame = Rotation.from_rotvec([0.3, -0.2, 1.0]).as_matrix()
    drift = np.cumsum(rng.normal(scale=0.004, size=(80, 3)), axis=0)
    estimate = Trajectory(reference.timestamps[rows] + 0.003, frame @ reference.rotations[rows],
                          (reference.translations[rows] + drift) @ frame.T + [1.0, 2.0, -0.5])
    write_trajectory(tmp_path / "gt.txt", reference)
    write_trajectory(tmp_path / "est.txt", estimate)

    ours = absolute_trajectory_error(read_trajectory(tmp_path / "est.txt"), read_trajectory(tmp_path / "gt.txt"))
    ref, est = sync.associate_trajectories(file_interface.read_tum_trajectory_file(tmp_path / "gt.txt"),
                                           file_interface.read_tum_trajectory_file(tmp_path / "est.txt"),
                                           max_diff=0.02)
    est.align(ref, correct_scale=False)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((ref, est))
    assert len(ours.errors) == 80
    assert ours.rmse > 0.01
    assert ours.rmse == pytest.approx(ape.get_statistic(metrics.StatisticsType.rmse), abs=1e-6)


# ------------------------------------------------------------------------------------------------- odometry
def positions_spread(translations):
    """RMS distance of positions from their centroid: the ATE of standing still, and ``|1 − s|`` times it the ATE of
    the trajectory scaled by ``s`` (after a rigid alignment, which for a scaled copy is the identity about the
    centroid: the cross-covariance ``s Σ (p − c)(p − c)ᵀ`` is symmetric positive semi-definite)."""
    return float(np.sqrt(np.mean(np.sum((translations - translations.mean(axis=0)) ** 2, axis=1))))


@pytest.mark.slow
@pytest.mark.parametrize("method, warm_iter, scale_error", [("gmm-pixels", None, 0.02), ("gmm-pixels", 5, 0.02),
                                                            ("gmm-points", None, 0.02), ("icp", None, 0.15)])
def test_odometry_on_synthetic_sequence(sequence, method, warm_iter, scale_error):
    """Frame-to-frame odometry over every other frame of the 16 (8 frames at 15 Hz, 0.5 s; halves the test time).

    Bound: the ATE of the ground truth scaled by ``1 − scale_error``, ``scale_error`` times the ATE of standing
    still (60 mm here): 1.2 mm for the GMMs (measured 0.47-0.76 mm), 9.0 mm for ICP on 2,500 random points per
    frame (5.5 mm). A method that gets the motion's length 15% (GMMs: 2%) wrong fails. (The former bound, 5% of
    the path, 9 mm, let a GMM odometry 15% short pass.)
    """
    frames = np.arange(0, N_FRAMES, 2)
    groundtruth = groundtruth_at_frames(sequence)[1].subset(frames)
    path_length = np.linalg.norm(np.diff(groundtruth.translations, axis=0), axis=1).sum()
    logged = []
    with threadpool_limits(1):
        result = run_odometry(sequence, method, frames, warm_iter=warm_iter, seed=0, callback=logged.append)
    error = absolute_trajectory_error(result.trajectory, sequence.groundtruth)
    standing_still = positions_spread(groundtruth.translations)
    print(f"\n{method} (warm_iter {warm_iter}): ATE RMSE {1000 * error.rmse:.2f} mm over {path_length:.3f} m "
          f"(standing still {1000 * standing_still:.1f} mm); per frame: model {result.prepare_seconds.mean():.3f} s, "
          f"registration {result.registration_seconds.mean():.3f} s")
    assert len(error.errors) == len(frames)
    assert error.rmse < scale_error * standing_still
    assert [frame.index for frame in logged] == frames.tolist()
    np.testing.assert_allclose(logged[-1].translation, result.trajectory.translations[-1])
    assert logged[0].registration is None and len(result.registration_seconds) == len(frames) - 1
    # A frame's registration time is all of its registration call (a schedule's cuts too), not only its solver's.
    assert np.all(result.registration_seconds > [registration.seconds for registration in result.registrations])
    assert [frame.registration_seconds for frame in logged[1:]] == result.registration_seconds.tolist()


# ---------------------------------------------------------------------------------------------- bad input
@pytest.mark.slow
def test_bad_input_names_the_file(sequence, tmp_path):
    with pytest.raises(DataError, match="missing_folder") as missing:
        read_sequence(tmp_path / "missing_folder")
    (tmp_path / "empty").mkdir()
    with pytest.raises(DataError, match="depth.txt") as no_listing:
        read_sequence(tmp_path / "empty")
    broken = tmp_path / "broken"
    (broken / "depth").mkdir(parents=True)
    (broken / "depth.txt").write_text("# timestamp filename\n1.0 depth/1.png\n2.0 depth/2.png\n")
    (broken / "depth" / "1.png").write_bytes(b"not a png at all")
    Image.fromarray(np.zeros((480, 640), dtype=np.uint8)).save(broken / "depth" / "2.png")
    broken_sequence = read_sequence(broken)
    assert broken_sequence.groundtruth is None
    with pytest.raises(DataError, match="1.png") as unreadable:
        broken_sequence.depth(0)
    with pytest.raises(DataError, match="2.png.*16-bit") as eight_bit:
        broken_sequence.depth(1)
    for caught in (missing, no_listing, unreadable, eight_bit):
        assert "\n" not in str(caught.value)


def test_warm_start_restarts_starved_components():
    """A component that lost its primitives restarts on the data (at a primitive, live median covariance, weight
    1/K); live components keep their parameters and the weights still sum to 1."""
    from types import SimpleNamespace

    from dgmm.odometry.frame_model import _warm_start
    from dgmm.primitives import Primitives

    covariances = np.stack([np.diag([1.0, 2.0, 3.0]), np.diag([2.0, 2.0, 2.0]), np.diag([1e-6, 1e-6, 1e-6])])
    mixture = SimpleNamespace(weights_=np.array([0.6, 0.4 - 1e-9, 1e-9]), means_=np.array([[0., 0, 0], [1, 1, 1],
                                                                                              [50, 50, 50]]),
                              covariances_=covariances)
    prims = Primitives.from_points(np.random.default_rng(0).normal(size=(30, 3)))
    weights, means, precisions = _warm_start(mixture, prims, np.random.default_rng(1))
    np.testing.assert_allclose(weights, np.array([0.6, 0.4, 1 / 3]) / (1 + 1 / 3), rtol=1e-7)
    np.testing.assert_array_equal(means[:2], mixture.means_[:2])
    assert any(np.array_equal(means[2], point) for point in prims.means)
    np.testing.assert_allclose(np.linalg.inv(precisions[2]), np.diag([1.5, 2.0, 2.5]))
    np.testing.assert_allclose(np.linalg.inv(precisions[:2]), covariances[:2])


@needs_fr1
@pytest.mark.parametrize("axis", ["y", "z", "x"])  # pan, roll, tilt of the camera
def test_gmm_pixels_d2d_holds_under_pure_rotation(axis):
    """A real fr1/xyz frame and the same surface seen from the camera turned by 5° (its pixel primitives rotated):
    pure rotation moves every component at once, the case where D2D from the identity is weakest. The mixture of
    the turned frame is fitted afresh (another k-means seed), as odometry does.

    Bound: the recovered rotation within 0.1° of the truth and the translation within 5 mm. fr1's fastest motion is
    about 2° per frame (30 Hz), so 5° is 2.5 times beyond it; ICP on 2,500 random points of each (the paper's
    baseline) is measured beside it and must do no better.
    """
    from dgmm.mixture import GaussianMixture
    from dgmm.odometry.pixels import CAMERAS
    from dgmm.primitives import Primitives
    from dgmm.registration import register_d2d, register_icp

    prims = pixel_primitives(read_sequence(FR1_XYZ).depth(0), CAMERAS["ros"])
    turn = Rotation.from_euler(axis, 5, degrees=True).as_matrix()  # camera 1 -> camera 0: x_0 = R x_1
    turned = Primitives(prims.means @ turn, turn.T @ prims.covariances @ turn, prims.weights)
    with threadpool_limits(1):
        fixed = GaussianMixture(100, random_state=0).fit(prims)
        moving = GaussianMixture(100, random_state=1).fit(turned)
        d2d = register_d2d(fixed, moving)
        rng = np.random.default_rng(0)
        icp = register_icp(turned.means[rng.choice(len(prims), 2500, replace=False)],
                           prims.means[rng.choice(len(prims), 2500, replace=False)])

    def angle_error(result):
        return np.degrees(Rotation.from_matrix(result.rotation.T @ turn).magnitude())
    print(f"\n{axis} 5°: D2D error {angle_error(d2d):.3f}°, ICP {angle_error(icp):.3f}°")
    assert angle_error(d2d) < 0.1 and np.linalg.norm(d2d.translation) < 0.005
    assert angle_error(d2d) <= angle_error(icp)


def test_point_gmm_runs_textbook_em_only():
    """With unit sizes the authors' EM is textbook EM (scale alpha / min alpha = 1, unweighted M-step = weighted), so
    the sweep runs gmm-points once; gmm-pixels, whose sizes are footprint areas, runs every variant, ICP none."""
    runs = odometry_runs(["gmm-pixels", "gmm-points", "icp"], ["textbook", "authors"])
    assert runs == {"gmm-pixels-textbook": ("gmm-pixels", "textbook"), "gmm-pixels-authors": ("gmm-pixels", "authors"),
                    "gmm-points-textbook": ("gmm-points", "textbook"), "icp": ("icp", "")}
