"""Snakemake's own cost per job under its two schedulers: a workflow of one-line jobs, run with each.

The sweep runs about 400 jobs on 2 cores. Between a job's end and the next job's start on that core Snakemake
checks and records the outputs and selects the next jobs: the greedy scheduler in a few loops over the ready jobs,
the ILP scheduler (Snakemake's default) by solving a mixed-integer program with CBC in a subprocess. This runs a
temporary workflow of ``--jobs`` jobs that each write one line (all ready at once, as the sweep's fits are), with
``--cores 2``, alternately under each scheduler, and prints each run's wall time and the CPU time of Snakemake and
its children (the solver included).

Run: ``python benchmarks/studies/scheduler_overhead.py [--jobs 200] [--repeats 2]``
"""
import argparse
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SNAKEFILE = """
rule all:
    input: expand("out/{{i}}.txt", i=range({jobs}))
rule job:
    output: "out/{{i}}.txt"
    benchmark: "bench/{{i}}.tsv"
    threads: 1
    shell: "echo {{wildcards.i}} > {{output}}"
"""


def run(folder, scheduler):
    """Wall and children's CPU seconds of one run of the workflow in ``folder`` from scratch."""
    for name in ("out", "bench", ".snakemake"):
        shutil.rmtree(folder / name, ignore_errors=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run([str(Path(sys.executable).with_name("snakemake")), "--cores", "2", "--scheduler", scheduler,
                    "--quiet", "all"], cwd=folder, check=True, capture_output=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    folder = Path(tempfile.mkdtemp(prefix="scheduler-overhead-"))
    try:
        (folder / "Snakefile").write_text(SNAKEFILE.format(jobs=args.jobs))
        print(f"load average at start: {os.getloadavg()}")
        print(f"{args.jobs} one-line jobs, --cores 2")
        for repeat in range(args.repeats):
            for scheduler in ("greedy", "ilp"):
                wall, cpu = run(folder, scheduler)
                print(f"{scheduler:>7}: wall {wall:6.2f} s ({1e3 * wall / args.jobs:5.1f} ms per job), CPU {cpu:6.2f} s "
                      f"({1e3 * cpu / args.jobs:5.1f} ms per job)")
        print(f"load average at end: {os.getloadavg()}")
    finally:
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
