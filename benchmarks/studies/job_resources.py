"""Peak memory and wall time of representative sweep jobs, for the `resources:` the rules declare.

Runs real Snakemake (full `config.yaml`, one core) on one target at a time in a temporary directory, in dependency
order, so that every job script started during a target's run is that target's own job. While it runs, the job's
process is polled for its peak resident set size (``VmHWM`` in ``/proc/PID/status``, which only grows, so the last
poll is the peak to within one poll interval) and its wall time. Prints one table row per job.

Usage: ``python benchmarks/studies/job_resources.py [WORKDIR]`` (a fresh temporary directory when omitted).
"""
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import psutil

REPO = Path(__file__).resolve().parents[2]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
POLL_SECONDS = 0.05

# (rule, target) in dependency order: each target's inputs are built by the rows above it.
TARGETS = [
    ("data_mesh", "results/data/armadillo/full.ply"),  # the largest registered file (an OBJ)
    ("data_mesh", "results/data/bunny/full.ply"),
    ("data_mesh", "results/data/bunny/res4.ply"),
    ("data_eval", "results/data/armadillo/full_eval.ply"),  # 50k Poisson-disk points
    ("data_eval", "results/data/bunny/full_eval.ply"),
    ("data_eval", "results/data/bunny/res4_eval.ply"),
    ("data_reduce", "results/data/armadillo/quadric1000.ply"),
    ("data_reduce", "results/data/armadillo/clustering1000.ply"),
    ("data_reduce", "results/data/bunny/poisson1000.ply"),
    ("data_reduce", "results/data/bunny/random1000.ply"),
    ("fit", "results/fits/bunny/res4-exact/textbook/k400-kmeans/scores.csv"),
    ("fit", "results/fits/bunny/res4-exact/authors/k400-random/scores.csv"),
    ("fit", "results/fits/bunny/poisson1000-points/textbook/k400-kmeans/scores.csv"),
    ("fit", "results/fits/armadillo/quadric1000-exact/textbook/k100-kmeans/scores.csv"),
    ("fig2", "results/tables/fig2.csv"),
]


def peak_rss_mb(process):
    """Peak resident set size of a live process in MB (``VmHWM``), or None once it has gone.

    Parameters
    ----------
    process : psutil.Process
        The job script's process.

    Returns
    -------
    float or None
        ``VmHWM`` in MB (10**6 bytes).
    """
    try:
        for line in Path(f"/proc/{process.pid}/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024 / 1e6
    except (FileNotFoundError, ProcessLookupError):
        return None
    return None


def measure(workdir, target):
    """Build one target with Snakemake and poll the job scripts it starts.

    Parameters
    ----------
    workdir : Path
        Snakemake's working directory (``--directory``).
    target : str
        The file to build; its inputs already exist in ``workdir``.

    Returns
    -------
    list of tuple of (float, float)
        ``(peak_rss_mb, wall_seconds)`` of each job script started.
    """
    command = [str(SNAKEMAKE), "--snakefile", str(REPO / "Snakefile"), "--directory", str(workdir),
               "--configfile", str(REPO / "config.yaml"), "--cores", "1", target]
    workdir.mkdir(parents=True, exist_ok=True)
    log = workdir / "snakemake.log"
    with open(log, "w") as stderr:
        snakemake = psutil.Popen(command, stdout=subprocess.DEVNULL, stderr=stderr)
    jobs = {}  # pid -> [process, peak MB, start, last seen]
    while snakemake.poll() is None:
        now = time.monotonic()
        for child in snakemake.children(recursive=True):
            if child.pid not in jobs:
                try:
                    if not any("/.snakemake/scripts/" in part for part in child.cmdline()):
                        continue
                except psutil.Error:
                    continue
                jobs[child.pid] = [child, 0.0, now, now]
        for job in jobs.values():
            peak = peak_rss_mb(job[0])
            if peak is not None:
                job[1], job[3] = max(job[1], peak), now
        time.sleep(POLL_SECONDS)
    if snakemake.returncode:
        raise RuntimeError(f"snakemake {target} failed:\n{log.read_text()[-2000:]}")
    return [(peak, last - start) for _, peak, start, last in jobs.values()]


def main():
    """Measure every target of TARGETS and print a Markdown table."""
    workdir = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="dgmm-resources-"))
    print("| rule | target | peak RSS (MB) | wall (s) |\n|---|---|---:|---:|", flush=True)
    for rule, target in TARGETS:
        for peak, seconds in measure(workdir, target):
            print(f"| {rule} | {target.removeprefix('results/')} | {peak:.0f} | {seconds:.1f} |", flush=True)


if __name__ == "__main__":
    main()
