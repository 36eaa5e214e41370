"""The authors' odometry protocol (dgmm.odometry.protocols): pixel covariances, the per-frame fit, the runs.

References are independent of the code under test: a Monte Carlo of the uniform pixel footprint for the patch, a
Monte Carlo over the eight points the authors' notebook builds (written here from the notebook's geometry: pixel
corner rays at the depths of a ±1 px disparity) for the disparity box, scikit-learn's own ``GaussianMixture`` for the
per-frame fit, and the protocol's parts called one by one for the odometry loop.
"""
import numpy as np
import pytest
from sklearn.mixture import GaussianMixture as SklearnMixture
from threadpoolctl import threadpool_limits

from dgmm.errors import InputError
from dgmm.odometry import CAMERAS, backproject, odometry_runs, pixel_primitives, read_sequence, run_odometry
from dgmm.odometry.frame_model import SCHEDULES
from dgmm.odometry.pixel_covariance import BASELINE, disparity_box_covariances, patch_covariances
from dgmm.odometry.pixels import PIXEL_STEP
from dgmm.odometry.protocols import PROTOCOLS, protocol_runs, run_protocol
from dgmm.odometry.sklearn_em import fit_sklearn_defaults
from dgmm.primitives import Primitives
from dgmm.registration import register_d2d
from dgmm.variants import VARIANTS
from tests.test_odometry_metrics import FR1_XYZ, needs_fr1

CAMERA = CAMERAS["fr3"]
PIXELS = [(0, 0, 0.6), (320, 240, 1.5), (636, 476, 3.0), (100, 400, 7.5), (500, 60, 14.0)]
"""(u, v, Z) of pixels across the image and the depth range (near and far clip of the disparity included)."""


def _points(pixels):
    u, v, z = np.array(pixels, dtype=float).T
    return np.stack([(u - CAMERA.cx) / CAMERA.fx * z, (v - CAMERA.cy) / CAMERA.fy * z, z], axis=1)


@pytest.mark.parametrize("pixel", PIXELS)
def test_patch_covariance_is_the_uniform_footprint(pixel):
    """A point drawn uniformly over the pixel's 4 x 4 block at its depth: its covariance is the patch's."""
    u, v, z = pixel
    rng = np.random.default_rng(1)
    du, dv = rng.uniform(-PIXEL_STEP / 2, PIXEL_STEP / 2, (2, 400_000))
    samples = np.stack([(u + du - CAMERA.cx) / CAMERA.fx * z, (v + dv - CAMERA.cy) / CAMERA.fy * z,
                        np.full(du.shape, z)], axis=1)
    reference = np.cov(samples.T)
    covariance = patch_covariances(_points([pixel]), CAMERA, PIXEL_STEP)[0]
    np.testing.assert_allclose(np.diag(covariance)[:2], np.diag(reference)[:2], rtol=0.01)
    np.testing.assert_allclose(covariance, reference, atol=0.01 * reference.max())


def _notebook_box_points(u, v, z):
    """The eight points of gen_gmm-mine.ipynb's box of pixel (u, v) at depth z, from its geometry: the rays through
    the block's column edges u ± 2 at rows v ± 2; the right edge at the depth of disparity + 1 px and at z, the left
    edge at z and at the depth of disparity - 1 px (disparities clipped to 2..325 px)."""
    disparity = CAMERA.fx * BASELINE / z
    near = CAMERA.fx * BASELINE / min(max(disparity + 1, 2), 325)
    far = CAMERA.fx * BASELINE / min(max(disparity - 1, 2), 325)

    def at(column, row, depth):
        return [(column - CAMERA.cx) / CAMERA.fx * depth, (row - CAMERA.cy) / CAMERA.fy * depth, depth]

    return np.array([at(u + du, v + dv, depth) for dv in (2, -2)
                     for du, depth in ((2, near), (-2, z), (2, z), (-2, far))])


@pytest.mark.parametrize("pixel", PIXELS)
def test_disparity_box_is_the_notebooks(pixel):
    """Monte Carlo over the notebook's eight points: their covariance x 8/12 is the notebook's Σ (c cᵀ - m mᵀ) / 12."""
    corners = _notebook_box_points(*pixel)
    samples = corners[np.random.default_rng(2).integers(8, size=400_000)]
    reference = np.cov(samples.T, bias=True) * 8 / 12
    covariance = disparity_box_covariances(_points([pixel]), CAMERA, PIXEL_STEP)[0]
    np.testing.assert_allclose(covariance, reference, atol=0.01 * np.abs(reference).max())
    assert np.linalg.eigvalsh(covariance).min() > 0 or pixel[2] > 13  # a box, not flat (far: the clip flattens it)


def test_disparity_box_depth_spread():
    """Along the optical axis the box's depth variance follows from the disparity error alone: the four depths
    (near, z, z, far), each twice, spread (8/12) x their variance; at 2 m (disparity 20 px) about 5.8 cm of sd."""
    z = 2.0
    disparity = CAMERA.fx * BASELINE / z
    depths = CAMERA.fx * BASELINE / np.array([disparity + 1, disparity, disparity, disparity - 1])
    covariance = disparity_box_covariances(np.array([[0.0, 0.0, z]]), CAMERA, PIXEL_STEP)[0]
    assert covariance[2, 2] == pytest.approx(np.var(depths) * 8 / 12, rel=1e-12)
    assert np.sqrt(covariance[2, 2]) == pytest.approx(0.058, abs=0.001)


def test_pixel_primitives_take_the_covariance_and_unit_sizes():
    depth = np.zeros((CAMERA.height, CAMERA.width))
    depth[::PIXEL_STEP, ::PIXEL_STEP] = np.linspace(0.5, 4.0, depth[::PIXEL_STEP, ::PIXEL_STEP].size).reshape(120, 160)
    prims = pixel_primitives(depth, CAMERA, size="unit", covariance="disparity")
    points = backproject(depth, CAMERA)
    np.testing.assert_array_equal(prims.means, points)
    np.testing.assert_array_equal(prims.weights, np.ones(len(points)))
    np.testing.assert_allclose(prims.covariances, disparity_box_covariances(points, CAMERA, PIXEL_STEP))
    with pytest.raises(InputError, match="covariance must be one of"):
        pixel_primitives(depth, CAMERA, covariance="box")


@pytest.fixture(scope="module")
def fr1_frame():
    sequence = read_sequence(FR1_XYZ)
    return sequence, next(iter(sequence.depth_frames([0])))


@needs_fr1
@pytest.mark.parametrize("seed", [0, 7])
def test_fit_is_scikit_learns_on_points(fr1_frame, seed):
    """Sizes 1, covariances 0: the per-frame fit is scikit-learn's GaussianMixture(K) at its defaults, started from
    the same k-means seed, to rounding, with the same iteration count."""
    _, depth = fr1_frame
    points = backproject(depth, CAMERAS["ros"])
    k = 40
    with threadpool_limits(1):
        ours = fit_sklearn_defaults(Primitives.from_points(points), k, np.random.default_rng(seed))
        sklearn_seed = int(np.random.default_rng(seed).integers(np.iinfo(np.int32).max))  # the k-means seed drawn
        reference = SklearnMixture(k, random_state=sklearn_seed).fit(points)
    assert ours.n_iter_ == reference.n_iter_ < 100
    np.testing.assert_allclose(ours.weights_, reference.weights_, atol=1e-9)
    np.testing.assert_allclose(ours.means_, reference.means_, atol=1e-9)
    np.testing.assert_allclose(ours.covariances_, reference.covariances_, atol=1e-10)


@needs_fr1
def test_authors_protocol_is_its_parts(fr1_frame):
    """run_odometry's authors-disparity: each frame's primitives of size 1 with the disparity box, fitted by
    scikit-learn's defaults from the frame's seed, registered by BFGS D2D from the identity."""
    sequence, _ = fr1_frame
    models = []
    with threadpool_limits(1):
        result = run_odometry(sequence, "gmm-pixels", [0, 1], intrinsics=CAMERAS["ros"], protocol="authors-disparity",
                              seed=3, n_components=30, callback=lambda frame: models.append(frame.model))
        fits = [fit_sklearn_defaults(pixel_primitives(depth, CAMERAS["ros"], size="unit", covariance="disparity"), 30,
                                     np.random.default_rng([3, index]), reg_covar=1e-6)
                for index, depth in zip([0, 1], sequence.depth_frames([0, 1]))]
        registration = register_d2d(*fits, solver="bfgs")
    for model, fit in zip(models, fits):
        np.testing.assert_allclose(model.means_, fit.means_, atol=1e-9)
        np.testing.assert_allclose(model.covariances_, fit.covariances_, atol=1e-10)
    np.testing.assert_allclose(result.registrations[0].rotation, registration.rotation, atol=1e-9)
    np.testing.assert_allclose(result.registrations[0].translation, registration.translation, atol=1e-9)


def test_runs_and_their_protocols():
    runs = odometry_runs(["gmm-pixels", "gmm-points", "icp"], ["textbook", "authors"],
                         ["ours", "authors-patch", "authors-disparity"])
    assert runs == {"gmm-pixels-textbook": ("gmm-pixels", "textbook"), "gmm-pixels-authors": ("gmm-pixels", "authors"),
                    "gmm-points-textbook": ("gmm-points", "textbook"), "icp": ("icp", ""),
                    "gmm-pixels-authors-patch": ("gmm-pixels", "authors"),
                    "gmm-points-authors-patch": ("gmm-points", "authors"),
                    "gmm-pixels-authors-disparity": ("gmm-pixels", "authors")}
    assert [run_protocol(run) for run in runs] == ["ours"] * 4 + ["authors-patch"] * 2 + ["authors-disparity"]
    assert odometry_runs(["gmm-pixels"], ["textbook"]) == {"gmm-pixels-textbook": ("gmm-pixels", "textbook")}
    assert protocol_runs(["authors-disparity"], ["icp", "gmm-points"]) == {}
    assert protocol_runs(["ours-unit"], ["gmm-pixels", "icp"]) == {"gmm-pixels-ours-unit": ("gmm-pixels", "textbook")}
    assert run_protocol("gmm-pixels-ours-unit") == "ours-unit"
    with pytest.raises(InputError, match="^protocols must be one of ours, ours-unit, authors-patch, authors-disparity"):
        odometry_runs(["gmm-pixels"], ["textbook"], ["authors"])


def test_authors_schedule_and_protocols():
    schedule = SCHEDULES["authors"]
    assert (schedule.seed_sample, schedule.em_iter, schedule.em_tol, schedule.solver) == (None, 100, 1e-3, "bfgs")
    assert not (schedule.overlap_rounds or schedule.cut_rounds or schedule.overlap_refits)
    assert {name: (p.schedule, p.size, p.covariance, p.methods, p.capped) for name, p in PROTOCOLS.items() if p} == {
        "ours-unit": (None, "unit", "patch", ("gmm-pixels",), False),
        "authors-patch": ("authors", "unit", "patch", ("gmm-pixels", "gmm-points"), True),
        "authors-disparity": ("authors", "unit", "disparity", ("gmm-pixels",), True)}


def test_bad_protocol_is_one_line(tmp_path):
    with pytest.raises(InputError, match="^protocol must be one of ours, ours-unit, authors-patch, authors-disparity, "
                                         "got 'x'$"):
        run_odometry(None, "gmm-pixels", protocol="x")
    with pytest.raises(InputError, match="^protocol 'authors-patch' applies to gmm-pixels, gmm-points, not 'icp'$"):
        run_odometry(None, "icp", protocol="authors-patch")


def test_cli_protocols_are_the_librarys():
    from dgmm.cli import ODOMETRY_PROTOCOLS

    assert ODOMETRY_PROTOCOLS == tuple(PROTOCOLS)


@needs_fr1
def test_the_unit_size_switch_is_ours_with_pixels_of_size_1(fr1_frame):
    """ours-unit keeps the caller's schedule and changes only the pixels' size: the same trajectory as ours with
    ``size="unit"``, bit for bit, and another than ours with areas."""
    sequence, _ = fr1_frame
    with threadpool_limits(1):
        poses = [run_odometry(sequence, "gmm-pixels", [0, 1, 2], intrinsics=CAMERAS["ros"], seed=1, n_components=20,
                              **options).trajectory
                 for options in ({"protocol": "ours-unit"}, {"size": "unit"}, {"size": "area"})]
    np.testing.assert_array_equal(poses[0].translations, poses[1].translations)
    assert not np.array_equal(poses[0].translations, poses[2].translations)


@needs_fr1
def test_both_variants_are_one_algorithm_on_unit_sizes(fr1_frame):
    """The authors' protocol's sizes are all 1: textbook EM and the authors' give the same trajectory, bit for bit."""
    sequence, _ = fr1_frame
    with threadpool_limits(1):
        poses = [run_odometry(sequence, "gmm-pixels", [0, 1, 2], intrinsics=CAMERAS["ros"], protocol="authors-patch",
                              variant=variant, seed=1, n_components=20).trajectory for variant in VARIANTS]
    np.testing.assert_array_equal(poses[0].translations, poses[1].translations)
    np.testing.assert_array_equal(poses[0].rotations, poses[1].rotations)
