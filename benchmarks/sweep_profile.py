"""Where a cold sweep's time goes: the wall time of `make run` in sweep units, and per rule its jobs' wall time
and the part of it spent in the job's own computation.

    sweep units = cold sweep wall time / scikit-learn's time to fit 50,000 bunny points, K=100, 25 iterations,
                  one thread (benchmarks/em_speed.py's fit, timed in the same run)

so that runs on machines of different speed compare. Steps:

1. clone the committed HEAD beside this repository (``../shared`` then resolves as in CI): nothing is cached;
2. time the yardstick;
3. run the sweep in the clone as `make run` does once its install step is done (this environment's
   ``snakemake --cores N``, the clone first on ``PYTHONPATH``);
4. read every job's Snakemake ``benchmark:`` file (``results/benchmarks/{rule}/...tsv``, its wall time ``s``) and,
   for the rules that time their own computation, the job's timing table (the seconds a fit's seeds, a chunk's
   trials or an odometry run's frames took): overhead = job wall time - computation.

Usage: ``python benchmarks/sweep_profile.py [--cores 2] [--keep]`` (``make profile``); it prints the "Sweep profile"
section of docs/benchmarks.md, ready to paste.
"""
import argparse
import csv
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path
from statistics import mean, median

from threadpoolctl import threadpool_limits

from em_speed import sklearn_fit_seconds

REPO = Path(__file__).resolve().parents[1]

# rule -> (timing table of a job, relative to results/, from its benchmark file's path below the rule's folder;
#          the table's columns that hold the job's computation seconds)
COMPUTATION = {
    "fit": (lambda job: f"fits/{job}/seconds.csv", ("fit_seconds",)),
    "registration_chunk": (lambda job: f"registration/{job}/seconds.csv", ("seconds",)),
}


def read_rows(path):
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle, delimiter="\t" if path.suffix == ".tsv" else ","))


def job_times(results):
    """rule -> [(job wall seconds, computation seconds or None)] from the benchmark files under ``results``
    (Snakemake's ``s`` column; not its ``cpu_time``, which counts only the job's process, and a job of the sweep
    computes in a fork of the job server)."""
    jobs = defaultdict(list)
    root = results / "benchmarks"
    for path in sorted(root.rglob("*.tsv")):
        relative = path.relative_to(root)  # {rule}.tsv for a rule with one job, else {rule}/{wildcards}.tsv
        rule = relative.stem if len(relative.parts) == 1 else relative.parts[0]
        row = read_rows(path)[0]
        computation = None
        if rule in COMPUTATION and len(relative.parts) > 1:
            table, columns = COMPUTATION[rule]
            job = relative.relative_to(rule).with_suffix("").as_posix()
            computation = sum(float(r[c]) for r in read_rows(results / table(job)) for c in columns)
        jobs[rule].append((float(row["s"]), computation))
    return jobs


def rule_table(jobs):
    """Markdown table per rule: jobs, mean and total job wall time, mean computation, and the median overhead
    (job wall - computation)."""
    lines = ["| rule | jobs | mean job wall (s) | sum of job walls (s) | mean computation (s) "
             "| median overhead (s) |",
             "|---|---:|---:|---:|---:|---:|"]
    for rule, times in sorted(jobs.items(), key=lambda item: -sum(w for w, _ in item[1])):
        walls = [w for w, _ in times]
        timed = [(w, t) for w, t in times if t is not None]
        comp = f"{mean(t for _, t in timed):.2f}" if timed else "–"
        over = f"{median(w - t for w, t in timed):.2f}" if timed else "–"
        lines.append(f"| {rule} | {len(times)} | {mean(walls):.2f} | {sum(walls):.0f} | {comp} | {over} |")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("--keep", action="store_true", help="keep the clone (its results/) after the run")
    args = parser.parse_args()

    clone = Path(tempfile.mkdtemp(prefix="sweep-profile-", dir=REPO.parent))
    try:
        subprocess.run(["git", "clone", "--quiet", str(REPO), str(clone)], check=True)
        with threadpool_limits(1):
            yardstick = sklearn_fit_seconds()
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=clone, capture_output=True, text=True,
                                check=True).stdout.strip()
        load_before = os.getloadavg()
        env = {**os.environ, "PYTHONPATH": str(clone)}
        snakemake = Path(sys.executable).with_name("snakemake")
        start = time.perf_counter()
        subprocess.run([str(snakemake), "--cores", str(args.cores)], cwd=clone, env=env, check=True)
        wall = time.perf_counter() - start
        load = os.getloadavg()
        print("### Sweep profile\n")
        print(f"`make profile` at commit {commit}: cold sweep {wall:.0f} s on {args.cores} cores; yardstick "
              f"(scikit-learn, 50k points, K=100, 25 iterations, 1 thread) {yardstick:.2f} s; "
              f"**{wall / yardstick:.1f} sweep units** (goal ≤ 25); load average before "
              f"{' / '.join(f'{x:.2f}' for x in load_before)}, after {' / '.join(f'{x:.2f}' for x in load)}. "
              "Per rule, from each job's Snakemake `benchmark:` file (results/benchmarks/) and, for `fit` and "
              "`registration_chunk`, the job's own timing table (its seeds' or trials' seconds): overhead is the "
              "rest of the job (starting it, loading, scoring, recordings; goal ≤ 1 s median).\n")
        print(rule_table(job_times(clone / "results")))
    finally:
        if args.keep:
            print(f"\nkept {clone}")
        else:
            shutil.rmtree(clone, ignore_errors=True)


if __name__ == "__main__":
    main()
