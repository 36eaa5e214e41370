"""The data stage run by real Snakemake on tests/config.yaml: the session's workflow run (conftest.py), broken mirrors
in runs of their own, and the config check.

Expected counts come from the mirror's SOURCE.md (bunny 34834 used vertices / 69451 faces, res4 453 / 948) and
from the config's budgets; nothing is compared with numbers the workflow printed.
"""

import numpy as np
import pytest
import trimesh
import yaml

from dgmm.data import load_mesh, load_points
from tests.workflow import REPO, TEST_CONFIG, TEST_CONFIG_FILE, config_error, run_snakemake

DATA = TEST_CONFIG["data"]


def _snakemake(workdir, *args, configfile=TEST_CONFIG_FILE):
    """Run the repository's Snakefile with ``workdir`` as working directory; return the completed process."""
    return run_snakemake(workdir, *args, configfile=configfile, timeout=600)


def test_test_config_mirror_is_the_shared_stanford_folder():
    """Relative mirror paths are read from the repository root, so any working directory finds the same mirror."""
    mirror = (REPO / DATA["mirrors"][0]).resolve()
    assert mirror == (REPO.parent / "shared" / "data" / "stanford").resolve()
    assert (mirror / "bunny.ply").is_file()


@pytest.fixture(scope="module")
def built(workflow_run):
    """The results of the session's workflow run, whose stages start with `snakemake data` on the tiny config."""
    return workflow_run / "results"


@pytest.mark.slow
def test_data_outputs_and_counts(built):
    folder = built / "data" / "bunny"
    n_eval, (budget,) = DATA["eval_points"], DATA["budgets"]
    vertices, faces = load_mesh(folder / "full.ply")
    assert vertices.shape == (34834, 3) and faces.shape == (69451, 3)
    source = trimesh.load(REPO.parent / "shared" / "data" / "stanford" / "bunny.ply", process=False)
    used = np.unique(source.faces)
    assert np.allclose(vertices, source.vertices[used], rtol=1e-6, atol=0)
    assert np.array_equal(faces, np.searchsorted(used, source.faces))
    assert [len(a) for a in load_mesh(folder / "res4.ply")] == [453, 948]
    for name in ("full_eval", "res4_eval"):
        assert abs(len(load_points(folder / f"{name}.ply")) - n_eval) <= 0.005 * n_eval
    assert len(load_mesh(folder / f"quadric{budget}.ply")[1]) == budget
    assert abs(len(load_mesh(folder / f"clustering{budget}.ply")[1]) - budget) <= 0.05 * budget
    assert abs(len(load_points(folder / f"poisson{budget}.ply")) - budget) <= 0.005 * budget
    assert len(load_points(folder / f"random{budget}.ply")) == budget
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    for name in ("full_eval", f"poisson{budget}", f"random{budget}"):
        points = load_points(folder / f"{name}.ply")
        assert np.all(points >= low - 1e-6) and np.all(points <= high + 1e-6)
    assert sorted(p.name for p in folder.iterdir()) == sorted(
        ["full.ply", "res4.ply", "full_eval.ply", "res4_eval.ply"]
        + [f"{method}{budget}.ply" for method in DATA["methods"]])
    assert len(list((built / "logs" / "data" / "bunny").glob("*.log"))) == 8


@pytest.mark.slow
def test_second_run_does_nothing(built):
    run = _snakemake(built.parent, "data")
    assert run.returncode == 0
    assert "Nothing to be done" in run.stdout + run.stderr


@pytest.mark.slow
def test_wrong_sha256_fails_without_output(tmp_path):
    """A mirror copy that fails its checksum stops the job with one line naming the file; nothing is left."""
    mirror = tmp_path / "mirror"
    mirror.mkdir()
    (mirror / "bunny.ply").write_bytes(b"ply\nformat ascii 1.0\nend_header\n")
    config = {**yaml.safe_load(TEST_CONFIG_FILE.read_text())}
    config["data"] = {**DATA, "mirrors": [str(mirror)], "cache": str(tmp_path / "cache")}
    (tmp_path / "config.yaml").write_text(yaml.safe_dump(config))
    workdir = tmp_path / "work"
    run = _snakemake(workdir, "results/data/bunny/full.ply", configfile=tmp_path / "config.yaml")
    assert run.returncode != 0
    log = (workdir / "results" / "logs" / "data" / "bunny" / "full.log").read_text()
    message = log.strip().splitlines()[-1]  # the traceback's last line is the exception and its message
    assert message.startswith("dgmm.errors.DataError: ")
    assert str(mirror / "bunny.ply") in message and "sha256" in message
    assert [p for p in (workdir / "results").rglob("*") if p.is_file() and "logs" not in p.parts] == []


@pytest.mark.slow
def test_bad_config_value_names_the_key(tmp_path):
    """The suite's one real dry run of a bad config: the Snakefile stops before any job, naming the key (the other
    bad configs are checked in process by ``config_error``, the same validation)."""
    config = {**yaml.safe_load(TEST_CONFIG_FILE.read_text())}
    config["data"] = {**DATA, "eval_points": -5}
    (tmp_path / "config.yaml").write_text(yaml.safe_dump(config))
    assert "On instance['data']['eval_points']" in config_error(config)
    run = _snakemake(tmp_path, "-n", "data", configfile=tmp_path / "config.yaml")
    assert run.returncode != 0
    assert "On instance['data']['eval_points']" in run.stdout + run.stderr
    assert not (tmp_path / "results").exists()


def test_the_test_config_passes_the_config_check():
    """The control of every bad-config test: tests/config.yaml itself passes, so a bad value is what fails."""
    assert config_error(TEST_CONFIG) == ""
