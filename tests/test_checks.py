"""dgmm.experiments.checks against independent references: scipy's rotations and Gaussian density, Monte Carlo
integrals over triangles, and counts by hand; the identities' references against planted errors; the timing checks'
rows (every setting once per repeat, in alternating order)."""
import numpy as np
import pytest
import trimesh
import yaml
from scipy.spatial.transform import Rotation
from scipy.stats import multivariate_normal

from dgmm.data import load_mesh, load_points
from dgmm.experiments.checks import identities, timing_registration
from dgmm.experiments.checks.convergence import (convergence_rows, coverage, effective_components,
                                                iterations_to_converge)
from dgmm.experiments.checks.identities import CGAL_TETRAHEDRON_MOMENT, identity_rows
from dgmm.experiments.checks.interleaved import COLUMNS, interleaved_times, setting_order
from dgmm.experiments.checks.optimisers import _rotvec_params
from dgmm.experiments.checks.resampling import component_integrals, merged, pieces_by_triangle, split_in_four
from dgmm.experiments.checks.timing import TIMING_CHECKS
from dgmm.experiments.checks.timing_meshes import approximation_times, decimation_times, sampling_times
from dgmm.experiments.checks.timing_odometry import d2d_primitives_times, odometry_frame_times
from dgmm.experiments.checks.timing_registration import cpd_p2d_times, d2d_cost, d2d_determinant_times
from dgmm.experiments.sweep import build_input, fit_seeds, job_seed
from dgmm.mixture import GaussianMixture
from dgmm.odometry import read_sequence
from dgmm.primitives import Primitives
from dgmm.registration import register_p2d, rotation_distance_deg
from dgmm.runtime.tables import read_csv

from conftest import REPO, SHARED_DATA
from tests.workflow import copy_run, run_snakemake

FR1_XYZ = SHARED_DATA / "tum" / "rgbd_dataset_freiburg1_xyz"


def test_iterations_to_converge_is_the_first_iteration_that_stays_within_the_tolerance():
    history = [1.0, 1.5, 1.95, 2.1, 1.9, 1.99, 2.0]  # within 0.05 of 2.0 at iterations 3, then 6 for good
    assert iterations_to_converge(history, 0.05) == 6
    assert iterations_to_converge(history, 0.15) == 3
    assert iterations_to_converge([5.0, 5.0], 0.01) == 1


def test_convergence_is_measured_on_textbook_ems_bound_under_either_em(res4_mesh):
    """The authors' EM optimises a bound scaled by α / α_min; its rows carry textbook EM's bound (eq. 8 per unit
    area), as a refit to the same iterations scores it, and not the fit's own."""
    vertices, faces, _ = res4_mesh
    prims = Primitives.from_mesh(vertices, faces)
    rows = {variant: convergence_rows(prims, vertices, model="bunny", input_name="res4-exact", variant=variant,
                                      components=[6], inits=["kmeans"], seeds=1, root_seed=0, max_iter=30)[0]
            for variant in ("authors", "textbook")}
    seed = job_seed(0, "bunny/res4-exact/authors/k6-kmeans", 0)
    authors = GaussianMixture(6, max_iter=30, tol=1e-12, variant="authors", random_state=seed).fit(prims)
    assert rows["authors"]["bound_final"] == pytest.approx(authors.score_primitives(prims), abs=1e-12)
    assert abs(authors.lower_bound_ - rows["authors"]["bound_final"]) > 0.1  # its own scale is another
    textbook = GaussianMixture(6, max_iter=30, tol=1e-12, random_state=job_seed(
        0, "bunny/res4-exact/textbook/k6-kmeans", 0)).fit(prims)
    assert rows["textbook"]["bound_final"] == textbook.lower_bound_


def test_coverage_counts_points_inside_two_sigma_ellipsoids():
    mixture = GaussianMixture.from_parameters([0.5, 0.5], [[0, 0, 0], [10, 0, 0]],
                                              [np.diag([1.0, 4.0, 1.0]), np.eye(3)])
    points = np.array([[1.9, 0, 0], [0, 3.9, 0], [0, 4.1, 0], [2.1, 0, 0], [10, 0, 1.5], [5, 0, 0]])
    assert coverage(mixture, points) == pytest.approx(3 / 6)  # the first two, and the one 1.5σ from the second


def test_effective_components():
    assert effective_components(np.full(4, 0.25)) == pytest.approx(1.0)
    assert effective_components(np.array([1.0, 0.0, 0.0, 0.0])) == pytest.approx(0.25)


def test_rotation_vector_parameters_give_scipys_quaternion():
    rotvec = np.array([0.3, -0.2, 0.5])
    params = _rotvec_params(np.concatenate([[1.0, 2.0, 3.0], rotvec]))
    x, y, z, w = Rotation.from_rotvec(rotvec).as_quat()
    assert params == pytest.approx([1.0, 2.0, 3.0, w, x, y, z])
    assert _rotvec_params(np.zeros(6)) == pytest.approx([0, 0, 0, 1, 0, 0, 0])


def test_d2d_cost_with_the_determinant_is_the_overlap_of_the_mixtures():
    rng = np.random.default_rng(0)
    covariances = [np.diag(rng.uniform(0.5, 2.0, 3)) for _ in range(4)]
    fixed = GaussianMixture.from_parameters([0.3, 0.7], rng.normal(size=(2, 3)), covariances[:2])
    moving = GaussianMixture.from_parameters([0.6, 0.4], rng.normal(size=(2, 3)), covariances[2:])
    params = np.array([0.1, -0.2, 0.3, 1.0, 0.0, 0.0, 0.0])  # a translation only
    overlap = sum(a * b * multivariate_normal.pdf(m, n + params[:3], s + c)
                  for a, m, s in zip(fixed.weights_, fixed.means_, fixed.covariances_)
                  for b, n, c in zip(moving.weights_, moving.means_, moving.covariances_))
    assert d2d_cost(params, fixed, moving, True) == pytest.approx(-overlap)
    free = sum(a * b * np.exp(-0.5 * (m - n - params[:3]) @ np.linalg.solve(s + c, m - n - params[:3]))
               for a, m, s in zip(fixed.weights_, fixed.means_, fixed.covariances_)
               for b, n, c in zip(moving.weights_, moving.means_, moving.covariances_))
    assert d2d_cost(params, fixed, moving, False) == pytest.approx(-free)


def test_split_in_four_keeps_the_surface_and_the_component_integrals(bunny_res4):
    vertices, faces = np.asarray(bunny_res4.vertices), np.asarray(bunny_res4.faces)
    split_vertices, split_faces = split_in_four(vertices, faces)
    assert len(split_faces) == 4 * len(faces)
    mesh, split = Primitives.from_mesh(vertices, faces), Primitives.from_mesh(split_vertices, split_faces)
    assert split.weights.sum() == pytest.approx(mesh.weights.sum(), rel=1e-12)
    mixture = GaussianMixture(50, random_state=0, max_iter=5).fit(mesh)  # small components: the trace term matters
    integrals = component_integrals(mixture, mesh)
    assert component_integrals(mixture, split) == pytest.approx(integrals, abs=1e-9)
    # Monte Carlo over the surface: uniform points on the triangles, area-weighted
    rng = np.random.default_rng(1)
    triangles = vertices[faces]
    chosen = rng.choice(len(faces), 200_000, p=mesh.weights / mesh.weights.sum())
    u, v = rng.random((2, len(chosen)))
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    a, b, c = triangles[chosen].transpose(1, 0, 2)
    points = a + u[:, None] * (b - a) + v[:, None] * (c - a)
    samples = [multivariate_normal.logpdf(points, m, s) for m, s in zip(mixture.means_, mixture.covariances_)]
    errors = np.array([sample.std() / np.sqrt(len(sample)) for sample in samples])
    assert np.all(np.abs(integrals - [sample.mean() for sample in samples]) <= 4 * errors + 1e-3)


def test_pieces_merged_by_their_triangle_are_the_original_triangles(bunny_res4):
    """The shared-responsibility switch: each triangle's four pieces, merged by their moments, are that triangle as
    from_mesh computes it (moments of the uniform distribution over it), in the original order."""
    vertices, faces = np.asarray(bunny_res4.vertices), np.asarray(bunny_res4.faces)
    pieces, parents = pieces_by_triangle(vertices, faces)
    assert len(pieces) == 4 * len(faces) and np.array_equal(np.bincount(parents), np.full(len(faces), 4))
    original, shared = Primitives.from_mesh(vertices, faces), merged(pieces, parents)
    assert shared.weights == pytest.approx(original.weights, rel=1e-12)
    assert np.abs(shared.means - original.means).max() <= 1e-12 * np.abs(original.means).max()
    assert np.abs(shared.covariances - original.covariances).max() <= 1e-9 * np.abs(original.covariances).max()
    assert not np.allclose(pieces.covariances[::4], original.covariances)  # a piece alone is not its triangle


def _relative(row):
    return row["max_error"] / row["scale"]


@pytest.fixture(scope="module")
def res4_mesh(bunny_res4):
    """bunny_res4 as (vertices, faces) arrays, and a K=12 mixture of its triangles."""
    vertices, faces = np.asarray(bunny_res4.vertices), np.asarray(bunny_res4.faces)
    return vertices, faces, GaussianMixture(12, random_state=0, max_iter=5).fit(Primitives.from_mesh(vertices, faces))


def test_the_identities_hold_to_rounding(res4_mesh):
    rows = identity_rows(*res4_mesh, random_triangles=50, n_components=4, n_iter=10, reg_covar=1e-6, samples=64,
                         seed=0)
    assert [row["identity"] for row in rows] == ["cgal_triangle_moment", "cgal_five_times_tetrahedron",
                                                 "mean_update_exact_equals_approx", "hierarchical_gmm_update",
                                                 "points_equal_sklearn", "triangle_bound_monte_carlo",
                                                 "general_bound_monte_carlo"]
    assert rows[0]["cases"] == 948 + 50
    assert all(_relative(row) < 1e-11 and row["noise"] == 0 for row in rows[:5]), rows
    # the row is its worst quantity, and the detail names every quantity compared
    assert rows[2]["detail"].count(" of ") == 3 and "exact - approx covariances" in rows[2]["detail"]


def _triangle_quadrature(triangle, weight, mean, covariance):
    """``∫ log(λ N(x)) dx / area`` over one triangle by the edge-midpoint rule, exact for the quadratic integrand."""
    midpoints = (triangle + np.roll(triangle, 1, axis=0)) / 2
    return np.log(weight) + multivariate_normal.logpdf(midpoints, mean, covariance).mean()


@pytest.mark.parametrize("seed", range(3))
def test_the_bounds_are_their_monte_carlo_integrals(res4_mesh, seed):
    """Eq. 8 on the mesh and eq. 11 on Gaussian primitives lie within 3 standard errors of their integrals; the
    printed eq. 11 (its Σ_p read as tr Σ_p) lies far outside, so the comparison can tell a wrong closed form."""
    vertices, faces, mixture = res4_mesh
    rng = np.random.default_rng(seed)
    triangle = identities.triangle_bound_monte_carlo(vertices, faces, mixture, 256, rng)
    general = identities.general_bound_monte_carlo(mixture, 4, 256, rng)
    for row in (triangle, general):
        assert 0 < row["noise"] < 0.05 and row["max_error"] < 3 * row["noise"], row
    printed = float(general["detail"].split("as printed (−Σ_p read as −tr Σ_p) ")[1].split(",")[0])
    sampled = float(general["detail"].split("Monte Carlo ")[1].split(" ")[0])
    assert abs(printed - sampled) > 10 * general["noise"]


def test_the_monte_carlo_samples_cover_a_triangle_uniformly():
    """One triangle, one component: the sampled integral matches the exact edge-midpoint quadrature."""
    triangle = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.2], [0.3, 0.8, -0.1]])
    mixture = GaussianMixture.from_parameters(np.ones(1), np.array([[0.5, 0.5, 0.0]]), 0.1 * np.eye(3)[None])
    row = identities.triangle_bound_monte_carlo(triangle, np.array([[0, 1, 2]]), mixture, 20000,
                                                np.random.default_rng(0))
    exact = _triangle_quadrature(triangle, 1.0, mixture.means_[0], mixture.covariances_[0])
    sampled = float(row["detail"].split("Monte Carlo ")[1].split(" ")[0])
    assert abs(sampled - exact) < 3 * row["noise"] and row["max_error"] < 3 * row["noise"]


def test_a_wrong_cgal_moment_matrix_fails(res4_mesh):
    """A planted wrong matrix, 4 times the tetrahedron's instead of CGAL's 5 times, fails by far."""
    vertices, faces, _ = res4_mesh
    wrong = 4 * CGAL_TETRAHEDRON_MOMENT
    row = identities.cgal_triangle_moment(vertices, faces, 20, np.random.default_rng(0), moment=wrong)
    assert _relative(row) > 0.1
    assert _relative(identities.cgal_five_times_tetrahedron(wrong)) == pytest.approx(0.2)


def test_a_perturbed_triangle_covariance_fails_the_mean_update_identity(res4_mesh, monkeypatch):
    triangle_covariances = identities.triangle_covariances
    monkeypatch.setattr(identities, "triangle_covariances", lambda triangles: 1.01 * triangle_covariances(triangles))
    row = identities.mean_update_exact_equals_approx(*res4_mesh[:2], 4, np.random.default_rng(0))
    assert _relative(row) == pytest.approx(0.01 / 1.01, rel=1e-6)  # the covariance term is off by 1%


def test_a_hierarchical_update_without_the_primitives_covariances_fails(res4_mesh, monkeypatch):
    update = identities.weighted_update
    monkeypatch.setattr(identities, "weighted_update",
                        lambda h, sizes, means, covariances: update(h, sizes, means, 0 * covariances))
    assert _relative(identities.hierarchical_gmm_update(res4_mesh[2], 4, np.random.default_rng(0))) > 0.01


def test_scikit_learn_one_iteration_short_fails(res4_mesh, monkeypatch):
    sklearn_fit = identities.sklearn_fit
    monkeypatch.setattr(identities, "sklearn_fit",
                        lambda points, start, n_iter, reg_covar: sklearn_fit(points, start, n_iter - 1, reg_covar))
    assert _relative(identities.points_equal_sklearn(res4_mesh[0], 4, 10, 1e-6, np.random.default_rng(0))) > 1e-6


def test_interleaved_repeats_run_every_setting_once_per_repeat_in_alternating_order():
    calls = []
    settings = {name: (lambda case, name=name: calls.append((case, name)) or f"{name} on {case}")
                for name in ("a", "b", "c")}
    rows = interleaved_times("check", ["x", "y", "z"], settings, lambda case, setting, result: (7, result))
    assert calls == [("x", "a"), ("x", "b"), ("x", "c"), ("y", "c"), ("y", "b"), ("y", "a"),
                     ("z", "a"), ("z", "b"), ("z", "c")]
    assert [(row["repeat"], row["setting"]) for row in rows] == [(0, "a"), (0, "b"), (0, "c"), (1, "c"), (1, "b"),
                                                                 (1, "a"), (2, "a"), (2, "b"), (2, "c")]
    assert all(set(row) == set(COLUMNS) and row["check"] == "check" and row["iterations"] == 7 for row in rows)
    assert rows[3]["detail"] == "c on y" and all(row["seconds"] >= 0 for row in rows)
    assert setting_order(settings, 4) == ["a", "b", "c"] and setting_order(settings, 5) == ["c", "b", "a"]


def test_timing_checks_are_the_configurable_ones():
    schema = yaml.safe_load((REPO / "workflow" / "schemas" / "config.schema.yaml").read_text())
    assert set(TIMING_CHECKS) == set(schema["properties"]["checks"]["properties"]["timing"]["properties"])
    assert set(TIMING_CHECKS) == set(yaml.safe_load((REPO / "config.yaml").read_text())["checks"]["timing"])


def _assert_paired(rows, check, settings, repeats):
    """Every setting once per repeat, in the given order on even repeats and reversed on odd ones."""
    expected = [(repeat, setting) for repeat in range(repeats) for setting in (settings if repeat % 2 == 0
                                                                               else settings[::-1])]
    assert [(row["repeat"], row["setting"]) for row in rows] == expected
    assert all(row["check"] == check and row["seconds"] > 0 for row in rows)


def test_mesh_timing_rows(res4_mesh):
    mesh = res4_mesh[:2]
    rows = approximation_times(mesh, repeats=2, n_components=5, max_iter=2, root_seed=0)
    _assert_paired(rows, "approximation", ["exact", "approx", "centroids"], 2)
    assert {row["iterations"] for row in rows} == {2}
    rows = decimation_times(mesh, repeats=2, budget=300) + sampling_times(mesh, repeats=2, budget=100)
    _assert_paired(rows[:4], "decimation", ["clustering", "quadric"], 2)
    _assert_paired(rows[4:], "sampling", ["random", "poisson"], 2)
    assert rows[1]["detail"] == "300 faces" and rows[4]["detail"] == "100 points" and rows[0]["iterations"] == ""


def test_registration_timing_rows(res4_mesh, bunny_res4):
    vertices, faces, mixture = res4_mesh
    rows = d2d_determinant_times((vertices, faces), repeats=2, n_components=5, root_seed=0)
    _assert_paired(rows, "d2d determinant", ["determinant-free", "with determinant"], 2)
    assert all(row["detail"].startswith("rotation error ") for row in rows)
    dense = trimesh.sample.sample_surface(bunny_res4, 2000, seed=1)[0]
    rows = cpd_p2d_times((vertices, faces), dense, mixture, repeats=2, root_seed=0, key="test", max_angle_deg=15.0,
                         max_translation=0.05, cpd={"max_iter": 5, "tol": 1e-9}, gradient="analytic")
    _assert_paired(rows, "cpd vs p2d", ["cpd", "cpd dgmm", "p2d", "p2d numerical", "p2d authors"], 2)
    by_setting = {(row["repeat"], row["setting"]): row for row in rows}
    for repeat in range(2):  # pycpd and dgmm's copy of it: the same iterations and the same pose
        assert by_setting[repeat, "cpd"]["iterations"] == by_setting[repeat, "cpd dgmm"]["iterations"] == 5
        assert by_setting[repeat, "cpd"]["detail"] == by_setting[repeat, "cpd dgmm"]["detail"]


def test_the_authors_p2d_scores_with_scikit_learn_and_lands_where_ours_does(res4_mesh):
    """registration_test.py's P2D: its cost is scikit-learn's score of the mixture (the same mean log-likelihood as
    dgmm's), and from a small known motion it lands on ours' pose."""
    vertices, _, mixture = res4_mesh
    authors = timing_registration.sklearn_mixture(mixture)
    assert authors.score(vertices) == pytest.approx(mixture.score(vertices), abs=1e-9)
    rotation = Rotation.from_euler("xyz", [3, -2, 4], degrees=True).as_matrix()
    moved = vertices @ rotation.T + [0.002, -0.001, 0.003]
    theirs = timing_registration.register_p2d_authors(moved, authors)
    ours = register_p2d(moved, mixture, gradient="numeric", compiled=False)
    assert rotation_distance_deg(theirs.rotation, ours.rotation) < 0.05
    np.testing.assert_allclose(theirs.translation, ours.translation, atol=1e-4)


ODOMETRY = dict(name=FR1_XYZ.name, root_seed=0, intrinsics="ros", n_components=10, schedule="overlap", warm_iter=0,
                pixel_size="area", icp_points=500)


def test_odometry_timing_rows():
    sequence = read_sequence(FR1_XYZ)
    rows = d2d_primitives_times(sequence, repeats=2, **ODOMETRY)
    _assert_paired(rows, "d2d primitives", ["pixels", "pixels bfgs", "points", "points bfgs"], 2)
    rows = odometry_frame_times(sequence, repeats=2, **ODOMETRY)
    _assert_paired(rows, "odometry frame", ["gmm-pixels", "icp"], 2)
    assert all(row["detail"].startswith("rotation error ") for row in rows)


CHECK_TABLES = ("convergence.csv", "resampling.csv", "optimisers.csv", "identities.csv")


@pytest.mark.slow  # the check jobs of the session's Snakemake run on tests/config.yaml, and a rerun of a copy
def test_check_jobs_write_their_tables_and_rerun_byte_identical(workflow_run, tmp_path):
    targets = [f"results/tables/{name}" for name in (*CHECK_TABLES, "optimisers_seconds.csv", "timing_seconds.csv")]
    assert all((workflow_run / target).is_file() for target in targets)  # `snakemake checks` wrote them
    tables = workflow_run / "results" / "tables"
    first = {name: (tables / name).read_bytes() for name in CHECK_TABLES}
    convergence = read_csv(tables / "convergence.csv")
    assert {(row["input"], row["variant"]) for row in convergence} == {
        ("res4-exact", "textbook"), ("res4-exact", "authors"), ("res4-vertices", "textbook")}
    # after 25 of its 30 iterations a fit is the fitting sweep's fit of the same seed (tests/config.yaml: none at
    # K=12, so fit one here the way the sweep does)
    data = workflow_run / "results" / "data" / "bunny"
    vertices, faces = load_mesh(data / "res4.ply")
    row = next(row for row in convergence if row["input"] == "res4-exact" and row["variant"] == "textbook")
    sweep_rows, _ = fit_seeds(build_input("res4-exact", vertices, faces), load_points(data / "res4_eval.ply"),
                              n_components=12,
                              init="kmeans", variant="textbook", n_seeds=1, root_seed=0,
                              key="bunny/res4-exact/textbook/k12-kmeans", max_iter=25, tol=1e-12, reg_covar=1e-6)
    assert float(row["eval_ll_25"]) == pytest.approx(sweep_rows[0]["eval_ll"], abs=1e-9)
    assert {row["check"] for row in read_csv(tables / "timing_seconds.csv")} == {
        name.replace("_", " ") for name in TIMING_CHECKS}
    assert all(float(row["max_error"]) <= max(1e-9 * float(row["scale"]), 4 * float(row["noise"]))
               for row in read_csv(tables / "identities.csv"))
    copy = copy_run(workflow_run, tmp_path / "copy")
    for name in CHECK_TABLES:
        (copy / "results" / "tables" / name).unlink()
    rerun = run_snakemake(copy, *targets)
    assert rerun.returncode == 0, rerun.stderr[-3000:]
    assert {name: (copy / "results" / "tables" / name).read_bytes() for name in CHECK_TABLES} == first
