"""The odometry stage (Fig 7) run by real Snakemake on tests/config.yaml (the session's workflow run, conftest.py): 8
frames of the synthetic sequence, and a configured TUM folder that is missing (reported pending).

References are independent of the code under test: evo's APE (Umeyama alignment without scale) recomputed from the
written TUM files, numpy's reading of those files for the MCAP poses, `rerun rrd verify`, Pillow for the PNG.
"""
import math
import shutil
import subprocess

import numpy as np
import pytest
import yaml
from PIL import Image

from dgmm.errors import DataError
from dgmm.odometry import first_frames, seconds_summary
from dgmm.odometry.tum import read_sequence
from dgmm.runtime.tables import read_csv
from tests.test_recording import read_blueprint, read_mcap, read_rrd, xyz
from tests.reference_tables import assert_within_bands
from tests.workflow import RERUN, TEST_CONFIG, TEST_CONFIG_FILE, config_error, run_snakemake

RUNS = {"gmm-pixels-textbook": ("gmm-pixels", "textbook"), "gmm-points-textbook": ("gmm-points", "textbook"),
        "icp": ("icp", "")}
METHODS = list(RUNS)  # job folders
N_FRAMES = TEST_CONFIG["odometry"]["frames"]
PROTOCOL_RUNS = {"gmm-pixels-authors-patch": "authors-patch", "gmm-points-authors-patch": "authors-patch",
                 "gmm-pixels-authors-disparity": "authors-disparity"}
"""tests/config.yaml's authors' protocols: gmm-pixels runs (and gmm-points under authors-patch) over the first
authors_frames frames."""
AUTHORS_FRAMES = TEST_CONFIG["odometry"]["authors_frames"]
MISSING = TEST_CONFIG["odometry"]["sequences"][0]


def odometry_config(**odometry):
    """tests/config.yaml with its odometry section updated."""
    config = yaml.safe_load(TEST_CONFIG_FILE.read_text())
    config["odometry"] = {**config["odometry"], **odometry}
    return config


def write_config(tmp_path, **odometry):
    """:func:`odometry_config` written to a file in ``tmp_path``; returns the file's path."""
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(odometry_config(**odometry)))
    return path


@pytest.fixture(scope="module")
def stage(workflow_run):
    """Results of the session's workflow run (conftest.py), which includes `snakemake odometry` on the tiny config (no
    TUM folder: the synthetic sequence)."""
    return workflow_run / "results"


def tum_rows(path):
    """A TUM file's rows as an array of shape (n, 8), read with numpy."""
    return np.loadtxt(path, comments="#", ndmin=2)


@pytest.mark.slow
def test_every_output_exists(stage):
    sequence = stage / "odometry" / "synthetic" / "sequence"
    assert len(list((sequence / "depth").glob("*.png"))) == N_FRAMES
    assert (sequence / "groundtruth.txt").is_file()
    for method in METHODS:
        job = stage / "odometry" / "synthetic" / method
        assert sorted(p.name for p in job.iterdir()) == sorted(
            ["trajectory.txt", "ate.csv", "seconds.csv", "odometry.mcap", "odometry.rrd"])
        assert len(tum_rows(job / "trajectory.txt")) == N_FRAMES
    for table in ("odometry.csv", "odometry_seconds.csv"):
        assert (stage / "tables" / table).is_file()
    png = (stage / "odometry" / "fig7.png").read_bytes()
    assert png.startswith(b"\x89PNG") and b"tIME" not in png and b"Software" not in png
    with Image.open(stage / "odometry" / "fig7.png") as image:
        assert min(image.size) > 300
    assert not list(stage.rglob("*.part")) and not list(stage.rglob("*.tmp"))


@pytest.mark.slow
def test_table_is_the_reference_within_its_bands(stage):
    assert_within_bands(stage / "tables" / "odometry.csv")


@pytest.mark.slow
def test_table_has_every_run_with_finite_metrics_and_the_missing_sequence(stage):
    rows = read_csv(stage / "tables" / "odometry.csv")
    assert list(rows[0]) == ["sequence", "method", "variant", "schedule", "frames", "ate_rmse_m",
                             "rpe_translation_m_s", "rpe_rotation_deg_s", "protocol", "missing_folder"]
    *rows, pending = rows
    rows, authors = rows[:len(RUNS)], rows[len(RUNS):]
    assert [(row["method"], row["variant"]) for row in rows] == list(RUNS.values())
    assert [row["schedule"] for row in rows] == ["overlap", "overlap", ""]  # tests/config.yaml's; ICP has none
    assert [row["protocol"] for row in rows] == ["ours", "ours", ""]
    assert [(row["method"], row["variant"], row["schedule"], row["protocol"], int(row["frames"]))
            for row in authors] == [(run.removesuffix(f"-{protocol}"), "authors", "authors", protocol, AUTHORS_FRAMES)
                                    for run, protocol in PROTOCOL_RUNS.items()]
    for row in authors:
        assert math.isfinite(float(row["ate_rmse_m"])) and row["missing_folder"] == ""
    for row in rows:
        assert row["sequence"] == "synthetic" and int(row["frames"]) == N_FRAMES and row["missing_folder"] == ""
        assert math.isfinite(float(row["ate_rmse_m"])) and float(row["ate_rmse_m"]) >= 0
        assert row["rpe_translation_m_s"] == row["rpe_rotation_deg_s"] == ""  # 8 frames span less than 1 s
    assert pending == {"sequence": "rgbd_dataset_freiburg3_missing", "method": "", "variant": "", "schedule": "",
                       "frames": "",
                       "ate_rmse_m": "", "rpe_translation_m_s": "", "rpe_rotation_deg_s": "", "protocol": "",
                       "missing_folder": MISSING}
    seconds = read_csv(stage / "tables" / "odometry_seconds.csv")
    assert [(row["method"], row["variant"], row["protocol"]) for row in seconds] == [
        *((method, variant, "ours" if variant else "") for method, variant in RUNS.values()),
        *((run.removesuffix(f"-{protocol}"), "authors", protocol) for run, protocol in PROTOCOL_RUNS.items())]
    for run in PROTOCOL_RUNS:
        assert len(tum_rows(stage / "odometry" / "synthetic" / run / "trajectory.txt")) == AUTHORS_FRAMES
        assert len(read_csv(stage / "odometry" / "synthetic" / run / "seconds.csv")) == AUTHORS_FRAMES
    for row, method in zip(seconds, METHODS):
        frames = read_csv(stage / "odometry" / "synthetic" / method / "seconds.csv")
        assert len(frames) == N_FRAMES and frames[0]["registration_seconds"] == ""
        model = np.mean([float(f["model_seconds"]) for f in frames])
        registration = np.mean([float(f["registration_seconds"]) for f in frames[1:]])
        assert float(row["mean_seconds_per_frame"]) == pytest.approx(model + registration, rel=1e-12)
        assert float(row["mean_seconds_per_frame"]) > 0 and float(row["mean_cpu_seconds_per_frame"]) > 0


@pytest.mark.slow
def test_ate_equals_evo(stage):
    """The table's ATE is evo's APE RMSE (translation, Umeyama alignment without scale) of the written files."""
    from evo.core import metrics, sync
    from evo.tools import file_interface

    groundtruth = stage / "odometry" / "synthetic" / "sequence" / "groundtruth.txt"
    table = {(row["method"], row["variant"]): row["ate_rmse_m"] for row in read_csv(stage / "tables" / "odometry.csv")}
    for method in METHODS:
        estimate = stage / "odometry" / "synthetic" / method / "trajectory.txt"
        ref, est = sync.associate_trajectories(file_interface.read_tum_trajectory_file(groundtruth),
                                               file_interface.read_tum_trajectory_file(estimate), max_diff=0.02)
        assert est.num_poses == N_FRAMES
        est.align(ref, correct_scale=False)
        ape = metrics.APE(metrics.PoseRelation.translation_part)
        ape.process_data((ref, est))
        assert float(table[RUNS[method]]) == pytest.approx(ape.get_statistic(metrics.StatisticsType.rmse), abs=1e-6)


@pytest.mark.slow
def test_mcap_poses_equal_the_trajectory_files(stage):
    truth = tum_rows(stage / "odometry" / "synthetic" / "sequence" / "groundtruth.txt")
    for method in METHODS:
        job = stage / "odometry" / "synthetic" / method
        messages = read_mcap(job / "odometry.mcap")
        by_topic = {}
        for topic, schema, message, _ in messages:
            by_topic.setdefault(topic, []).append((schema.name, message))
        frames = [message for _, message in by_topic["/odometry/frame"]]
        assert [frame["index"] for frame in frames] == list(range(N_FRAMES))
        assert frames[0]["registration_seconds"] is None and all(f["registration_seconds"] > 0 for f in frames[1:])
        timed = [float(row["registration_seconds"]) for row in read_csv(job / "seconds.csv")[1:]]
        assert [frame["registration_seconds"] for frame in frames[1:]] == pytest.approx(timed, rel=1e-12)
        written = tum_rows(job / "trajectory.txt")
        ((schema, estimated),) = by_topic["/odometry/estimated"]
        assert schema == "foxglove.PosesInFrame" and estimated.frame_id == "odometry"
        positions = np.array([xyz(p.position) for p in estimated.poses])
        quaternions = np.array([xyz(p.orientation, "xyzw") for p in estimated.poses])
        np.testing.assert_allclose(positions, written[:, 1:4], rtol=0, atol=1e-8)
        signs = np.sign(np.sum(quaternions * written[:, 4:], axis=1))
        np.testing.assert_allclose(quaternions * signs[:, None], written[:, 4:], rtol=0, atol=1e-8)
        # Ground truth: the groundtruth.txt rows at the frames' timestamps.
        ((schema, groundtruth),) = by_topic["/odometry/groundtruth"]
        rows = truth[[np.argmin(np.abs(truth[:, 0] - stamp)) for stamp in written[:, 0]]]
        np.testing.assert_allclose([xyz(p.position) for p in groundtruth.poses], rows[:, 1:4],
                                   rtol=0, atol=1e-8)


@pytest.mark.slow
def test_rrd_verifies_and_holds_every_frame(stage):
    for method in METHODS:
        path = stage / "odometry" / "synthetic" / method / "odometry.rrd"
        verify = subprocess.run([str(RERUN), "rrd", "verify", str(path)], capture_output=True, text=True)
        assert verify.returncode == 0, verify.stderr
        assert read_blueprint(path)[0] == "frame"
        model = read_rrd(path, "/world/camera/model")
        assert sorted(model["frame"]) == list(range(N_FRAMES))
        if method == "icp":
            sizes = [len(points) for points in model["Points3D:positions"]]
            assert sizes == [TEST_CONFIG["odometry"]["icp_points"]] * N_FRAMES
        else:
            sizes = [len(centers) for centers in model["Ellipsoids3D:centers"]]
            assert sizes == [TEST_CONFIG["odometry"]["components"]] * N_FRAMES
        assert sorted(read_rrd(path, "/world/camera")["frame"]) == list(range(N_FRAMES))


@pytest.mark.slow
def test_rerun_gives_byte_identical_ate(stage, tmp_path):
    """Same config and seed: a second run of a job writes the same trajectory and ATE row, byte for byte."""
    for part in ("data/bunny/res4.ply", "odometry/synthetic/sequence"):
        source, target = stage / part, tmp_path / "results" / part
        target.parent.mkdir(parents=True, exist_ok=True)
        (shutil.copytree if source.is_dir() else shutil.copy2)(source, target)
    job = "odometry/synthetic/icp"
    run = run_snakemake(tmp_path, f"results/{job}/ate.csv", timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    for name in ("ate.csv", "trajectory.txt"):
        assert (tmp_path / "results" / job / name).read_bytes() == (stage / job / name).read_bytes()


@pytest.mark.slow
def test_broken_real_sequence_fails_with_one_line_naming_the_file(stage, tmp_path):
    """A configured TUM folder that exists is used; a corrupt depth PNG stops the job with one line naming it."""
    folder = tmp_path / "rgbd_dataset_freiburg3_long_office_household"
    (folder / "depth").mkdir(parents=True)
    shutil.copy(stage / "odometry" / "synthetic" / "sequence" / "groundtruth.txt", folder / "groundtruth.txt")
    stamps = tum_rows(folder / "groundtruth.txt")[:9:3, 0]
    listing = "".join(f"{stamp:.6f} depth/{stamp:.6f}.png\n" for stamp in stamps)
    (folder / "depth.txt").write_text("# timestamp filename\n" + listing)
    for stamp in stamps:
        (folder / "depth" / f"{stamp:.6f}.png").write_bytes(b"not a png")
    workdir = tmp_path / "work"
    run = run_snakemake(workdir, "odometry", configfile=write_config(
        tmp_path, sequences=[str(folder)], methods=["icp"]), timeout=600)
    assert run.returncode != 0
    log = (workdir / "results" / "logs" / "odometry" / folder.name / "icp.log").read_text()
    message = log.strip().splitlines()[-1]  # the traceback's last line is the exception and its message
    assert message.startswith("dgmm.errors.DataError: ")
    assert str(folder / "depth" / f"{stamps[0]:.6f}.png") in message
    # The real folder was used (no synthetic sequence) and the failed job left no file behind.
    assert [p for p in (workdir / "results").rglob("*") if p.is_file() and "logs" not in p.parts] == []


def test_sequence_without_enough_groundtruth_names_the_file(tmp_path):
    folder = tmp_path / "seq"
    folder.mkdir()
    (folder / "depth.txt").write_text("".join(f"{10 + k / 30:.6f} depth/{k}.png\n" for k in range(5)))
    with pytest.raises(DataError, match="groundtruth.txt"):
        first_frames(read_sequence(folder), 5)
    (folder / "groundtruth.txt").write_text("10.000000 0 0 0 0 0 0 1\n10.033333 0 0 0 0 0 0 1\n")
    with pytest.raises(DataError, match=str(folder / "groundtruth.txt")) as caught:
        first_frames(read_sequence(folder), 5)
    assert "\n" not in str(caught.value)


def test_seconds_summary_adds_the_mean_model_and_registration_times():
    rows = [{"model_seconds": "1.0", "registration_seconds": ""},
            {"model_seconds": "3.0", "registration_seconds": "0.5"},
            {"model_seconds": "2.0", "registration_seconds": "1.5"}]
    summary = seconds_summary(rows)
    assert summary["frames"] == 3
    assert summary["mean_seconds_per_frame"] == pytest.approx(2.0 + 1.0)


def test_bad_config_value_names_the_key():
    """Fewer than 3 frames stop the workflow before any job (the config check, run in process), naming the key."""
    assert "On instance['odometry']['frames']" in config_error(odometry_config(frames=1))


@pytest.mark.parametrize("key, value", [("protocols", ["ours", "authors"]), ("authors_frames", 1)])
def test_bad_protocol_settings_name_the_key(key, value):
    """An unknown protocol and a prefix of fewer than 3 frames stop the workflow before any job (the config check,
    run in process), naming the key."""
    assert f"On instance['odometry']['{key}']" in config_error(odometry_config(**{key: value}))
