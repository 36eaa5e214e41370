"""The sweep on a real single-node Slurm cluster through Snakemake's SLURM executor and `profiles/slurm`.

`tests/slurm_cluster.py` starts munged, slurmctld and slurmd (Debian's packages, as root) with their state under a
temporary directory; the fixture stops them, and kills every job process, even when a test fails. Skipped where the
daemons or the executor plugin are not installed; `.ci/run` installs both, so CI runs it.
"""
import importlib.util
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
CLUSTER_SCRIPT = REPO / "tests" / "slurm_cluster.py"
TARGET = "results/tables/likelihood.csv"
START_TIMEOUT = 90
RUN_TIMEOUT = 240


def missing_slurm():
    """Why the cluster cannot be started here, or an empty string.

    Returns
    -------
    str
    """
    for daemon in ("munged", "slurmctld", "slurmd"):
        if not (Path("/usr/sbin") / daemon).exists():
            return f"/usr/sbin/{daemon} not installed (apt-get install slurmctld slurmd slurm-client munge)"
    if importlib.util.find_spec("snakemake_executor_plugin_slurm") is None:
        return "snakemake-executor-plugin-slurm not installed (pip install -e '.[slurm]')"
    if os.geteuid() != 0:
        return "the test cluster's daemons run as root"
    return ""


pytestmark = [pytest.mark.slow, pytest.mark.skipif(bool(missing_slurm()), reason=missing_slurm())]


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """Environment for Slurm clients and Snakemake that reaches a running single-node test cluster."""
    root = tmp_path_factory.mktemp("slurm")
    root.chmod(0o700)  # munged refuses state in directories others can write to
    with open(root / "cluster.out", "w") as out:
        helper = subprocess.Popen([sys.executable, str(CLUSTER_SCRIPT), str(root)], stdout=out,
                                  stderr=subprocess.STDOUT, start_new_session=True)
    try:
        deadline = time.monotonic() + START_TIMEOUT
        while not (root / "ready").exists():
            if helper.poll() is not None or time.monotonic() > deadline:
                logs = "\n".join(f"{p.name}: {p.read_text()[-1500:]}" for p in sorted(root.glob("*.out")))
                pytest.fail(f"the Slurm test cluster did not start:\n{logs}")
            time.sleep(0.2)
        yield {**os.environ, "SLURM_CONF": str(root / "slurm.conf"),
               "PATH": f"{root / 'bin'}{os.pathsep}{os.environ['PATH']}"}
    finally:
        helper.terminate()
        try:
            helper.wait(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(helper.pid, signal.SIGKILL)
            helper.wait()


@pytest.fixture(scope="module")
def config(tmp_path_factory):
    """tests/config.yaml cut down further: bunny res4 fitted by both EM variants, one seed, K=25."""
    config = yaml.safe_load((REPO / "tests" / "config.yaml").read_text())
    config["data"]["eval_points"] = 2000
    config["fit"].update(seeds=1, max_iter=10, experiments={"tiny": dict(
        models=["bunny"], inputs=["res4-exact"], components=[25], inits=["kmeans"])})
    path = tmp_path_factory.mktemp("config") / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    return path


def snakemake(workdir, config, *options, env=None):
    """Run Snakemake on the likelihood table; its wall time and the finished process.

    Parameters
    ----------
    workdir : Path
        Working directory (``--directory``).
    config : Path
        Config file.
    *options : str
        More command-line options (the executor's profile).
    env : dict, optional
        Environment; this process's when omitted.

    Returns
    -------
    tuple of (float, subprocess.CompletedProcess)
    """
    command = [str(SNAKEMAKE), "--snakefile", str(REPO / "Snakefile"), "--directory", str(workdir),
               "--configfile", str(config), *options, TARGET]
    start = time.monotonic()
    run = subprocess.run(command, capture_output=True, text=True, timeout=RUN_TIMEOUT, env=env, cwd=REPO)
    return time.monotonic() - start, run


def on_slurm(workdir, config, env):
    """`snakemake --profile profiles/slurm` as docs/user_guide/slurm.md runs it, checking job states every few seconds.

    Parameters
    ----------
    workdir, config : Path
        As for `snakemake`.
    env : dict
        The cluster's environment.

    Returns
    -------
    tuple of (float, subprocess.CompletedProcess)
    """
    return snakemake(workdir, config, "--profile", "profiles/slurm",
                     "--slurm-init-seconds-before-status-checks", "2", env=env)


def slurm_jobs(run, env):
    """The Slurm jobs a Snakemake run submitted, as ``(cpus, memory, time limit, state)`` rows in job order.

    Parameters
    ----------
    run : subprocess.CompletedProcess
        The Snakemake run; its log names the run's Slurm job name.
    env : dict
        The cluster's environment.

    Returns
    -------
    list of tuple of str
    """
    run_id = next(line.split()[-1] for line in run.stderr.splitlines() if line.startswith("SLURM run ID:"))
    queue = subprocess.run(["squeue", "--states=all", "--noheader", "--name", run_id, "--format=%i|%C|%m|%l|%T"],
                           env=env, capture_output=True, text=True, timeout=30, check=True)
    rows = sorted((line.split("|") for line in queue.stdout.split()), key=lambda row: int(row[0]))
    return [tuple(row[1:]) for row in rows]


@pytest.fixture(scope="module")
def local(config, tmp_path_factory):
    """The tiny sweep run locally (`--cores 2`), started at once so that it runs while the cluster starts and runs its
    own copy (mostly waiting on Slurm): a function that waits for it and returns its working directory and wall
    time."""
    workdir = tmp_path_factory.mktemp("local")
    command = [str(SNAKEMAKE), "--snakefile", str(REPO / "Snakefile"), "--directory", str(workdir),
               "--configfile", str(config), "--cores", "2", TARGET]
    start = time.monotonic()
    with open(workdir.with_name("local.out"), "w") as out:
        process = subprocess.Popen(command, stdout=out, stderr=subprocess.STDOUT, cwd=REPO)
    ended = []  # when it exited, noted by a thread that waits for it
    waiter = threading.Thread(target=lambda: ended.append((process.wait(), time.monotonic())), daemon=True)
    waiter.start()

    def finished():
        waiter.join(timeout=RUN_TIMEOUT)
        assert ended and ended[0][0] == 0, workdir.with_name("local.out").read_text()[-3000:]
        return workdir, ended[0][1] - start

    yield finished
    if process.poll() is None:
        process.kill()
        process.wait()


@pytest.fixture(scope="module")
def slurm(cluster, config, tmp_path_factory):
    """The same sweep on the cluster: working directory, wall time and the finished Snakemake process."""
    workdir = tmp_path_factory.mktemp("on-slurm")
    seconds, run = on_slurm(workdir, config, cluster)
    assert run.returncode == 0, run.stderr[-3000:]
    return workdir, seconds, run


def test_the_sweep_on_slurm_gives_the_local_likelihood_table_byte_for_byte(local, slurm, cluster):
    (local_dir, local_seconds), (slurm_dir, slurm_seconds, run) = local(), slurm
    assert (slurm_dir / TARGET).read_bytes() == (local_dir / TARGET).read_bytes()
    jobs = slurm_jobs(run, cluster)
    print(f"\ntiny sweep, side by side: local {local_seconds:.0f} s, Slurm {slurm_seconds:.0f} s with {len(jobs)} "
          f"Slurm jobs ({(slurm_seconds - local_seconds) / len(jobs):.0f} s overhead per Slurm job)")


def test_jobs_ask_slurm_for_their_rules_resources_and_fits_are_batched(slurm, cluster):
    """5 rule jobs, 3 Slurm jobs: each model's data jobs share one, fits share one (2 CPUs), the table has its own."""
    *_, run = slurm
    # (CPUs, memory, time limit, state): data_mesh then data_eval (1000 MB, 5 + 5 min); the 2 fits side by side
    # (2 x 1000 MB, 5 min); likelihood_table (500 MB, 5 min).
    assert slurm_jobs(run, cluster) == [("1", "1000M", "10:00", "COMPLETED"), ("2", "2000M", "5:00", "COMPLETED"),
                                        ("1", "500M", "5:00", "COMPLETED")]


def test_a_failed_cluster_job_fails_the_run_naming_its_log_and_leaves_no_output(slurm, config, cluster, tmp_path):
    """A corrupt evaluation set in the working directory: the fit jobs fail on the cluster."""
    slurm_dir, *_ = slurm
    shutil.copytree(slurm_dir / "results" / "data", tmp_path / "results" / "data")  # copy2 keeps the mtimes
    evaluation = tmp_path / "results" / "data" / "bunny" / "res4_eval.ply"
    evaluation.write_bytes(evaluation.read_bytes()[:300])  # a truncated copy, newer than the mesh it comes from
    _, run = on_slurm(tmp_path, config, cluster)
    assert run.returncode != 0
    # Both fits of the batch read the corrupt file; whichever fails first is reported (the other is stopped).
    named = set(re.findall(r"log: (results/logs/fits/\S+\.log)", run.stderr))
    assert "Error in rule fit" in run.stderr and named, run.stderr[-3000:]
    assert any("res4_eval.ply: cannot read points" in (tmp_path / log).read_text() for log in named)
    assert not (tmp_path / TARGET).exists()
    assert not [p for p in (tmp_path / "results" / "fits").rglob("*") if p.is_file()], "a failed fit left output"
    assert not list(tmp_path.rglob("*.part"))
