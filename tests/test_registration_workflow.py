"""The registration stage run by real Snakemake on tests/config.yaml (the session's workflow run, conftest.py): tables,
shared trials, recordings; a chunk rerun on a copy.

Expected rows come from the test config; trial poses are checked against the authors' protocol (Euler angles
within ±15°, translations within ±0.05 per axis scaled by the diagonal over the bunny's 0.24077) and the table's
errors are recomputed from the recorded poses with quaternion algebra written out here.
"""
import shutil
import subprocess
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from dgmm.experiments.trials import METHODS, method_variants, mixture_source
from dgmm.runtime.tables import read_csv
from tests.test_recording import read_blueprint, read_mcap, read_rrd, xyz
from tests.reference_tables import assert_within_bands
from tests.workflow import RERUN, TEST_CONFIG, copy_run, run_snakemake

REG = TEST_CONFIG["registration"]
COLUMNS = ["model", "mesh", "protocol", "variant", "method", "trial", "rotation_error_deg", "translation_error_pct",
           "iterations", "converged"]
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def workdir(workflow_run):
    """Working directory of the session's workflow run (conftest.py), which includes `snakemake registration` on the
    tiny config."""
    return workflow_run


@pytest.fixture(scope="module")
def table(workdir):
    return read_csv(workdir / "results" / "tables" / "registration.csv")


def expected_keys():
    """(model, mesh, variant, method, trial) of every configured trial (the test config: scaled trials only)."""
    keys = set()
    for experiment in REG["experiments"].values():
        for model in experiment["models"]:
            for method, variant in method_settings(experiment["methods"]):
                keys |= {(model, experiment["mesh"], variant, method, trial) for trial in range(experiment["trials"])}
    return keys


def method_settings(methods):
    """(method, EM variant) of every registration job of ``methods``."""
    return [(method, variant) for method in methods for variant in method_variants(method, REG["variants"])]


def chunk_folders(results):
    return sorted(results.glob("registration/*/*/*/*/*/c*"))


def pose(message):
    """(quaternion (x, y, z, w), position) of the single pose of a PosesInFrame message."""
    (single,) = message.poses
    return xyz(single.orientation, "xyzw"), xyz(single.position)


def quaternion_product(a, b):
    """Hamilton product of (x, y, z, w) quaternions."""
    (ax, ay, az, aw), (bx, by, bz, bw) = a, b
    return np.array([aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz])


def rotate(q, v):
    """Rotate vector ``v`` by the unit quaternion ``q`` (x, y, z, w): q v q*."""
    conjugate = q * np.array([-1, -1, -1, 1])
    return quaternion_product(quaternion_product(q, np.append(v, 0.0)), conjugate)[:3]


def trials_of(folder):
    """Per trial of a chunk's MCAP: (trial message, true pose message, estimated pose message), and the params."""
    messages = read_mcap(folder / "trials.mcap")
    (params,) = [m for topic, _, m, _ in messages if topic == "/registration/params"]
    by_time = defaultdict(dict)
    for topic, schema, message, log_time in messages:
        by_time[log_time][topic] = (schema.name, message)
    trials = []
    for topics in by_time.values():
        if "/registration/trial" in topics:
            assert topics["/registration/true_pose"][0] == "foxglove.PosesInFrame"
            assert topics["/registration/estimated_pose"][0] == "foxglove.PosesInFrame"
            trials.append(tuple(topics[f"/registration/{name}"][1] for name in ("trial", "true_pose",
                                                                               "estimated_pose")))
    return trials, params


def test_table_has_every_trial_of_every_method(workdir, table):
    assert list(table[0]) == COLUMNS
    keys = [(r["model"], r["mesh"], r["variant"], r["method"], int(r["trial"])) for r in table]
    assert len(keys) == len(set(keys)) and set(keys) == expected_keys()
    seconds = read_csv(workdir / "results" / "tables" / "registration_seconds.csv")
    assert [(r["model"], r["mesh"], r["variant"], r["method"], int(r["trial"])) for r in seconds] == keys
    assert all(float(r["seconds"]) > 0 for r in seconds)
    n_chunks = -(-max(e["trials"] for e in REG["experiments"].values()) // REG["trials_per_chunk"])
    assert n_chunks >= 2  # the tiny config still splits trials into chunks
    assert len(chunk_folders(workdir / "results")) == sum(
        len(method_settings(e["methods"])) * -(-e["trials"] // REG["trials_per_chunk"])
        for e in REG["experiments"].values())


def test_table_is_the_reference_within_its_bands(workdir):
    assert_within_bands(workdir / "results" / "tables" / "registration.csv")


def test_every_trial_ends_in_the_papers_range(table):
    """Paper Fig 6 (bunny, 250 trials): every method's mean rotation error is below 3 deg and translation error
    below 1.1% of the diagonal. Each trial, not a median (which two diverging trials of four pass), must end in
    that range: here every method's worst trial is within 2.7 deg and 0.65%. A trial that diverges fails, and so
    does one that removes only two thirds of its motion (tried on trial 1, which starts 9 deg away: 3.02 deg)."""
    for row in table:
        assert float(row["rotation_error_deg"]) < 3.0 and float(row["translation_error_pct"]) < 1.1, row


def test_methods_see_identical_trials_within_the_protocol(workdir):
    results = workdir / "results"
    vertices = trimesh.load(results / "data" / "bunny" / "res4.ply", process=False).vertices
    diagonal = np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0))
    seen = defaultdict(dict)  # (model, mesh, trial) -> method -> (true pose, centre, source digest)
    for folder in chunk_folders(results):
        model, mesh, _, variant, method = folder.parts[-6:-1]
        trials, params = trials_of(folder)
        assert params["diagonal"] == pytest.approx(diagonal, rel=1e-12)
        for trial, true_pose, _ in trials:
            quaternion, position = pose(true_pose)
            seen[model, mesh, trial["trial"]][method, variant] = (tuple(quaternion), tuple(position),
                                                                  tuple(trial["centre"]), trial["source_sha256"])
            # Authors' protocol: Euler angles within ±15° (static xyz axes), the centre moved by at most
            # 0.05 * diagonal / 0.24077 per axis.
            angles = Rotation.from_quat(quaternion).as_euler("xyz", degrees=True)
            assert np.all(np.abs(angles) <= 15.0)
            centre = np.array(trial["centre"])
            shift = rotate(quaternion, centre) + position - centre
            assert np.all(np.abs(shift) <= 0.05 * diagonal / 0.24077 + 1e-12)
    methods = {setting for e in REG["experiments"].values() for setting in method_settings(e["methods"])}
    for key, by_method in seen.items():
        assert set(by_method) == methods, key
        assert len(set(by_method.values())) == 1, f"methods saw different trials at {key}"
    assert len({value for by_method in seen.values() for value in by_method.values()}) == len(seen)


def test_recorded_poses_reproduce_the_table(workdir, table):
    rows = {(r["model"], r["mesh"], r["variant"], r["method"], int(r["trial"])): r for r in table}
    checked = 0
    for folder in chunk_folders(workdir / "results"):
        model, mesh, _, variant, method = folder.parts[-6:-1]
        trials, params = trials_of(folder)
        first, stop = params["trials"]
        assert [trial["trial"] for trial, _, _ in trials] == list(range(first, stop))
        for trial, true_pose, estimated_pose in trials:
            row = rows[model, mesh, variant, method, trial["trial"]]
            (q_true, t_true), (q_est, t_est) = pose(true_pose), pose(estimated_pose)
            # Both are poses of the moved source in the model frame: the relative rotation's angle, and how far
            # apart they put the source centre.
            relative = quaternion_product(q_true * np.array([-1, -1, -1, 1]), q_est)
            rotation = np.degrees(2 * np.arctan2(np.linalg.norm(relative[:3]), abs(relative[3])))
            centre = np.array(trial["centre"])
            gap = (rotate(q_true, centre) + t_true) - (rotate(q_est, centre) + t_est)
            translation = 100 * np.linalg.norm(gap) / params["diagonal"]
            assert rotation == pytest.approx(float(row["rotation_error_deg"]), rel=1e-6, abs=1e-9)
            assert translation == pytest.approx(float(row["translation_error_pct"]), rel=1e-6, abs=1e-9)
            assert trial["iterations"] == int(row["iterations"])
            assert str(trial["converged"]) == row["converged"]
            checked += 1
    assert checked == len(table)


def test_every_rrd_verifies_and_shows_the_first_trials_moving(workdir, table):
    results = workdir / "results"
    recordings = sorted(results.glob("registration/**/*.rrd"))
    gmms = sorted(results.glob("registration/**/gmm.npz"))
    n_mixtures = len({(model, e["mesh"], protocol, mixture_source(m), v) for e in REG["experiments"].values()
                      for model in e["models"] for protocol in e.get("protocols", ["scaled"])
                      for m, v in method_settings(e["methods"]) if METHODS[m].needs_mixture})
    assert len(gmms) == n_mixtures and len(recordings) == len(chunk_folders(results)) + len(gmms)
    verify = subprocess.run([str(RERUN), "rrd", "verify", *map(str, recordings)], capture_output=True, text=True)
    assert verify.returncode == 0, verify.stderr
    iterations = {(r["model"], r["mesh"], r["variant"], r["method"], int(r["trial"])): int(r["iterations"])
                  for r in table}
    for gmm in gmms:  # the P2D methods' fit
        assert read_blueprint(gmm.parent / "fit.rrd")[0] == "iteration"
    for folder in chunk_folders(results):
        model, mesh, _, variant, method = folder.parts[-6:-1]
        first = REG["trials_per_chunk"] * int(folder.name[1:])
        recorded = range(first, first + REG["recorded_trials"])
        timeline, views = read_blueprint(folder / "trials.rrd")
        assert timeline == "iteration" and views["objective"][2] == [f"/trial-{trial}/objective" for trial in recorded]
        assert {name for name in views if name != "objective"} == {f"trial {trial}" for trial in recorded}
        for trial in recorded:
            moving = read_rrd(folder / "trials.rrd", f"/trial-{trial}/source")
            # Iteration 0 is the trial's start, then one row per iteration of the method.
            assert moving["iteration"] == list(range(iterations[model, mesh, variant, method, trial] + 1))
        assert not read_rrd(folder / "trials.rrd", f"/trial-{first + REG['recorded_trials']}/source")


def test_rerun_chunk_gives_the_same_table_bytes(workdir, tmp_path):
    """Delete one chunk's outputs in a copy of the run; Snakemake redoes it and the table is byte-identical."""
    copy = copy_run(workdir, tmp_path / "copy")
    chunk = copy / "results" / "registration" / "bunny" / "res4" / "scaled" / "textbook" / "points-random" / "c1"
    shutil.rmtree(chunk)
    table = Path("results") / "tables" / "registration.csv"
    (copy / table).unlink()
    run = run_snakemake(copy, "registration", timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    assert (chunk / "errors.csv").is_file()
    assert (copy / table).read_bytes() == (workdir / table).read_bytes()
