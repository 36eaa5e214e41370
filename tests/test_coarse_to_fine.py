"""dgmm.registration.coarse_to_fine: widened mixtures, the schedule, and poses recovered where one BFGS from the
identity fails."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from dgmm.errors import InputError
from dgmm.mixture import GaussianMixture
from dgmm.registration import register_p2d
from dgmm.registration.coarse_to_fine import WidenedMixture, register_p2d_coarse_to_fine


@pytest.fixture(scope="module")
def comb():
    """Points on five thin parallel plates 0.25 apart (a comb), and a K=20 mixture of them: a likelihood with
    five narrow ridges, the shape of a mesh GMM's sheets."""
    rng = np.random.default_rng(0)
    plates = rng.uniform([-1, -1, 0], [1, 1, 0], size=(2000, 3)) + np.repeat(np.arange(5) * 0.25, 400)[:, None] \
        * [0, 0, 1]
    plates[:, 0] *= 1 + 0.5 * (plates[:, 2] > 0.6)  # the top plates are wider: no symmetry swaps them
    mixture = GaussianMixture(20, random_state=0).fit(plates)
    return plates, mixture


def test_widened_mixture_adds_the_variance_and_keeps_the_precision_factor_consistent(comb):
    _, mixture = comb
    widened = WidenedMixture(mixture, 0.01)
    np.testing.assert_allclose(widened.covariances_, mixture.covariances_ + 0.01 * np.eye(3))
    u = widened.precisions_cholesky_
    np.testing.assert_allclose(u @ u.transpose(0, 2, 1), np.linalg.inv(widened.covariances_), rtol=1e-10)
    assert np.allclose(np.tril(u, -1), 0)  # upper-triangular, as scikit-learn's precisions_cholesky_
    np.testing.assert_array_equal(widened.weights_, mixture.weights_)


def test_a_schedule_of_only_zero_is_the_papers_p2d(comb):
    plates, mixture = comb
    moved = plates[::10] + [0.02, 0.0, 0.03]
    ours = register_p2d_coarse_to_fine(moved, mixture, scales=[0.0])
    paper = register_p2d(moved, mixture)
    np.testing.assert_array_equal(ours.rotation, paper.rotation)
    np.testing.assert_array_equal(ours.translation, paper.translation)
    assert ours.iterations == paper.iterations and ours.method == "p2d-c2f"


def test_coarse_to_fine_leaves_the_wrong_ridge_that_one_bfgs_stops_on(comb):
    """Shifted by 1.2 plate gaps across the plates, one BFGS settles the points on the neighbouring plates;
    the coarse stages see one broad basin and bring them back."""
    plates, mixture = comb
    source = plates[::5]
    rotation = Rotation.from_euler("xyz", [4, -3, 5], degrees=True).as_matrix()
    centre = source.mean(axis=0)
    moved = (source - centre) @ rotation.T + centre + [0.05, -0.04, 0.3]
    steps = []
    robust = register_p2d_coarse_to_fine(moved, mixture, callback=lambda i, reg: steps.append(i))
    paper = register_p2d(moved, mixture)
    error = lambda reg: np.abs(reg.apply(moved) - source).max()  # noqa: E731
    assert error(paper) > 0.1  # the paper's P2D: a wrong ridge
    assert error(robust) < 0.02
    assert steps == list(range(1, robust.iterations + 1))


@pytest.mark.parametrize("scales", [[], [0.5, 0.1], [0.1, 0.5, 0.0], [-0.1, 0.0]])
def test_bad_schedules_are_refused(comb, scales):
    plates, mixture = comb
    with pytest.raises(InputError, match="scales"):
        register_p2d_coarse_to_fine(plates[:10], mixture, scales=scales)
