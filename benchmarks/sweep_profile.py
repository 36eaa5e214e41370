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
   trials, an odometry run's frames or a timing check's repeats took): overhead = job wall time - computation; the
   visual-odometry stage's share of the job time (the ``odometry_*`` rules' job walls over all jobs'; goal ≤ a
   third); and the floor, those computations alone spread over the cores, the wall time no cut of overhead beats;
5. account for the cores' idle time, ``cores x wall - sum of job walls``, from Snakemake's metadata
   (``.snakemake/metadata``: each job's start, the time its outputs were written, its inputs): before the first
   job starts (Snakemake builds the DAG), with fewer jobs running than cores (between a job's end and the next
   start on its core Snakemake checks and records outputs and selects jobs), after the last job, and the rest
   (inside a job's span but outside its benchmark window: Snakemake starting the script); and the critical
   path, the longest chain of jobs through the DAG, the wall time no number of cores could beat.

Usage: ``python benchmarks/sweep_profile.py [--cores 2] [--keep]`` (``make profile``); it prints the tables of
docs/benchmarks/sweep.md, ready to paste. ``--workdir DIR`` prints the tables of a run already made in ``DIR``
(its wall time taken from its first job's start to its last job's end; ``--yardstick S`` gives its units).
"""
import argparse
import base64
import csv
import json
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
    "odometry_run": (lambda job: f"odometry/{job}/seconds.csv", ("cpu_seconds",)),
    "check_timing": (lambda job: f"checks/timing/{job}.csv", ("seconds",)),
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
            computation = sum(float(r[c]) for r in read_rows(results / table(job)) for c in columns if r[c])
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


def job_spans(workdir):
    """Every job of the Snakemake run in ``workdir``, from its metadata (one record per output file): a list of
    dicts with ``rule``, ``start`` (epoch seconds Snakemake marked the outputs incomplete, starting the job),
    ``end`` (the outputs' last modification), ``inputs`` and ``outputs`` (paths relative to ``workdir``)."""
    root = Path(workdir) / ".snakemake" / "metadata"
    jobs = {}
    for path in sorted(p for p in root.rglob("*") if p.is_file()):
        # a long path's base64 name is split into folders whose names start with "@"
        output = base64.urlsafe_b64decode("".join(part.lstrip("@") for part in path.relative_to(root).parts))
        record = json.loads(path.read_text())
        job = jobs.setdefault((record["rule"], record["job_hash"]),
                              dict(rule=record["rule"], start=record["starttime"], end=record["endtime"],
                                   inputs=set(record["input"]), outputs=set()))
        job["start"], job["end"] = min(job["start"], record["starttime"]), max(job["end"], record["endtime"])
        job["outputs"].add(output.decode())
    return list(jobs.values())


def job_wall(jobs, prefix=""):
    """Sum of the job wall times of the rules named ``prefix…`` (every rule by default)."""
    return sum(wall for rule, times in jobs.items() if rule.startswith(prefix) for wall, _ in times)


def stage_line(jobs, prefix="odometry"):
    """Markdown line: the job wall time of the rules named ``prefix…`` (the visual-odometry stage) and its share
    of all jobs'."""
    total, stage = job_wall(jobs), job_wall(jobs, prefix)
    return (f"Visual odometry (the `{prefix}_*` rules): {stage:.0f} of {total:.0f} s of job time, "
            f"**{100 * stage / total:.1f}%** (goal ≤ a third).")


def floor_line(jobs, cores, yardstick=None):
    """Markdown line: the sweep's wall time if nothing but the computations its rules time themselves ran (the fits'
    seeds, the registration trials, the odometry frames' CPU, the timing checks' repeats), spread evenly over
    ``cores``: a floor no cut of overhead alone can go below (in sweep units with ``yardstick``)."""
    computation = sum(t for times in jobs.values() for _, t in times if t is not None)
    units = f", **{computation / cores / yardstick:.1f} sweep units**" if yardstick else ""
    return (f"Computation alone (fits' seeds, registration trials, odometry frames' CPU, timing repeats): "
            f"{computation:.0f} of {job_wall(jobs):.0f} s of job time; on {cores} cores with nothing else, "
            f"{computation / cores:.0f} s{units}.")


def running_below(spans, cores):
    """Core-seconds left idle while fewer than ``cores`` of the jobs ``spans`` ran, between the first start and
    the last end."""
    events = sorted([(job["start"], 1) for job in spans] + [(job["end"], -1) for job in spans])
    idle, running, previous = 0.0, 0, events[0][0]
    for moment, change in events:
        idle += max(0, cores - running) * (moment - previous)
        running, previous = running + change, moment
    return idle


def critical_path(spans):
    """The chain of jobs, each using an output of the one before, whose spans add up longest: (seconds, rules
    of the chain in order)."""
    producer = {output: index for index, job in enumerate(spans) for output in job["outputs"]}
    longest = {}

    def finish(index):  # the longest chain ending with job ``index``: (seconds, previous job or None)
        if index not in longest:
            job = spans[index]
            before = max(((finish(producer[f])[0], producer[f]) for f in job["inputs"] if f in producer),
                         default=(0.0, None))
            longest[index] = (before[0] + job["end"] - job["start"], before[1])
        return longest[index]

    for index in sorted(range(len(spans)), key=lambda i: spans[i]["start"]):  # producers first: shallow recursion
        finish(index)
    last = max(longest, key=lambda i: longest[i][0])
    chain, index = [], last
    while index is not None:
        chain.append(spans[index]["rule"])
        index = longest[index][1]
    return longest[last][0], chain[::-1]


def idle_table(spans, jobs, cores, wall, run_start=None, run_end=None):
    """Markdown lines accounting for the run's idle core-seconds, ``cores x wall - sum of job walls`` (job walls
    from the benchmark files, ``jobs`` as :func:`job_times` returns), and its critical path."""
    walls = job_wall(jobs)
    first, last = min(j["start"] for j in spans), max(j["end"] for j in spans)
    before = cores * (first - run_start) if run_start is not None else 0.0
    after = cores * (run_end - last) if run_end is not None else 0.0
    below = running_below(spans, cores)
    idle = cores * wall - walls
    length, chain = critical_path(spans)
    steps = [rule for i, rule in enumerate(chain) if i == 0 or rule != chain[i - 1]]
    return "\n".join([
        f"Idle core-seconds ({cores} x wall - sum of job walls): **{idle:.0f}** of {cores * wall:.0f} "
        f"({100 * idle / (cores * wall):.0f}%):",
        "",
        "| where | core-seconds |",
        "|---|---:|",
        f"| before the first job (Snakemake starts, builds the DAG) | {before:.0f} |",
        f"| fewer jobs running than cores (a job's end to its core's next start included: Snakemake checks "
        f"and records outputs, selects the next jobs) | {below:.0f} |",
        f"| after the last job | {after:.0f} |",
        f"| inside jobs' spans, outside their benchmark windows (Snakemake starting the job's script) "
        f"| {idle - before - below - after:.0f} |",
        "",
        f"Critical path (the longest chain of jobs, each using an output of the one before): {length:.0f} s, "
        f"{len(chain)} jobs: {' → '.join(steps)}.",
    ])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("--keep", action="store_true", help="keep the clone (its results/) after the run")
    parser.add_argument("--workdir", type=Path, help="only print the tables of the run already made in this folder")
    parser.add_argument("--yardstick", type=float, help="with --workdir: that run's yardstick seconds, for units")
    args = parser.parse_args()
    if args.workdir is not None:
        spans = job_spans(args.workdir)
        jobs = job_times(args.workdir / "results")
        print(rule_table(jobs) + "\n")
        print(stage_line(jobs) + "\n")
        print(floor_line(jobs, args.cores, args.yardstick) + "\n")
        print(idle_table(spans, jobs, args.cores, max(j["end"] for j in spans) - min(j["start"] for j in spans)))
        return

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
        start, run_start = time.perf_counter(), time.time()
        subprocess.run([str(snakemake), "--cores", str(args.cores)], cwd=clone, env=env, check=True)
        wall, run_end = time.perf_counter() - start, time.time()
        load = os.getloadavg()
        print("### Sweep profile\n")
        print(f"`make profile` at commit {commit}: cold sweep {wall:.0f} s on {args.cores} cores; yardstick "
              f"(scikit-learn, 50k points, K=100, 25 iterations, 1 thread) {yardstick:.2f} s; "
              f"**{wall / yardstick:.1f} sweep units** (goal ≤ 15); load average before "
              f"{' / '.join(f'{x:.2f}' for x in load_before)}, after {' / '.join(f'{x:.2f}' for x in load)}. "
              "Per rule, from each job's Snakemake `benchmark:` file (results/benchmarks/) and, for `fit`, "
              "`registration_chunk`, `odometry_run` and `check_timing`, the job's own timing table (its seeds', "
              "trials', frames' or repeats' seconds): overhead is the "
              "rest of the job (starting it, loading, scoring, recordings; goal ≤ 1 s median).\n")
        jobs = job_times(clone / "results")
        print(rule_table(jobs) + "\n")
        print(stage_line(jobs) + "\n")
        print(floor_line(jobs, args.cores, yardstick) + "\n")
        print(idle_table(job_spans(clone), jobs, args.cores, wall, run_start, run_end))
    finally:
        if args.keep:
            print(f"\nkept {clone}")
        else:
            shutil.rmtree(clone, ignore_errors=True)


if __name__ == "__main__":
    main()
