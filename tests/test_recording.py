"""Recorders read back with independent readers: mcap's reader with Foxglove's protobuf decoder (mcap-protobuf-support)
and jsonschema, the rerun CLI and rerun's chunk reader (recordings and their blueprints).

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
from foxglove_schemas_protobuf.PosesInFrame_pb2 import PosesInFrame
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from mcap.decoder import DecoderFactory
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory as ProtobufDecoderFactory
from mcap_protobuf.schema import build_file_descriptor_set
from rerun.chunk import RrdReader
from scipy.spatial.transform import Rotation

from dgmm.errors import InputError
from dgmm.mixture import GaussianMixture
from dgmm.odometry import OdometryFrame
from dgmm.recording import (
    DEFAULT_N_SIGMA,
    FitRecorder,
    McapWriter,
    OdometryRecorder,
    RegistrationRecorder,
    covariance_ellipsoids,
    json_schemas,
    poses_in_frame,
)
from dgmm.registration import Registration, RigidTrial, register_p2d
from dgmm.odometry.tum import Trajectory

RERUN_CLI = str(Path(sys.executable).parent / "rerun")  # installed with rerun-sdk beside the interpreter



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


class JsonDecoderFactory(DecoderFactory):
    """mcap decoder of JSON messages (mcap ships none)."""

    def decoder_for(self, message_encoding, schema):
        return json.loads if message_encoding == "json" else None


def read_mcap(path):
    """Messages of an MCAP file as a list of (topic, schema, decoded message, log_time): protobuf messages decoded
    by mcap-protobuf-support from the file's own schema, JSON messages as dicts."""
    with open(path, "rb") as stream:
        reader = make_reader(stream, decoder_factories=[ProtobufDecoderFactory(), JsonDecoderFactory()])
        return [(channel.topic, schema, decoded, message.log_time)
                for schema, channel, message, decoded in reader.iter_decoded_messages(log_time_order=False)]


def read_blueprint(path):
    """The blueprint of an .rrd file: (timeline of the time panel, {view name: (kind, origin, contents)})."""
    reader = RrdReader(path)
    (store,) = reader.blueprints()
    rows = {}
    for chunk in reader.store(store=store).stream().to_chunks():
        for row in chunk.to_record_batch().to_pylist():
            rows.setdefault(chunk.entity_path, {}).update({k: v for k, v in row.items() if v is not None})
    views = {row["ViewBlueprint:display_name"][0]: (row["ViewBlueprint:class_identifier"][0],
                                                    row["ViewBlueprint:space_origin"][0],
                                                    rows[f"{entity}/ViewContents"]["ViewContents:query"])
             for entity, row in rows.items() if "ViewBlueprint:display_name" in row}
    return rows["/time_panel"]["TimePanelBlueprint:timeline"][0], views


def xyz(vector, keys="xyz"):
    """The fields ``keys`` of a protobuf vector, quaternion or colour, as an array."""
    return np.array([getattr(vector, key) for key in keys])


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
        if schema.encoding == "protobuf":  # the maintained package's schema, under its well-known name
            assert schema.name == type(message).DESCRIPTOR.full_name == SceneUpdate.DESCRIPTOR.full_name
            assert schema.data == build_file_descriptor_set(SceneUpdate).SerializeToString()
        else:
            assert schema.encoding == "jsonschema"
            schema_json = json.loads(schema.data)
            jsonschema.Draft202012Validator.check_schema(schema_json)
            jsonschema.validate(message, schema_json)
            assert schema_json["title"] == schema.name and schema.name.startswith("dgmm.")
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

    scenes = [(schema.name, m, log_time) for topic, schema, m, log_time in messages if topic == "/fit/mixture"]
    assert [name for name, *_ in scenes] == ["foxglove.SceneUpdate"] * len(seeds)
    for (_, scene, log_time), seed, model in zip(scenes, seeds, models):
        (entity,) = scene.entities
        assert entity.id == f"seed-{seed}" and entity.frame_id == "world"
        assert entity.timestamp.seconds * 10**9 + entity.timestamp.nanos == log_time
        metadata = {kv.key: kv.value for kv in entity.metadata}
        assert float(metadata["bound"]) == model.history_[-1]
        n_sigma = float(metadata["n_sigma"])
        assert len(entity.spheres) == 3
        for sphere, mean, covariance in zip(entity.spheres, model.means_, model.covariances_):
            np.testing.assert_array_equal(xyz(sphere.pose.position), mean)
            check_ellipsoid(covariance, xyz(sphere.pose.orientation, "xyzw"), xyz(sphere.size) / 2, n_sigma)


def test_no_hand_written_foxglove_schema_remains():
    """dgmm's JSON schemas are its own messages; every Foxglove type comes from the maintained package."""
    titles = [value["title"] for name, value in vars(json_schemas).items() if name.endswith("_SCHEMA")]
    assert titles and all(title.startswith("dgmm.") for title in titles)


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

    timeline, views = read_blueprint(rrd_path)
    assert timeline == "iteration"
    assert views == {"input and mixture": ("3D", "/", ["/input", "/mixture"]),
                     "bound": ("TimeSeries", "/bound", ["$origin/**"])}

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


def _interrupt_after(monkeypatch, owner, name):
    """Make ``owner.name`` run for real, then raise KeyboardInterrupt: Ctrl-C landing just after a file opened."""
    real = getattr(owner, name)

    def interrupted(*args, **kwargs):
        real(*args, **kwargs)
        raise KeyboardInterrupt

    monkeypatch.setattr(owner, name, interrupted)


@pytest.mark.parametrize("recorder", [FitRecorder, RegistrationRecorder, OdometryRecorder])
@pytest.mark.parametrize("opened", ["mcap", "rrd"])
def test_ctrl_c_while_a_recorder_opens_leaves_no_files(tmp_path, monkeypatch, recorder, opened):
    """The recorder's constructor never returned, so only the constructor can discard what it opened."""
    import mcap.writer
    import rerun

    if opened == "mcap":
        _interrupt_after(monkeypatch, mcap.writer.Writer, "start")
    else:
        _interrupt_after(monkeypatch, rerun.RecordingStream, "save")
    with pytest.raises(KeyboardInterrupt):
        recorder(tmp_path / "out.mcap", tmp_path / "out.rrd")
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_while_rerun_builds_its_stream_is_held_until_the_stream_exists(tmp_path, monkeypatch):
    """SIGINT in the middle of rerun's RecordingStream constructor: without holding it, the half-built stream's
    ``__del__`` raises (it assumes the finished object) and Python prints that traceback on stderr."""
    import gc
    import os
    import signal

    import rerun

    real = rerun.RecordingStream.__init__

    def interrupted(self, *args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C lands here, before the stream is made
        real(self, *args, **kwargs)

    monkeypatch.setattr(rerun.RecordingStream, "__init__", interrupted)
    unraisable = []
    monkeypatch.setattr(sys, "unraisablehook", unraisable.append)
    inherited = signal.signal(signal.SIGINT, signal.default_int_handler)  # a suite started with `&` ignores SIGINT
    try:
        with pytest.raises(KeyboardInterrupt):
            FitRecorder(tmp_path / "out.mcap", tmp_path / "out.rrd")
    finally:
        signal.signal(signal.SIGINT, inherited)
    gc.collect()
    assert unraisable == [] and list(tmp_path.iterdir()) == []


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
            out.write(f"/register/{name}", poses_in_frame(r, t, log_time_ns=out.next_log_time()))
        with pytest.raises(InputError, match="carries"):
            out.write("/register/true", {"seed": 0}, {"title": "other.Message"})
        with pytest.raises(InputError, match="its own schema"):
            out.write("/register/other", poses_in_frame(r, t, log_time_ns=0), {"title": "other.Message"})
        with pytest.raises(ValueError):
            out.write("/register/nan", {"x": float("nan")}, {"title": "other.Message"})

    messages = read_mcap(tmp_path / "poses.mcap")
    assert [topic for topic, *_ in messages] == ["/register/true", "/register/estimated"]
    topic, schema, message, log_time = messages[0]
    assert schema.name == "foxglove.PosesInFrame" and schema.encoding == "protobuf"
    assert schema.data == build_file_descriptor_set(PosesInFrame).SerializeToString()
    assert (message.timestamp.seconds, message.timestamp.nanos, message.frame_id) == (0, 0, "world")
    assert len(message.poses) == 5
    for pose, rotation, translation in zip(message.poses, rotations, translations):
        np.testing.assert_array_equal(xyz(pose.position), translation)
        np.testing.assert_allclose(quaternion_matrix(xyz(pose.orientation, "xyzw")), rotation, atol=1e-12)


def test_registration_recorder_writes_poses_and_a_blueprint_per_recorded_trial(tmp_path):
    source = blobs(seed=9, n_per_blob=40)
    mixture = GaussianMixture(3, max_iter=20, random_state=0).fit(source)
    rotation = Rotation.from_euler("xyz", [5.0, -4.0, 3.0], degrees=True).as_matrix()
    trial = RigidTrial(rotation, np.array([0.1, -0.2, 0.05]), source.mean(axis=0))
    mcap_path, rrd_path = tmp_path / "trials.mcap", tmp_path / "trials.rrd"
    with RegistrationRecorder(mcap_path, rrd_path, mixture=mixture, recorded_trials={0}) as recorder:
        for index in (0, 1):
            callback = recorder.begin_trial(index, trial, source)
            assert (callback is None) == (index == 1)
            result = register_p2d(trial.apply(source), mixture, callback=callback)
            recorder.end_trial(result, 0.0, 0.0)

    timeline, views = read_blueprint(rrd_path)
    assert timeline == "iteration"
    assert views == {"trial 0": ("3D", "/", ["/mixture", "/trial-0/**", "- /trial-0/objective"]),
                     "objective": ("TimeSeries", "/", ["/trial-0/objective"])}
    objective = read_rrd(rrd_path, "/trial-0/objective")
    assert objective["iteration"] == list(range(1, result.iterations + 1))
    assert not read_rrd(rrd_path, "/trial-1/source")

    messages = read_mcap(mcap_path)
    (scene,) = [m for topic, _, m, _ in messages if topic == "/registration/mixture"]
    np.testing.assert_array_equal([xyz(s.pose.position) for s in scene.entities[0].spheres], mixture.means_)
    true_poses = [m for topic, _, m, _ in messages if topic == "/registration/true_pose"]
    assert [type(m).DESCRIPTOR.full_name for m in true_poses] == ["foxglove.PosesInFrame"] * 2
    (pose,) = true_poses[0].poses  # the pose of the moved source: R and c + t - R c
    np.testing.assert_allclose(quaternion_matrix(xyz(pose.orientation, "xyzw")), rotation, atol=1e-12)
    np.testing.assert_allclose(xyz(pose.position), trial.apply(np.zeros((1, 3)))[0], atol=1e-12)


def test_odometry_recorder_writes_trajectories_and_its_blueprint(tmp_path):
    n_frames = 3
    rotations = Rotation.from_euler("z", np.arange(n_frames)[:, None] * 10.0, degrees=True).as_matrix()
    translations = np.arange(n_frames)[:, None] * np.array([0.1, 0.0, 0.02])
    truth = Trajectory(np.arange(n_frames) * 0.5 + 100.0, rotations, translations)
    model = GaussianMixture(3, max_iter=5, random_state=0).fit(blobs(seed=3, n_per_blob=30))
    mcap_path, rrd_path = tmp_path / "odometry.mcap", tmp_path / "odometry.rrd"
    depth = np.full((480, 640), 1.2345)  # metres: logged at every 4th pixel in millimetres, 1235
    with OdometryRecorder(mcap_path, rrd_path, groundtruth=truth, camera_frame="depth_optical",
                          pixel_step=4) as recorder:
        for index in range(n_frames):
            registration = None if index == 0 else Registration(np.eye(3), np.zeros(3), 4, 0.01, 1.5, True, "d2d")
            recorder(OdometryFrame(index, float(truth.timestamps[index]), rotations[index], translations[index],
                                   model, 0.02, registration, None if index == 0 else 0.03, depth))
        recorder.finish(truth)

    timeline, views = read_blueprint(rrd_path)
    assert timeline == "frame"
    assert views == {"camera path": ("3D", "/world", ["$origin/**"]),
                     "depth image": ("2D", "/world/camera/image", ["$origin/**"]),
                     "current frame's model": ("3D", "/world/camera", ["/world/camera/model"]),
                     "seconds per frame": ("TimeSeries", "/seconds", ["$origin/**"])}
    assert sorted(read_rrd(rrd_path, "/world/camera/model")["frame"]) == list(range(n_frames))
    assert sorted(read_rrd(rrd_path, "/seconds/model")["frame"]) == list(range(n_frames))
    image = read_rrd(rrd_path, "/world/camera/image")
    assert sorted(frame for frame in image["frame"] if frame is not None) == list(range(n_frames))
    assert {stamp for stamp in image["timestamp"] if stamp is not None} == {
        np.datetime64(int(stamp * 1e9), "ns") for stamp in truth.timestamps}

    messages = read_mcap(mcap_path)
    by_topic = {topic: (message, log_time) for topic, _, message, log_time in messages}
    assert messages[0][0] == "/odometry/params" and messages[0][3] == int(truth.timestamps[0] * 1e9)
    poses = [(message, log_time) for topic, _, message, log_time in messages if topic == "/odometry/pose"]
    assert [log_time for _, log_time in poses] == [int(stamp * 1e9) for stamp in truth.timestamps]
    np.testing.assert_array_equal([xyz(pose.pose.position) for pose, _ in poses], translations)
    transforms = [message for topic, _, message, _ in messages if topic == "/odometry/transforms"]
    assert [(t.parent_frame_id, t.child_frame_id) for t in transforms] == [("world", "odometry")] + [
        ("odometry", "depth_optical")] * n_frames
    for transform, rotation, translation in zip(transforms[1:], rotations, translations):
        np.testing.assert_allclose(quaternion_matrix(xyz(transform.rotation, "xyzw")), rotation, atol=1e-12)
        np.testing.assert_array_equal(xyz(transform.translation), translation)
    # The frame's whole registration time (0.03 s), not its solver's (Registration.seconds, 0.01 s).
    assert by_topic["/odometry/frame"][0]["registration_seconds"] == 0.03
    estimated, log_time = by_topic["/odometry/estimated"]
    assert estimated.frame_id == "odometry" and log_time == int(truth.timestamps[-1] * 1e9)
    np.testing.assert_array_equal([xyz(p.position) for p in estimated.poses], translations)
    groundtruth, _ = by_topic["/odometry/groundtruth"]
    for pose, rotation in zip(groundtruth.poses, rotations):
        np.testing.assert_allclose(quaternion_matrix(xyz(pose.orientation, "xyzw")), rotation, atol=1e-12)
