"""Primitive moments against independent references: Monte Carlo, Heron's formula, quadrature."""
import numpy as np
import pytest
import trimesh

from dgmm import InputError, Primitives
from dgmm.primitives import triangle_moments


def uniform_in_triangle(triangle, n, rng):
    """n points uniform over a triangle (reflected barycentric sampling)."""
    u, v = rng.uniform(size=(2, n))
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    a, b, c = triangle
    return a + u[:, None] * (b - a) + v[:, None] * (c - a)


def test_triangle_moments_equal_monte_carlo_moments():
    rng = np.random.default_rng(0)
    triangle = np.array([[0.3, -1.2, 2.0], [1.7, 0.4, 2.5], [-0.6, 0.9, 1.1]])
    samples = uniform_in_triangle(triangle, 2_000_000, rng)
    centroid, area, covariance = (x[0] for x in triangle_moments(triangle[None]))

    mean_se = samples.std(axis=0) / np.sqrt(len(samples))
    assert np.all(np.abs(centroid - samples.mean(axis=0)) < 5 * mean_se)

    centred = samples - samples.mean(axis=0)
    products = centred[:, :, None] * centred[:, None, :]
    cov_se = products.std(axis=0) / np.sqrt(len(samples))
    assert np.all(np.abs(covariance - products.mean(axis=0)) < 5 * cov_se)

    ab, bc, ca = (np.linalg.norm(triangle[i] - triangle[(i + 1) % 3]) for i in range(3))
    s = (ab + bc + ca) / 2
    assert area == pytest.approx(np.sqrt(s * (s - ab) * (s - bc) * (s - ca)), rel=1e-12)


def test_triangle_covariance_matches_the_paper_vertex_formula():
    rng = np.random.default_rng(1)
    triangles = rng.normal(size=(50, 3, 3)) + 100.0
    _, _, covariances = triangle_moments(triangles)
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    m = triangles.mean(axis=1)
    outer = lambda x: x[:, :, None] * x[:, None, :]  # noqa: E731
    paper = (outer(a) + outer(b) + outer(c) - 3 * outer(m)) / 12
    np.testing.assert_allclose(covariances, paper, rtol=0, atol=1e-9 * np.abs(outer(m)).max())


def test_from_mesh_drops_zero_area_faces_and_rejects_all_degenerate():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0.0]])
    prims = Primitives.from_mesh(vertices, [[0, 1, 2], [0, 1, 3]])  # second face is collinear
    assert len(prims) == 1 and prims.weights[0] == pytest.approx(0.5)
    with pytest.raises(InputError, match="no face of positive area"):
        Primitives.from_mesh(vertices, [[0, 1, 3]])


def test_from_mesh_accepts_trimesh(bunny_res4):
    prims = Primitives.from_mesh(bunny_res4)
    assert len(prims) == len(bunny_res4.faces)
    assert prims.weights.sum() == pytest.approx(bunny_res4.area, rel=1e-12)
    np.testing.assert_allclose(prims.means, bunny_res4.triangles_center, rtol=0, atol=1e-15)


def test_transformed_moves_moments_like_samples():
    rng = np.random.default_rng(2)
    triangle = rng.normal(size=(3, 3))
    rotation = trimesh.transformations.random_rotation_matrix(rng.uniform(size=3))[:3, :3]
    translation = np.array([0.5, -2.0, 3.0])
    moved = Primitives.from_mesh(triangle, [[0, 1, 2]]).transformed(rotation, translation)
    direct = Primitives.from_mesh(triangle @ rotation.T + translation, [[0, 1, 2]])
    np.testing.assert_allclose(moved.means, direct.means, atol=1e-12)
    np.testing.assert_allclose(moved.covariances, direct.covariances, atol=1e-12)


def test_concat_and_without_covariances(bunny_res4):
    mesh = Primitives.from_mesh(bunny_res4)
    points = Primitives.from_points(bunny_res4.vertices)
    both = Primitives.concat(mesh, points)
    assert len(both) == len(mesh) + len(points)
    assert np.all(mesh.without_covariances().covariances == 0)
    assert np.array_equal(mesh.without_covariances().weights, mesh.weights)


def test_primitives_are_immutable():
    prims = Primitives.from_points(np.zeros((3, 3)))
    with pytest.raises(ValueError):
        prims.means[0, 0] = 1.0


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: Primitives.from_points(np.zeros((0, 3))), "points is empty"),
        (lambda: Primitives.from_points(np.zeros((4, 0))), r"points must have shape \(n, d\) with d >= 1"),
        (lambda: Primitives.from_points([[0, 0, np.nan]]), "points contains NaN"),
        (lambda: Primitives.from_points(np.zeros((2, 3)), weights=[1, -1]), "non-negative"),
        (lambda: Primitives.from_points(np.zeros((2, 3)), weights=[0, 0]), "all zero"),
        (lambda: Primitives.from_mesh(np.zeros((4, 3)), [[0, 1, 2, 3]]), "must be triangles"),
        (lambda: Primitives.from_mesh(np.eye(3), [[0, 1, 5]]), "outside"),
        (lambda: Primitives.from_mesh(np.eye(3), np.zeros((0, 3), int)), "no faces"),
    ],
)
def test_bad_input_is_one_line_error(make, message):
    with pytest.raises(InputError, match=message) as info:
        make()
    assert "\n" not in str(info.value)
