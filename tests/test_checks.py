"""dgmm.experiments.checks against independent references: scipy's rotations and Gaussian density, Monte Carlo
integrals over triangles, and counts by hand."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from scipy.stats import multivariate_normal

from dgmm.data import load_mesh, load_points
from dgmm.experiments.checks.convergence import coverage, effective_components, iterations_to_converge
from dgmm.experiments.checks.optimisers import _rotvec_params
from dgmm.experiments.checks.resampling import component_integrals, split_in_four
from dgmm.experiments.checks.timing import d2d_cost
from dgmm.experiments.sweep import build_input, fit_seeds
from dgmm.mixture import GaussianMixture
from dgmm.primitives import Primitives
from dgmm.runtime.tables import read_csv
from tests.workflow import run_snakemake


def test_iterations_to_converge_is_the_first_iteration_that_stays_within_the_tolerance():
    history = [1.0, 1.5, 1.95, 2.1, 1.9, 1.99, 2.0]  # within 0.05 of 2.0 at iterations 3, then 6 for good
    assert iterations_to_converge(history, 0.05) == 6
    assert iterations_to_converge(history, 0.15) == 3
    assert iterations_to_converge([5.0, 5.0], 0.01) == 1


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


CHECK_TABLES = ("convergence.csv", "resampling.csv", "optimisers.csv")


@pytest.mark.slow  # a real Snakemake run of the check jobs on tests/config.yaml
def test_check_jobs_write_their_tables_and_rerun_byte_identical(tmp_path):
    targets = [f"results/tables/{name}" for name in (*CHECK_TABLES, "optimisers_seconds.csv", "timing_seconds.csv")]
    run = run_snakemake(tmp_path, *targets)
    assert run.returncode == 0, run.stderr[-3000:]
    tables = tmp_path / "results" / "tables"
    first = {name: (tables / name).read_bytes() for name in CHECK_TABLES}
    convergence = read_csv(tables / "convergence.csv")
    assert {(row["input"], row["variant"]) for row in convergence} == {
        ("res4-exact", "textbook"), ("res4-exact", "authors"), ("res4-vertices", "textbook")}
    # after 25 of its 30 iterations a fit is the fitting sweep's fit of the same seed (tests/config.yaml: none at
    # K=12, so fit one here the way the sweep does)
    vertices, faces = load_mesh(tmp_path / "results" / "data" / "bunny" / "res4.ply")
    row = next(row for row in convergence if row["input"] == "res4-exact" and row["variant"] == "textbook")
    sweep_rows, _ = fit_seeds(build_input("res4-exact", vertices, faces),
                              load_points(tmp_path / "results" / "data" / "bunny" / "res4_eval.ply"), n_components=12,
                              init="kmeans", variant="textbook", n_seeds=1, root_seed=0,
                              key="bunny/res4-exact/textbook/k12-kmeans", max_iter=25, tol=1e-12, reg_covar=1e-6)
    assert float(row["eval_ll_25"]) == pytest.approx(sweep_rows[0]["eval_ll"], abs=1e-9)
    assert {row["check"] for row in read_csv(tables / "timing_seconds.csv")} == {"approximation", "d2d determinant"}
    for name in CHECK_TABLES:
        (tables / name).unlink()
    rerun = run_snakemake(tmp_path, *targets)
    assert rerun.returncode == 0, rerun.stderr[-3000:]
    assert {name: (tables / name).read_bytes() for name in CHECK_TABLES} == first
