"""SIGTERM a tiny `fits` sweep at random moments just after a job finishes; count the runs that do not stop.

Snakemake's own SIGTERM handler deadlocks when the signal lands while its main thread records finished jobs
(``dgmm.runtime.snakemake_sigterm``). The window is narrow: this script aims at it. Each trial copies the tiny config's
data stage (made once) into a fresh directory, starts ``snakemake fits`` on ``--repo``'s Snakefile, waits until 1-8 jobs
have written their scores, sleeps up to ``--delay`` s, sends SIGTERM and waits 60 s: a run still alive then is a
hang (killed, counted). ``--burn`` runs a CPU-bound process beside the trials (a loaded machine widens the window).

Usage: ``python benchmarks/studies/sigterm_stress.py [--repo CHECKOUT] [--trials 40] [--delay 0.05] [--burn]
[--seed 0]``; ``--repo`` a checkout of an older commit measures the code before.
"""
import argparse
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")


def command(repo, workdir):
    return [str(SNAKEMAKE), "--snakefile", str(repo / "Snakefile"), "--directory", str(workdir), "--configfile",
            str(repo / "tests" / "config.yaml"), "--cores", "2", "fits"]


def trial(repo, data, rng, delay):
    """One interrupted run: True if it stopped within 60 s of SIGTERM."""
    workdir = Path(tempfile.mkdtemp(prefix="sigterm-stress-"))
    try:
        shutil.copytree(data, workdir / "results" / "data")
        run = subprocess.Popen(command(repo, workdir), env={**os.environ, "PYTHONPATH": str(repo)},
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        fits, target, deadline = workdir / "results" / "fits", rng.randint(1, 8), time.monotonic() + 120
        while len(list(fits.rglob("scores.csv"))) < target and time.monotonic() < deadline and run.poll() is None:
            time.sleep(0.01)
        time.sleep(rng.random() * delay)
        run.send_signal(signal.SIGTERM)
        try:
            run.wait(timeout=60)
            return True
        except subprocess.TimeoutExpired:
            os.killpg(run.pid, signal.SIGKILL)
            run.wait()
            return False
    finally:
        shutil.rmtree(workdir, ignore_errors=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repo", type=Path, default=REPO, help="checkout whose Snakefile and dgmm run")
    parser.add_argument("--trials", type=int, default=40)
    parser.add_argument("--delay", type=float, default=0.05, help="longest sleep between a job's end and SIGTERM")
    parser.add_argument("--burn", action="store_true", help="a CPU-bound process beside the trials")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    repo, rng = args.repo.resolve(), random.Random(args.seed)
    stage = Path(tempfile.mkdtemp(prefix="sigterm-stress-data-"))
    burner = None
    try:
        subprocess.run(command(repo, stage), env={**os.environ, "PYTHONPATH": str(repo)}, check=True,
                       capture_output=True)
        if args.burn:
            burner = subprocess.Popen([sys.executable, "-c", "import numpy as np\na = np.random.rand(300, 300)\n"
                                       "while True:\n    a @ a\n"])
        hangs = sum(not trial(repo, stage / "results" / "data", rng, args.delay) for _ in range(args.trials))
    finally:
        if burner is not None:
            burner.kill()
        shutil.rmtree(stage, ignore_errors=True)
    print(f"{repo}: {hangs} of {args.trials} runs did not stop within 60 s of SIGTERM")


if __name__ == "__main__":
    main()
