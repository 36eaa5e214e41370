"""The synthetic sequence's ray caster against brute force: every ray against every triangle by plane intersection
and inside-edge tests (not Möller–Trumbore), no bounding boxes, no blocks."""
import numpy as np
import trimesh

from dgmm.odometry.pixels import FR3
from dgmm.odometry.synthetic import handheld_trajectory, render_depth, room_scene


def _brute_force_depth(rays, origin, triangles):
    """Nearest hit parameter, |cos| of incidence and triangle index of each ray (inf, 0, -1 where none)."""
    v0, v1, v2 = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    normal = np.cross(v1 - v0, v2 - v0)  # (n_triangles, 3)
    facing = rays @ normal.T  # (n_rays, n_triangles)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((v0 - origin) * normal).sum(axis=1) / facing
    hits = origin + t[:, :, None] * rays[:, None, :]  # each ray's point on each triangle's plane
    inside = np.ones(t.shape, dtype=bool)
    for a, b in ((v0, v1), (v1, v2), (v2, v0)):  # on the inner side of all three edges
        inside &= (np.cross(b - a, hits - a) * normal).sum(axis=2) >= 0
    t = np.where(inside & (t > 1e-9) & (np.abs(facing) > 0), t, np.inf)
    nearest = t.argmin(axis=1)
    rows = np.arange(len(rays))
    found = np.isfinite(t[rows, nearest])
    cosine = np.abs(facing[rows, nearest]) / (np.linalg.norm(normal[nearest], axis=1) * np.linalg.norm(rays, axis=1))
    return t[rows, nearest], np.where(found, cosine, 0.0), np.where(found, nearest, -1)


def test_render_depth_matches_brute_force_ray_casting():
    # The room with an icosphere on the table (many small triangles in tight groups), seen from the hand-held path;
    # 80 x 60 rays, so the ray-triangle tests run in several blocks.
    sphere = trimesh.creation.icosphere(subdivisions=2).triangles
    triangles = room_scene([sphere], model_height=0.5)
    path = handheld_trajectory(200, seed=3)
    for sample in (0, 150):
        rotation, origin = path.rotations[sample], path.translations[sample]
        depth, cosine = render_depth(triangles, rotation, origin, FR3, step=8)
        expected, expected_cosine, index = _brute_force_depth(FR3.rays(8) @ rotation.T, origin, triangles)
        assert len(depth) == 4800 and np.count_nonzero(index >= 72) > 100  # the sphere is in view
        np.testing.assert_array_equal(np.isfinite(depth), np.isfinite(expected))
        np.testing.assert_allclose(depth, expected, rtol=0, atol=1e-9)
        np.testing.assert_allclose(cosine, expected_cosine, rtol=0, atol=1e-9)
