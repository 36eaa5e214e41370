"""Recorders read back with independent readers: mcap's reader + jsonschema, the rerun CLI and rerun's chunk reader.

Ellipsoids are checked against the covariances they came from through a quaternion-to-matrix formula written
here, not the code's own conversion.
"""
import itertools
import json
import subprocess
import sys
from pathlib import Path

import jsonschema
import numpy as np
import pytest
import trimesh
from mcap.reader import make_reader
from rerun.chunk import RrdReader
from scipy.spatial.transform import Rotation

from dgmm.errors import InputError
from dgmm.mixture import GaussianMixture
from dgmm.recording import (
    DEFAULT_N_SIGMA,
    POSES_IN_FRAME_SCHEMA,
    FitRecorder,
    McapWriter,
    covariance_ellipsoids,
    poses_in_frame,
)

RERUN_CLI = str(Path(sys.executable).parent / "rerun")  # installed with rerun-sdk beside the interpreter

# Required fields of Foxglove's published JSON schemas (foxglove-sdk schemas/jsonschema/SceneUpdate.json).
FOXGLOVE_SCENE_UPDATE_FIELDS = {"deletions", "entities"}
FOXGLOVE_SCENE_ENTITY_FIELDS = {"timestamp", "frame_id", "id", "lifetime", "frame_locked", "metadata", "arrows",
                                "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models"}
FOXGLOVE_SPHERE_FIELDS = {"pose", "size", "color"}


def quaternion_matrix(q):
    """Rotation matrix of a unit quaternion (x, y, z, w), by the textbook formula."""
    x, y, z, w = np.asarray(q, dtype=np.float64) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def blobs(seed=0, n_per_blob=150):
    """Three anisotropic Gaussian blobs, shape (3 * n_per_blob, 3)."""
    rng = np.random.default_rng(seed)
    centres = np.array([[0.0, 0.0, 0.0], [4.0, 0.0, 1.0], [0.0, 5.0, -2.0]])
    return np.concatenate([c + rng.normal(size=(n_per_blob, 3)) @ rng.normal(size=(3, 3)) for c in centres])


def read_mcap(path):
    """Messages of an MCAP file as a list of (topic, schema, decoded message, log_time)."""
    with open(path, "rb") as stream:
        reader = make_reader(stream)
        return [(channel.topic, schema, json.loads(message.data), message.log_time)
                for schema, channel, message in reader.iter_messages(log_time_order=False)]


def read_rrd(path, entity):
    """Columns of one entity of an .rrd file: component name -> list over rows, rows sorted by ``iteration``."""
    columns = {}
    for chunk in RrdReader(path).store().stream().to_chunks():
        if chunk.entity_path != entity:
            continue
        batch = chunk.to_record_batch()
        for name in batch.schema.names:
            if name not in ("rerun.controls.RowId", "log_time"):
                columns.setdefault(name, []).extend(batch.column(name).to_pylist())
    if "iteration" in columns:
        order = np.argsort(columns["iteration"], kind="stable")
        columns = {name: [values[i] for i in order] for name, values in columns.items()}
    return columns


def record_fit(tmp_path, data, seeds, *, name="fit", clock=None, n_components=3, max_iter=6):
    """Fit ``data`` once per seed with a FitRecorder attached; return the fitted models and the file paths."""
    mcap_path, rrd_path = tmp_path / f"{name}.mcap", tmp_path / f"{name}.rrd"
    params = {"n_components": n_components, "max_iter": max_iter, "seeds": list(seeds)}
    extra = {} if clock is None else {"clock": clock}
    models = []
    with FitRecorder(mcap_path, rrd_path, params=params, data=data, **extra) as recorder:
        for seed in seeds:
            recorder.begin_seed(seed)
            model = GaussianMixture(n_components, max_iter=max_iter, tol=0.0, random_state=seed,
                                    callback=recorder)
            models.append(model.fit(data))
            recorder.end_seed(model)
    return models, mcap_path, rrd_path


def check_ellipsoid(covariance, quaternion, half_sizes, n_sigma):
    """Assert that R diag((h / n_sigma)^2) R^T reproduces the covariance."""
    rotation = quaternion_matrix(quaternion)
    rebuilt = rotation @ np.diag((np.asarray(half_sizes) / n_sigma) ** 2) @ rotation.T
    np.testing.assert_allclose(rebuilt, covariance, rtol=1e-9, atol=1e-12 * np.abs(covariance).max())


# -------------------------------------------------------------------------------------------------------------

def test_covariance_ellipsoids_reproduce_covariances():
    rng = np.random.default_rng(1)
    factors = rng.normal(size=(20, 3, 3))
    covariances = factors @ factors.transpose(0, 2, 1)
    covariances[0] = np.diag([4.0, 1.0, 0.0])  # flat, as for a triangle
    n_sigma = 3.0
    rotations, half_sizes, quaternions = covariance_ellipsoids(covariances, n_sigma)
    np.testing.assert_allclose(np.linalg.det(rotations), 1.0, rtol=1e-12)
    np.testing.assert_allclose(rotations.transpose(0, 2, 1) @ rotations, np.broadcast_to(np.eye(3), (20, 3, 3)),
                               atol=1e-12)
    for covariance, rotation, half, quaternion in zip(covariances, rotations, half_sizes, quaternions):
        np.testing.assert_allclose(quaternion_matrix(quaternion), rotation, atol=1e-12)
        check_ellipsoid(covariance, quaternion, half, n_sigma)
    np.testing.assert_allclose(np.sort(half_sizes[0]), [0.0, 3.0, 6.0], atol=1e-12)


def test_covariance_ellipsoids_reject_bad_shape():
    with pytest.raises(InputError, match="covariances"):
        covariance_ellipsoids(np.eye(3))


def test_fit_recorder_mcap_reads_back(tmp_path):
    data = blobs()
    seeds = (3, 7)
    models, mcap_path, _ = record_fit(tmp_path, data, seeds)
    check = subprocess.run([RERUN_CLI, "mcap", "check", str(mcap_path)], capture_output=True, text=True)
    assert check.returncode == 0, check.stdout + check.stderr
    messages = read_mcap(mcap_path)

    for _, schema, message, _ in messages:
        assert schema.encoding == "jsonschema"
        schema_json = json.loads(schema.data)
        jsonschema.Draft202012Validator.check_schema(schema_json)
        jsonschema.validate(message, schema_json)
        assert schema_json["title"] == schema.name
    log_times = [log_time for *_, log_time in messages]
    assert log_times == sorted(set(log_times))

    params = [m for topic, _, m, _ in messages if topic == "/fit/params"]
    assert params == [{"n_components": 3, "max_iter": 6, "seeds": [3, 7]}]

    iterations = [m for topic, _, m, _ in messages if topic == "/fit/iteration"]
    for seed, model in zip(seeds, models):
        mine = [m for m in iterations if m["seed"] == seed]
        assert [m["iteration"] for m in mine] == list(range(1, model.n_iter_ + 1))
        assert [m["bound"] for m in mine] == model.history_
        seconds = [m["seconds"] for m in mine]
        assert seconds == sorted(seconds) and seconds[0] >= 0

    scenes = [(schema.name, m) for topic, schema, m, _ in messages if topic == "/fit/mixture"]
    assert [name for name, _ in scenes] == ["foxglove.SceneUpdate"] * len(seeds)
    for (_, scene), seed, model in zip(scenes, seeds, models):
        assert FOXGLOVE_SCENE_UPDATE_FIELDS <= scene.keys()
        (entity,) = scene["entities"]
        assert FOXGLOVE_SCENE_ENTITY_FIELDS <= entity.keys()
        assert entity["id"] == f"seed-{seed}"
        n_sigma = float(dict((kv["key"], kv["value"]) for kv in entity["metadata"])["n_sigma"])
        assert len(entity["spheres"]) == 3
        for sphere, mean, covariance in zip(entity["spheres"], model.means_, model.covariances_):
            assert FOXGLOVE_SPHERE_FIELDS <= sphere.keys()
            pose = sphere["pose"]
            np.testing.assert_array_equal([pose["position"][k] for k in "xyz"], mean)
            quaternion = [pose["orientation"][k] for k in "xyzw"]
            half_sizes = np.array([sphere["size"][k] for k in "xyz"]) / 2
            check_ellipsoid(covariance, quaternion, half_sizes, n_sigma)


def test_same_fit_gives_same_mcap_bytes(tmp_path):
    data = blobs(seed=2)
    paths = [record_fit(tmp_path, data, (0, 1), name=f"run{i}", clock=itertools.count().__next__)[1]
             for i in range(2)]
    assert paths[0].read_bytes() == paths[1].read_bytes()


def test_fit_recorder_rrd_replays_first_seed_on_mesh(tmp_path):
    mesh = trimesh.creation.icosphere(subdivisions=2)
    mesh.apply_scale([1.0, 2.0, 0.5])
    (first, second), _, rrd_path = record_fit(tmp_path, mesh, (5, 6), n_components=4, max_iter=5)

    result = subprocess.run([RERUN_CLI, "rrd", "verify", str(rrd_path)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr

    mesh_columns = read_rrd(rrd_path, "/input")
    np.testing.assert_allclose(mesh_columns["Mesh3D:vertex_positions"][0], mesh.vertices, rtol=1e-6)
    np.testing.assert_array_equal(mesh_columns["Mesh3D:triangle_indices"][0], mesh.faces)

    bound = read_rrd(rrd_path, "/bound")
    assert bound["iteration"] == list(range(1, first.n_iter_ + 1))
    assert [scalars[0] for scalars in bound["Scalars:scalars"]] == first.history_

    mixture = read_rrd(rrd_path, "/mixture")
    assert mixture["iteration"] == list(range(1, first.n_iter_ + 1))
    assert all(len(centers) == 4 for centers in mixture["Ellipsoids3D:centers"])
    np.testing.assert_allclose(mixture["Ellipsoids3D:centers"][-1], first.means_, rtol=1e-6, atol=1e-6)
    for covariance, quaternion, half_sizes in zip(first.covariances_, mixture["Ellipsoids3D:quaternions"][-1],
                                                  mixture["Ellipsoids3D:half_sizes"][-1]):
        rotation = quaternion_matrix(quaternion)
        rebuilt = rotation @ np.diag((np.asarray(half_sizes) / DEFAULT_N_SIGMA) ** 2) @ rotation.T
        # The recording stores float32 (eps 1.2e-7): compare to a few eps of the largest axis.
        np.testing.assert_allclose(rebuilt, covariance, atol=1e-6 * np.abs(covariance).max())


def test_rrd_of_points_holds_the_points(tmp_path):
    data = blobs(seed=4, n_per_blob=40)
    _, _, rrd_path = record_fit(tmp_path, data, (0,), max_iter=2)
    points = read_rrd(rrd_path, "/input")["Points3D:positions"]
    np.testing.assert_allclose(points[0], data, rtol=1e-6, atol=1e-6)


def test_failed_run_leaves_no_files(tmp_path):
    data = blobs(seed=5, n_per_blob=30)
    with pytest.raises(RuntimeError, match="job failed"):
        with FitRecorder(tmp_path / "fit.mcap", tmp_path / "fit.rrd", data=data) as recorder:
            recorder.begin_seed(0)
            GaussianMixture(2, max_iter=2, random_state=0, callback=recorder).fit(data)
            assert not (tmp_path / "fit.mcap").exists() and not (tmp_path / "fit.rrd").exists()
            raise RuntimeError("job failed")
    assert list(tmp_path.iterdir()) == []


def test_recorder_needs_a_seed(tmp_path):
    with FitRecorder(tmp_path / "fit.mcap") as recorder:
        with pytest.raises(InputError, match="begin_seed"):
            GaussianMixture(2, max_iter=1, callback=recorder).fit(blobs(n_per_blob=10))
    assert [p.name for p in tmp_path.iterdir()] == ["fit.mcap"]


def test_poses_in_frame_through_mcap_writer(tmp_path):
    rng = np.random.default_rng(8)
    rotations = Rotation.random(5, random_state=rng).as_matrix()
    translations = rng.normal(size=(5, 3))
    with McapWriter(tmp_path / "poses.mcap") as out:
        for name, (r, t) in {"true": (rotations, translations), "estimated": (rotations[::-1], translations)}.items():
            out.write(f"/register/{name}", poses_in_frame(r, t, log_time_ns=out.next_log_time()),
                      POSES_IN_FRAME_SCHEMA)
        with pytest.raises(InputError, match="carries"):
            out.write("/register/true", {"seed": 0}, {"title": "other.Message"})
        with pytest.raises(ValueError):
            out.write("/register/nan", {"x": float("nan")}, {"title": "other.Message"})

    messages = read_mcap(tmp_path / "poses.mcap")
    assert [topic for topic, *_ in messages] == ["/register/true", "/register/estimated"]
    topic, schema, message, log_time = messages[0]
    assert schema.name == "foxglove.PosesInFrame"
    jsonschema.validate(message, json.loads(schema.data))
    assert message["timestamp"] == {"sec": 0, "nsec": 0}
    for pose, rotation, translation in zip(message["poses"], rotations, translations):
        np.testing.assert_array_equal([pose["position"][k] for k in "xyz"], translation)
        np.testing.assert_allclose(quaternion_matrix([pose["orientation"][k] for k in "xyzw"]), rotation,
                                   atol=1e-12)
