"""ROS 2 recordings (MCAP) as odometry input: fr1/xyz's depth frames written with mcap-ros2-support's writer (16UC1
and 32FC1, with and without CameraInfo, a bag folder of two files), Foxglove's RawImage written with
mcap-protobuf-support's, read back and run.

References are independent of the reader under test: the TUM folder's own frames (read from its PNGs), numpy's
conversions of them (float32 metres, millimetres rounded), mcap's own readers and decoders for what the files
hold, and ``rerun mcap check`` for the output.
"""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from foxglove_schemas_protobuf.CameraCalibration_pb2 import CameraCalibration
from foxglove_schemas_protobuf.RawImage_pb2 import RawImage
from google.protobuf.timestamp_pb2 import Timestamp
from mcap.reader import make_reader
from mcap_protobuf.writer import Writer as ProtobufWriter
from mcap_ros2.decoder import DecoderFactory as Ros2DecoderFactory
from mcap_ros2.writer import Writer as Ros2Writer
from threadpoolctl import threadpool_limits

from dgmm.errors import DataError, InputError
from dgmm.odometry import CAMERAS, first_frames, open_sequence, read_sequence, run_odometry
from dgmm.odometry.metrics import absolute_trajectory_error
from dgmm.odometry.ros2_mcap import CAMERA_INFO_MSGDEF, IMAGE_MSGDEF, read_recording, write_recording
from tests.test_odometry_metrics import FR1_XYZ, needs_fr1
from tests.test_recording import read_mcap, xyz

DGMM = Path(sys.executable).with_name("dgmm")
RERUN = Path(sys.executable).with_name("rerun")
DEPTH, INFO = "/camera/depth/image_raw", "/camera/depth/camera_info"
N_FRAMES = 30
ROS = CAMERAS["ros"]

pytestmark = needs_fr1


# ------------------------------------------------------------------------------------------------ writing
def write_images(path, images, camera_info=None, topic=DEPTH):
    """A ROS 2 MCAP of ``sensor_msgs/msg/Image`` messages given as dicts (any encoding, size and stamp), and a
    CameraInfo first when given, written with mcap-ros2-support's writer as dicts of the message's fields."""
    with open(path, "wb") as stream, Ros2Writer(stream) as writer:
        if camera_info is not None:
            writer.write_message(INFO, writer.register_msgdef("sensor_msgs/msg/CameraInfo", CAMERA_INFO_MSGDEF),
                                 camera_info, log_time=0)
        schema = writer.register_msgdef("sensor_msgs/msg/Image", IMAGE_MSGDEF)
        for number, image in enumerate(images):
            writer.write_message(topic, schema, image, log_time=number + 1)
    return path


def image(stamp_ns, width=8, height=6, encoding="16UC1", data=None, frame_id="cam"):
    """One Image message of ``width`` x ``height`` pixels of 1 m (1000 mm) unless ``data`` is given."""
    data = np.full((height, width), 1000, "<u2").tobytes() if data is None else data
    return {"header": {"stamp": {"sec": stamp_ns // 10**9, "nanosec": stamp_ns % 10**9}, "frame_id": frame_id},
            "height": height, "width": width, "encoding": encoding, "is_bigendian": 0,
            "step": len(data) // height, "data": data}


def camera_info(width=8, height=6, k=(5.0, 0, 4.0, 0, 5.0, 3.0, 0, 0, 1)):
    return {"header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": "cam"}, "height": height, "width": width,
            "distortion_model": "plumb_bob", "d": [0.0] * 5, "k": list(k), "r": [1.0, 0, 0, 0, 1, 0, 0, 0, 1],
            "p": [0.0] * 12}


@pytest.fixture(scope="module")
def fr1():
    return read_sequence(FR1_XYZ)


@pytest.fixture(scope="module")
def recordings(fr1, tmp_path_factory):
    """fr1/xyz's first frames as ROS 2 recordings: 32FC1 and 16UC1 with CameraInfo, 32FC1 without, and a bag folder
    of two 16UC1 files."""
    folder = tmp_path_factory.mktemp("recordings")
    stamps = fr1.depth_timestamps[:N_FRAMES]
    paths = {}
    for encoding in ("32FC1", "16UC1"):
        paths[encoding] = folder / f"fr1_{encoding}.mcap"
        write_recording(paths[encoding], fr1.depth_frames(range(N_FRAMES)), stamps, ROS, encoding=encoding)
    paths["no info"] = folder / "fr1_noinfo.mcap"
    write_recording(paths["no info"], fr1.depth_frames(range(N_FRAMES)), stamps)
    bag = paths["bag"] = folder / "fr1_bag"
    bag.mkdir()
    half = N_FRAMES // 2
    for part, frames in enumerate((range(half), range(half, N_FRAMES))):
        write_recording(bag / f"fr1_bag_{part}.mcap", fr1.depth_frames(frames), stamps[frames], ROS,
                        encoding="16UC1")
    (bag / "metadata.yaml").write_text(
        "rosbag2_bagfile_information:\n  version: 8\n  storage_identifier: mcap\n  relative_file_paths:\n"
        "    - fr1_bag_0.mcap\n    - fr1_bag_1.mcap\n")
    return paths


def decoded(path, topic):
    """``topic``'s messages in ``path`` decoded by mcap-ros2-support alone, in log-time order."""
    with open(path, "rb") as stream:
        reader = make_reader(stream, decoder_factories=[Ros2DecoderFactory()])
        return [message for _, _, _, message in reader.iter_decoded_messages([topic])]


# ------------------------------------------------------------------------------------------------ reading
def test_writer_stores_rep118_pixels_and_the_calibration(fr1, recordings):
    images = decoded(recordings["16UC1"], DEPTH)
    assert len(images) == N_FRAMES and images[0].encoding == "16UC1" and images[0].header.frame_id
    png = np.rint(fr1.depth(3) * 5000)  # TUM's units (1/5000 m): one millimetre is five of them
    np.testing.assert_array_equal(np.frombuffer(images[3].data, "<u2").reshape(480, 640), np.rint(png / 5))
    floats = decoded(recordings["32FC1"], DEPTH)[3]
    np.testing.assert_array_equal(np.frombuffer(floats.data, "<f4").reshape(480, 640), (png / 5000).astype("<f4"))
    stamp = images[3].header.stamp
    assert stamp.sec + stamp.nanosec / 1e9 == pytest.approx(fr1.depth_timestamps[3], abs=1e-6)
    (info,) = decoded(recordings["16UC1"], INFO)
    assert (info.width, info.height, list(info.k)) == (640, 480, [525.0, 0, 319.5, 0, 525.0, 239.5, 0, 0, 1])
    check = subprocess.run([str(RERUN), "mcap", "check", "--full", str(recordings["16UC1"])], capture_output=True,
                           text=True)  # rerun's own ROS 2 decoder reads the stamps of every message
    assert check.returncode == 0 and DEPTH in check.stdout, check.stdout + check.stderr


def test_recordings_read_back_as_the_folder_s_frames(fr1, recordings):
    """32FC1: each depth is the PNG's float32 metres; 16UC1: its millimetres; the bag folder: both files in order."""
    folder = [fr1.depth(k) for k in range(N_FRAMES)]
    for name, quantise in [("32FC1", lambda d: d.astype(np.float32)), ("16UC1", lambda d: np.rint(d * 1000) / 1000),
                           ("bag", lambda d: np.rint(d * 1000) / 1000)]:
        sequence = read_recording(recordings[name], DEPTH)
        assert len(sequence) == N_FRAMES and sequence.image_size == (640, 480)
        np.testing.assert_allclose(sequence.depth_timestamps, fr1.depth_timestamps[:N_FRAMES], rtol=0, atol=1e-6)
        assert sequence.camera() == ("525,525,319.5,239.5", ROS)
        frames = [0, 1, 14, 15, 29]
        for depth, k in zip(sequence.depth_frames(frames), frames, strict=True):
            np.testing.assert_array_equal(depth, quantise(folder[k]), err_msg=f"{name} frame {k}")


def test_intrinsics_given_for_the_recording_s_image_size(recordings):
    sequence = read_recording(recordings["no info"], DEPTH)
    assert sequence.camera("fr1") == ("fr1", CAMERAS["fr1"])
    text, intrinsics = sequence.camera("500,501,320,240")
    assert (intrinsics.fx, intrinsics.fy, intrinsics.width, intrinsics.height) == (500, 501, 640, 480)
    with pytest.raises(InputError, match=f"no camera info on {INFO} .*{DEPTH} \\(sensor_msgs/msg/Image\\)"):
        sequence.camera()


def test_foxglove_raw_images_read_as_ros_images(tmp_path):
    """foxglove.RawImage and foxglove.CameraCalibration (written by mcap-protobuf-support) give what the same
    pixels give as sensor_msgs/msg/Image and CameraInfo."""
    rng = np.random.default_rng(0)
    depths = [rng.uniform(0.5, 4.0, size=(6, 8)).astype("<f4") for _ in range(3)]
    depths[1][2, 3] = np.nan  # REP 118: no measurement
    stamps = [10**18 + 33_333_333 * k for k in range(3)]
    with open(tmp_path / "fox.mcap", "wb") as stream:
        writer = ProtobufWriter(stream)
        writer.write_message(INFO, CameraCalibration(width=8, height=6, K=[5.0, 0, 4.0, 0, 5.0, 3.0, 0, 0, 1]),
                             log_time=0)
        for stamp, depth in zip(stamps, depths):
            time = Timestamp(seconds=stamp // 10**9, nanos=stamp % 10**9)
            writer.write_message(DEPTH, RawImage(timestamp=time, frame_id="cam", width=8, height=6, encoding="32FC1",
                                                 step=32, data=depth.tobytes()), log_time=stamp)
        writer.finish()
    ros = write_images(tmp_path / "ros.mcap", [image(s, encoding="32FC1", data=d.tobytes())
                                               for s, d in zip(stamps, depths)], camera_info())
    fox, reference = read_recording(tmp_path / "fox.mcap", DEPTH), read_recording(ros, DEPTH)
    assert fox.camera() == reference.camera() and fox.camera_frame == reference.camera_frame == "cam"
    np.testing.assert_array_equal(fox.depth_timestamps, np.array(stamps) / 1e9)
    for got, want, depth in zip(fox.depth_frames(range(3)), reference.depth_frames(range(3)), depths):
        np.testing.assert_array_equal(got, want)
        np.testing.assert_array_equal(got, np.nan_to_num(depth.astype(np.float64), nan=0.0))


def test_open_sequence_tells_the_kinds_apart(recordings):
    assert type(open_sequence(FR1_XYZ)).__name__ == "TumSequence"
    assert type(open_sequence(recordings["bag"], DEPTH)).__name__ == "McapSequence"
    with pytest.raises(InputError, match="--depth-topic"):
        open_sequence(recordings["16UC1"])
    with pytest.raises(InputError, match="not TUM folders"):
        open_sequence(FR1_XYZ, DEPTH)


def test_frames_stream_in_order(recordings):
    sequence = read_recording(recordings["16UC1"], DEPTH)
    with pytest.raises(InputError, match="indices must increase"):
        next(sequence.depth_frames([3, 2]))


def test_groundtruth_file_scores_a_recording(recordings):
    sequence = read_recording(recordings["32FC1"], DEPTH, groundtruth=FR1_XYZ / "groundtruth.txt")
    frames, truth = first_frames(sequence, 10)
    assert frames.tolist() == list(range(10)) and len(truth) == 10
    with pytest.raises(DataError, match="no ground truth"):
        first_frames(read_recording(recordings["32FC1"], DEPTH), 10)
    assert first_frames(read_recording(recordings["32FC1"], DEPTH), 10, require_groundtruth=False)[1] is None


# ------------------------------------------------------------------------------------------------ odometry
class _MillimetreFolder:
    """The TUM folder's frames with depth rounded to whole millimetres by numpy: what a 16UC1 recording holds."""

    def __init__(self, sequence):
        self._sequence, self.depth_timestamps = sequence, sequence.depth_timestamps

    def __len__(self):
        return len(self._sequence)

    def depth_frames(self, indices):
        return (np.rint(depth * 1000) / 1000 for depth in self._sequence.depth_frames(indices))

    def frame_source(self, index):
        return self._sequence.frame_source(index)


@pytest.mark.slow
def test_recording_runs_give_the_folder_s_trajectory(fr1, recordings):
    """gmm-pixels (the sweep's schedule) on the same 30 frames: 32FC1 gives the folder's trajectory to within what
    float32 depth explains (bound 1e-4 m on positions and ATE); 16UC1 (and the bag folder of two 16UC1 files)
    gives the trajectory of the folder's frames rounded to whole millimetres by numpy, whose ATE differs from the
    folder's by what that rounding causes (bound 2 mm). Measured values are printed (and in
    docs/user_guide/odometry.md)."""
    frames = np.arange(N_FRAMES)
    truth = first_frames(fr1, N_FRAMES)[1]
    with threadpool_limits(1):
        folder = run_odometry(fr1, "gmm-pixels", frames, intrinsics=ROS, seed=0).trajectory
        millimetres = run_odometry(_MillimetreFolder(fr1), "gmm-pixels", frames, intrinsics=ROS, seed=0).trajectory
        runs = {name: run_odometry(read_recording(recordings[name], DEPTH), "gmm-pixels", frames, intrinsics=ROS,
                                   seed=0).trajectory for name in ("32FC1", "16UC1", "bag")}
    ate = {name: absolute_trajectory_error(trajectory, truth).rmse
           for name, trajectory in {"folder": folder, "mm": millimetres, **runs}.items()}
    apart = {name: float(np.linalg.norm(run.translations - folder.translations, axis=1).max())
             for name, run in runs.items()}
    print("\nATE (m):", {name: round(value, 6) for name, value in ate.items()}, "; positions apart from the "
          "folder's (m):", {name: round(value, 6) for name, value in apart.items()})
    np.testing.assert_allclose(runs["32FC1"].translations, folder.translations, rtol=0, atol=1e-4)
    assert abs(ate["32FC1"] - ate["folder"]) < 1e-4
    for name in ("16UC1", "bag"):
        np.testing.assert_allclose(runs[name].translations, millimetres.translations, rtol=0, atol=1e-9)
        np.testing.assert_allclose(runs[name].timestamps, folder.timestamps, rtol=0, atol=1e-6)
    assert abs(ate["16UC1"] - ate["folder"]) < 0.002


def dgmm_odometry(*args):
    return subprocess.run([str(DGMM), "odometry", *map(str, args)], capture_output=True, text=True, timeout=600)


@pytest.mark.slow
def test_command_line_run_of_a_recording_and_its_outputs(recordings, tmp_path):
    """`dgmm odometry REC.mcap --depth-topic T --groundtruth F`: ATE printed, the trajectory at the header stamps,
    per-frame poses and transforms at the input's times (its images' frame), an output that `rerun mcap check`
    passes; the same run without ground truth prints no metrics."""
    recording, n = recordings["16UC1"], 10
    out = {name: tmp_path / name for name in ("t.txt", "o.mcap", "o.rrd")}
    run = dgmm_odometry(recording, "--depth-topic", DEPTH, "--groundtruth", FR1_XYZ / "groundtruth.txt", "--frames",
                        n, "--method", "icp", "-o", out["t.txt"], "--mcap", out["o.mcap"], "--rrd", out["o.rrd"])
    assert run.returncode == 0, run.stderr
    result = json.loads(run.stdout)
    assert (result["sequence"], result["frames"], result["intrinsics"]) == ("fr1_16UC1", n, "525,525,319.5,239.5")
    assert 0 < result["ate_rmse_m"] < 0.05 and result["seconds_per_frame"] > 0
    images = decoded(recording, DEPTH)[:n]
    stamps_ns = [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for m in images]
    rows = np.loadtxt(out["t.txt"], comments="#")
    np.testing.assert_allclose(rows[:, 0], np.array(stamps_ns) / 1e9, rtol=0, atol=1e-6)

    messages = read_mcap(out["o.mcap"])
    poses = [(message, log_time) for topic, _, message, log_time in messages if topic == "/odometry/pose"]
    np.testing.assert_allclose([log_time for _, log_time in poses], stamps_ns, rtol=0, atol=1000)  # the input's clock
    np.testing.assert_allclose([xyz(p.pose.position) for p, _ in poses], rows[:, 1:4], rtol=0, atol=1e-8)
    children = {message.child_frame_id for topic, _, message, _ in messages if topic == "/odometry/transforms"}
    assert children == {images[0].header.frame_id, "odometry"}
    check = subprocess.run([str(RERUN), "mcap", "check", str(out["o.mcap"])], capture_output=True, text=True)
    assert check.returncode == 0, check.stderr
    assert "/odometry/pose" in check.stdout and all(line.split()[0] == "ok" for line in check.stdout.splitlines()
                                                    if line.strip().startswith(("ok", "warn", "error", "fail")))
    verify = subprocess.run([str(RERUN), "rrd", "verify", str(out["o.rrd"])], capture_output=True, text=True)
    assert verify.returncode == 0, verify.stderr

    bare = dgmm_odometry(recordings["bag"], "--depth-topic", DEPTH, "--frames", n, "--method", "icp")
    assert bare.returncode == 0, bare.stderr
    result = json.loads(bare.stdout)
    assert result["sequence"] == "fr1_bag" and result["ate_rmse_m"] is None and result["rpe_rotation_deg_s"] is None


def test_writer_rejects_depth_it_cannot_store(tmp_path):
    with pytest.raises(InputError, match="65.535"):
        write_recording(tmp_path / "far.mcap", [np.full((2, 2), 70.0)], [1.0], encoding="16UC1")
    with pytest.raises(InputError, match="encoding"):
        write_recording(tmp_path / "rgb.mcap", [np.ones((2, 2))], [1.0], encoding="rgb8")
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------------------------ the sweep
@pytest.mark.slow
def test_sweep_runs_recordings_beside_tum_folders(recordings, tmp_path):
    """`snakemake odometry` with two recordings in odometry.sequences: one with ground truth (scored, in Fig 7
    against it) and one without camera info or ground truth (its intrinsics configured; a row without metrics, its
    panel unaligned); the job's trajectory has the command line's timestamps, the header stamps."""
    from dgmm.runtime.tables import read_csv
    from tests.test_odometry_workflow import write_config
    from tests.workflow import run_snakemake

    sequences = [{"path": str(recordings["16UC1"]), "depth_topic": DEPTH,
                  "groundtruth": str(FR1_XYZ / "groundtruth.txt")},
                 {"path": str(recordings["no info"]), "depth_topic": DEPTH, "intrinsics": "ros"}]
    config = write_config(tmp_path, sequences=sequences, methods=["icp"], frames=8)
    run = run_snakemake(tmp_path / "work", "odometry", configfile=config, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    results = tmp_path / "work" / "results"
    rows = {row["sequence"]: row for row in read_csv(results / "tables" / "odometry.csv")}
    assert set(rows) == {"fr1_16UC1", "fr1_noinfo"} and rows["fr1_16UC1"]["frames"] == "8"
    assert 0 < float(rows["fr1_16UC1"]["ate_rmse_m"]) < 0.05 and rows["fr1_noinfo"]["ate_rmse_m"] == ""
    assert (results / "odometry" / "fig7.png").stat().st_size > 0
    cli = dgmm_odometry(recordings["16UC1"], "--depth-topic", DEPTH, "--frames", 8, "--method", "icp", "-o",
                        tmp_path / "t.txt")
    assert cli.returncode == 0, cli.stderr
    job = np.loadtxt(results / "odometry" / "fr1_16UC1" / "icp" / "trajectory.txt", comments="#")
    assert job.shape == (8, 8) and np.array_equal(job[:, 0], np.loadtxt(tmp_path / "t.txt", comments="#")[:, 0])


def test_sweep_config_names_a_recording_s_missing_key():
    """A recording without its depth topic stops the workflow before any job (the config check, run in process)."""
    from tests.test_odometry_workflow import odometry_config
    from tests.workflow import config_error

    error = config_error(odometry_config(sequences=[{"path": "rec.mcap"}]))
    assert "On instance['odometry']['sequences'][0]" in error and "'required': ['path', 'depth_topic']" in error
