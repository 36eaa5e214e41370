"""The odometry schedule's ``cut_rounds`` (dgmm.odometry.measured_cut): which primitives the other frame measures,
and each mixture cut to them.

References are independent of the code under test: pixel indices shifted by hand for a plane seen at a known
depth, and the M-step over the seen primitives summed directly from every primitive's responsibilities.
"""
import dataclasses

import numpy as np
import pytest
from scipy.special import logsumexp
from scipy.spatial.transform import Rotation
from scipy.stats import multivariate_normal

from dgmm.errors import InputError
from dgmm.mixture import GaussianMixture
from dgmm.odometry import CAMERAS, pixel_primitives
from dgmm.odometry.frame_model import SCHEDULES
from dgmm.odometry.measured_cut import MeasuredFrame, cut, pose_change, seen_by, unseen_primitives
from dgmm.odometry.pixels import PIXEL_STEP
from dgmm.registration import Registration

ROS = CAMERAS["ros"]
ROWS, COLS = ROS.height // PIXEL_STEP, ROS.width // PIXEL_STEP


def banded_plane(depth=2.0):
    """A fronto-parallel plane at ``depth`` with fr1's band of no measurement (first 6 grid rows, last 10 grid
    columns) and a hole."""
    image = np.full((ROS.height, ROS.width), depth)
    image[:6 * PIXEL_STEP] = 0.0
    image[:, -10 * PIXEL_STEP:] = 0.0
    image[200:240, 100:180] = 0.0
    return image


def frame_of(image, mixture=None, variant="textbook"):
    return MeasuredFrame(mixture, pixel_primitives(image, ROS), image[::PIXEL_STEP, ::PIXEL_STEP] > 0, ROS,
                         PIXEL_STEP, variant)


@pytest.mark.parametrize("shift", [(0, 0), (3, 0), (-5, 2), (7, -4), (2.6, -1.4), (-0.4, 0.3)])
def test_seen_by_is_the_measured_pixel_the_point_moves_to(shift):
    """On a plane at depth Z, moving a point by ``(du Z step / fx, dv Z step / fy, 0)`` moves its pixel by
    ``(du, dv)`` grid cells; it is seen iff the nearest cell is inside the grid and measured."""
    image = banded_plane()
    frame = frame_of(image)
    du, dv = shift
    points = frame.primitives.means + [du * PIXEL_STEP * 2.0 / ROS.fx, dv * PIXEL_STEP * 2.0 / ROS.fy, 0.0]
    valid = image[::PIXEL_STEP, ::PIXEL_STEP] > 0
    rows, cols = np.nonzero(valid)  # raster order, as the primitives
    rows, cols = rows + int(round(dv)), cols + int(round(du))
    inside = (rows >= 0) & (rows < ROWS) & (cols >= 0) & (cols < COLS)
    expected = np.zeros(len(points), dtype=bool)
    expected[inside] = valid[rows[inside], cols[inside]]
    np.testing.assert_array_equal(seen_by(points, frame), expected)
    assert not seen_by(-points[:5], frame).any()  # behind the camera


def test_unseen_primitives_map_each_frame_into_the_other():
    """Two banded planes (different depths, the second with its own hole), the moving camera turned 10° about the
    optical axis and shifted: a primitive is unseen iff, moved into the other camera one point at a time
    (``x_m = Rᵀ (x_f − t)``, ``x_f = R x_m + t``), its nearest grid pixel there is outside or unmeasured."""
    fixed_image, moving_image = banded_plane(2.0), banded_plane(2.5)
    moving_image[300:400, 400:480] = 0.0
    fixed, moving = frame_of(fixed_image), frame_of(moving_image)
    angle = np.radians(10.0)
    rotation = np.array([[np.cos(angle), -np.sin(angle), 0.0], [np.sin(angle), np.cos(angle), 0.0], [0, 0, 1.0]])
    translation = np.array([0.2, -0.1, -0.5])

    def unseen_one_by_one(points, to_other, other):
        out = []
        for point in points:
            x, y, z = to_other(point)
            col, row = round((ROS.fx * x / z + ROS.cx) / PIXEL_STEP), round((ROS.fy * y / z + ROS.cy) / PIXEL_STEP)
            out.append(not (0 <= row < ROWS and 0 <= col < COLS and other[row, col] > 0))
        return np.array(out)

    fixed_unseen, moving_unseen = unseen_primitives(fixed, moving, rotation, translation)
    np.testing.assert_array_equal(fixed_unseen, unseen_one_by_one(
        fixed.primitives.means, lambda x: rotation.T @ (x - translation), moving_image[::PIXEL_STEP, ::PIXEL_STEP]))
    np.testing.assert_array_equal(moving_unseen, unseen_one_by_one(
        moving.primitives.means, lambda x: rotation @ x + translation, fixed_image[::PIXEL_STEP, ::PIXEL_STEP]))
    assert 0.05 < fixed_unseen.mean() < 0.95 and 0.05 < moving_unseen.mean() < 0.95  # the case has power


def test_cut_is_the_m_step_over_the_seen_primitives():
    """A textbook-EM fixed point cut to the primitives left of a column: weights, means and covariances equal the
    M-step summed directly over those primitives with their responsibilities."""
    rng = np.random.default_rng(0)
    v, u = np.mgrid[0:ROS.height, 0:ROS.width]
    image = 1.0 + 0.4 * np.sin(u / 90.0) + 0.3 * (v / ROS.height) ** 2 + 0.002 * rng.standard_normal(u.shape)
    frame = frame_of(image)
    mixture = GaussianMixture(4, max_iter=2000, tol=0.0, reg_covar=1e-6, random_state=0).fit(frame.primitives)
    frame = frame_of(image, mixture)
    prims = frame.primitives
    unseen = prims.means[:, 0] / prims.means[:, 2] > 0.2  # the right part of the view
    weights, means, covariances = cut(frame, unseen)

    seen = ~unseen
    resp = mixture.predict_proba(prims)[seen] * (prims.weights[seen] / prims.weights.mean())[:, None]
    mass = resp.sum(axis=0)
    x, c = prims.means[seen], prims.covariances[seen]
    direct_means = resp.T @ x / mass[:, None]
    direct_covariances = np.stack([
        (resp[:, k, None] * (x - direct_means[k])).T @ (x - direct_means[k])
        + np.einsum("p,pab->ab", resp[:, k], c) for k in range(4)]) / mass[:, None, None] + 1e-6 * np.eye(3)
    assert unseen.mean() > 0.2 and (mass / mass.sum()).min() > 0.01  # every component keeps primitives
    np.testing.assert_allclose(weights, mass / mass.sum(), rtol=1e-6)
    np.testing.assert_allclose(means, direct_means, rtol=0, atol=1e-6)
    np.testing.assert_allclose(covariances, direct_covariances, rtol=0, atol=1e-7)


def test_cut_drops_a_component_with_no_seen_primitive():
    """Every primitive unseen but one component's: that component alone keeps weight."""
    rng = np.random.default_rng(1)
    image = np.where(np.arange(ROS.width) < ROS.width // 2, 1.0, 3.0)[None, :].repeat(ROS.height, 0)
    image = image + 0.002 * rng.standard_normal(image.shape)
    frame = frame_of(image)
    mixture = GaussianMixture(2, max_iter=200, tol=0.0, random_state=0).fit(frame.primitives)
    frame = frame_of(image, mixture)
    near = mixture.means_[:, 2].argmin()
    weights, _, _ = cut(frame, frame.primitives.means[:, 2] > 2.0)
    np.testing.assert_allclose(weights[near], 1.0)
    assert weights[1 - near] == 0.0


@pytest.mark.parametrize("variant", ["textbook", "authors"])
def test_cut_of_a_two_iteration_fit_is_its_last_m_step_over_the_seen_primitives(variant):
    """The odometry's mixtures run two EM iterations, far from a fixed point: the cut equals the second M-step
    summed directly over the seen primitives, with responsibilities computed here by scipy under the parameters
    after one iteration (for the authors' EM the Mahalanobis-plus-trace term times ``alpha / min(alpha)`` and an
    unweighted M-step; the textbook M-step weighted by size)."""
    rng = np.random.default_rng(2)
    v, u = np.mgrid[0:ROS.height, 0:ROS.width]
    image = 1.0 + 0.6 * (u / ROS.width) ** 2 + 0.5 * np.cos(v / 70.0) + 0.002 * rng.standard_normal(u.shape)
    prims = frame_of(image).primitives
    common = dict(tol=None, reg_covar=1e-6, random_state=0, variant=variant)
    before = GaussianMixture(5, max_iter=1, **common).fit(prims)
    mixture = GaussianMixture(5, max_iter=2, **common).fit(prims)
    unseen = prims.means[:, 0] / prims.means[:, 2] < -0.1
    weights, means, covariances = cut(frame_of(image, mixture, variant), unseen)

    def m_step_over_seen(model):
        sizes = prims.weights
        scale = sizes / sizes.min() if variant == "authors" else np.ones(len(sizes))
        gaussians = [multivariate_normal(mean, cov) for mean, cov in zip(model.means_, model.covariances_)]
        peaks = np.array([gaussian.logpdf(gaussian.mean) for gaussian in gaussians])  # log-normalisers
        log_rho = np.log(model.weights_) + peaks + scale[:, None] * np.column_stack([
            gaussian.logpdf(prims.means) - peak - 0.5 * np.einsum("ab,pba->p", np.linalg.inv(gaussian.cov),
                                                                  prims.covariances)
            for gaussian, peak in zip(gaussians, peaks)])
        resp = np.exp(log_rho - logsumexp(log_rho, axis=1, keepdims=True))[~unseen]
        resp *= (np.ones(len(sizes)) if variant == "authors" else sizes)[~unseen, None]
        mass = resp.sum(axis=0)
        x, c = prims.means[~unseen], prims.covariances[~unseen]
        direct_means = resp.T @ x / mass[:, None]
        direct_covariances = np.stack([
            (resp[:, k, None] * (x - direct_means[k])).T @ (x - direct_means[k]) + np.einsum("p,pab->ab", resp[:, k], c)
            for k in range(len(mass))]) / mass[:, None, None] + 1e-6 * np.eye(3)
        return mass / mass.sum(), direct_means, direct_covariances

    expected = m_step_over_seen(before)
    assert 0.2 < unseen.mean() < 0.5
    np.testing.assert_allclose(weights, expected[0], rtol=1e-8)
    np.testing.assert_allclose(means, expected[1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(covariances, expected[2], rtol=0, atol=1e-10)
    # The case has power: responsibilities under the fitted parameters give another mixture.
    assert np.abs(m_step_over_seen(mixture)[1] - expected[1]).max() > 1e-4


def test_a_schedule_that_ends_widened_needs_cut_rounds():
    """The overlap rounds may end widened only when cut rounds register the mixtures themselves after them."""
    assert SCHEDULES["overlap"].overlap_scales[-1] > 0 and SCHEDULES["overlap"].cut_rounds > 0
    with pytest.raises(InputError, match="overlap_scales"):
        dataclasses.replace(SCHEDULES["overlap"], cut_rounds=0)


def test_pose_change_is_the_centroid_shift_in_radii_or_the_turn_in_radians():
    """Poses chosen here: a turn about the centroid moves it nowhere (the change is the angle), a pure translation
    moves it by its length, and a turn about the origin moves it by the chord ``2 |c| sin(θ/2)``."""
    centroid, radius = np.array([0.3, -0.2, 2.0]), 1.5
    start = Registration(np.eye(3), np.zeros(3), 0, 0.0, 0.0, True, "d2d")
    turn = Rotation.from_rotvec([0.0, 0.02, 0.0]).as_matrix()
    about_centroid = dataclasses.replace(start, rotation=turn, translation=centroid - turn @ centroid)
    assert pose_change(start, about_centroid, centroid, radius) == pytest.approx(0.02, rel=1e-12)
    shifted = dataclasses.replace(start, translation=np.array([0.0, 0.003, 0.004]))
    assert pose_change(start, shifted, centroid, radius) == pytest.approx(0.005 / radius, rel=1e-12)
    about_origin = dataclasses.replace(start, rotation=turn)  # the chord is longer than 0.02 radii here
    chord = 2 * np.linalg.norm(centroid[[0, 2]]) * np.sin(0.01)
    assert pose_change(start, about_origin, centroid, radius) == pytest.approx(chord / radius, rel=1e-9)
    assert pose_change(about_centroid, start, centroid, radius) == pytest.approx(0.02, rel=1e-12)
