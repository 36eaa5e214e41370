"""dgmm.experiments.trials: seeded trials shared by every method, the methods table, run_trials on known poses."""
import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from dgmm.errors import InputError
from dgmm.experiments.trials import (METHODS, PROTOCOLS, bounding_diagonal, fit_mixture, make_trials, mixture_source,
                                     protocol_reg_covar, run_trials)
from dgmm.mixture import GaussianMixture


def sphere_points(n, seed=0):
    """n points uniform on the unit sphere, stretched into an asymmetric ellipsoid (no rotational symmetry)."""
    directions = np.random.default_rng(seed).normal(size=(n, 3))
    return directions / np.linalg.norm(directions, axis=1, keepdims=True) * [1.0, 0.6, 0.3]


def test_a_trial_does_not_depend_on_the_other_trials_asked_for():
    dense = sphere_points(2000)
    together = make_trials(dense, 100, range(5), root_seed=3, key="m/mesh", diagonal=2.0)
    alone = make_trials(dense, 100, [3], root_seed=3, key="m/mesh", diagonal=2.0)[0]
    assert alone.index == together[3].index == 3
    np.testing.assert_array_equal(alone.source, together[3].source)
    np.testing.assert_array_equal(alone.target, together[3].target)
    np.testing.assert_array_equal(alone.trial.rotation, together[3].trial.rotation)
    other = make_trials(dense, 100, [3], root_seed=3, key="m/other", diagonal=2.0)[0]
    assert not np.array_equal(other.source, alone.source)


def test_trial_points_are_distinct_rows_of_the_dense_sample_moved_within_the_protocol():
    dense = sphere_points(500)
    diagonal = bounding_diagonal(dense)
    for setup in make_trials(dense, 200, range(10), root_seed=0, key="k", diagonal=diagonal):
        rows = {tuple(row) for row in dense}
        assert all(tuple(p) in rows for p in setup.source) and all(tuple(p) in rows for p in setup.target)
        assert len({tuple(p) for p in setup.source}) == 200  # drawn without replacement
        np.testing.assert_allclose(setup.trial.centre, setup.source.mean(axis=0))
        angles = Rotation.from_matrix(setup.trial.rotation).as_euler("xyz", degrees=True)
        assert np.all(np.abs(angles) <= 15.0)
        assert np.all(np.abs(setup.trial.translation) <= 0.05 * diagonal / 0.24077)


def test_bounding_diagonal_of_a_box():
    corners = np.array([[0, 0, 0], [3, 4, 12], [1, 1, 1]], dtype=float)
    assert bounding_diagonal(corners) == 13.0


def test_methods_table_names_the_papers_methods_and_their_coarse_to_fine_p2d():
    paper = ["mesh-kmeans", "mesh-random", "points-kmeans", "points-random"]
    assert set(METHODS) == {*paper, *(f"{name}-c2f" for name in paper), "icp", "cpd"}
    assert [name for name, method in METHODS.items() if method.needs_mixture] == [
        *paper, *(f"{name}-c2f" for name in paper)]
    assert [mixture_source(f"{name}-c2f") for name in paper] == paper
    assert mixture_source("mesh-kmeans") == "mesh-kmeans"


@pytest.mark.slow
def test_every_method_undoes_small_trials_on_a_dense_target():
    """With source and target drawn from the same dense sample, every method removes most of each trial's motion.

    The trials start 4.3 and 5.2 deg and 1.7 and 3.6 % of the diagonal away. Each method must leave less than a
    fraction of that start: P2D on the K=20 mixture a tenth (it leaves 0.07 and 0.06), ICP and CPD on 300 of 3000
    points 0.45 (they leave up to 0.42 in rotation, 0.39 in translation). A method that removes only a third or a
    half of the motion (tried: 2.9 and 3.4 deg, 1.2 and 2.4 %; it passed the former bounds of 3 deg and 2 %) fails.
    """
    dense = sphere_points(3000, seed=1)
    diagonal = bounding_diagonal(dense)
    setups = make_trials(dense, 300, range(2), root_seed=0, key="sphere", diagonal=diagonal, max_angle_deg=5.0,
                         max_translation=0.01)
    start = {setup.index: (Rotation.from_matrix(setup.trial.rotation).magnitude() * 180 / np.pi,
                           100 * np.linalg.norm(setup.trial.translation) / diagonal) for setup in setups}
    mixture = GaussianMixture(20, random_state=0, max_iter=100, tol=1e-6).fit(dense)
    for method, fraction in (("points-kmeans", 0.1), ("icp", 0.45), ("cpd", 0.45)):
        rows, seconds = run_trials(method, setups, diagonal, mixture=mixture)
        assert [row["trial"] for row in rows] == [0, 1] and len(seconds) == 2
        for row in rows:
            start_angle, start_translation = start[row["trial"]]
            assert row["rotation_error_deg"] < fraction * start_angle, (method, row)
            assert row["translation_error_pct"] < fraction * start_translation, (method, row)


def test_bad_method_or_missing_mixture_is_an_input_error():
    setups = make_trials(sphere_points(100), 10, [0], root_seed=0, key="k", diagonal=1.0)
    with pytest.raises(InputError, match="must be one of"):
        run_trials("p2p", setups, 1.0)
    with pytest.raises(InputError, match="needs a fitted mixture"):
        run_trials("mesh-kmeans", setups, 1.0)
    with pytest.raises(InputError, match="n_points"):
        make_trials(sphere_points(100), 101, [0], root_seed=0, key="k", diagonal=1.0)


def test_literal_protocol_draws_the_authors_translations_in_model_units():
    """The same trial under both protocols: one rotation, the translation scaled by diagonal / the bunny's or not."""
    dense = sphere_points(500) * 1000.0  # millimetres, diagonal about 2600
    diagonal = bounding_diagonal(dense)
    scaled = make_trials(dense, 100, range(3), root_seed=0, key="k", diagonal=diagonal)
    literal = make_trials(dense, 100, range(3), root_seed=0, key="k", diagonal=diagonal, protocol="literal")
    for a, b in zip(scaled, literal):
        np.testing.assert_array_equal(a.trial.rotation, b.trial.rotation)
        np.testing.assert_allclose(a.trial.translation, b.trial.translation * diagonal / 0.24077, rtol=1e-12)
        assert np.all(np.abs(b.trial.translation) <= 0.05)
    with pytest.raises(InputError, match="protocol"):
        make_trials(dense, 100, [0], root_seed=0, key="k", diagonal=diagonal, protocol="metres")


def test_scaled_protocol_fits_a_scaled_copy_of_the_mixture_to_a_scaled_copy_of_the_model():
    """Under ``scaled`` a model in millimetres gets the mixture of the same model in metres, times 1000; ``literal``
    keeps the absolute floor, which binds on a box's flat faces in metres and not in millimetres."""
    box = trimesh.creation.box(extents=[0.2, 0.12, 0.08]).subdivide().subdivide()
    metres, faces = np.asarray(box.vertices), np.asarray(box.faces)
    fits = {}
    for protocol in PROTOCOLS:
        for unit in (1.0, 1000.0):
            vertices = metres * unit
            reg_covar = protocol_reg_covar(1e-4, bounding_diagonal(vertices), protocol)
            fits[protocol, unit] = fit_mixture("mesh-kmeans", vertices, faces, n_components=6, max_iter=30, tol=1e-9,
                                               reg_covar=reg_covar, variant="textbook", seed=0)
    small, large = fits["scaled", 1.0], fits["scaled", 1000.0]
    np.testing.assert_allclose(large.weights_, small.weights_, rtol=1e-6)
    np.testing.assert_allclose(large.means_, 1000.0 * small.means_, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(large.covariances_, 1e6 * small.covariances_, rtol=1e-5, atol=1e-3)
    thinnest = {unit: np.sqrt(np.linalg.eigvalsh(fits["literal", unit].covariances_)[:, 0].min()) / unit
                for unit in (1.0, 1000.0)}  # in metres
    assert thinnest[1000.0] < 0.1 * thinnest[1.0]  # the floor: 1e-4 mm² against 1e-4 m²
    with pytest.raises(InputError, match="protocol"):
        protocol_reg_covar(1e-6, 1.0, "metres")
