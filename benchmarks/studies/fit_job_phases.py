"""Where a fit job's time goes: the phases of workflow/scripts/fit.py for one (input, K, init, variant), in process.

A job of the sweep runs in a fork of the job server (dgmm.runtime.job_server) whose imports are loaded, so this script
imports first and times only what the job does after them: read the input mesh and the evaluation set, build the
primitives, open the recordings (MCAP and rerun), fit the 10 seeds (recording every iteration), score each fit on
the 50,000-point evaluation set (its primitives built once), close the recordings. The sweep profile counts the fits
as the job's computation and the rest as its overhead. Scoring is timed twice more, one seed's mixture on the
evaluation set: from the moment table, as ``GaussianMixture.score`` scores 3-D primitives, and from BLAS's 1 MiB
blocks of ``log rho``, its route in other dimensions (and 3-D's before 8faf1f5).

The evaluation set is a Poisson-disk sample of bunny res4 as the data stage draws it (dgmm.meshes.poisson_disk; a
few seconds, not timed). Times are process CPU and wall; the load average is printed beside them.

Before all this a job starts: Snakemake runs the script in a new Python whose first lines are Snakemake's preamble
(unpickling the job's ``snakemake`` object imports parts of Snakemake), then ``hand_over`` sends it to the server,
which forks. Timed last, on a job server of the sweep's preloads: 10 runs of a script that only hands over, and of
one with the preamble's imports before it (median wall; CPU of the client processes, not of the forks).

Run: ``python benchmarks/studies/fit_job_phases.py [--input res4-exact] [--components 100] [--init kmeans]
[--variant textbook]``
"""
import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import trimesh  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

import dgmm.mixture  # noqa: E402
from dgmm.compiled.scoring import screened_log_normalisers  # noqa: E402
from dgmm.data import load_mesh, save_ply  # noqa: E402
from dgmm.gaussian import SCREEN  # noqa: E402
from dgmm.experiments.sweep import SIZED, build_input, fit_seeds, parse_input  # noqa: E402
from dgmm.primitives import Primitives  # noqa: E402
from dgmm.meshes import poisson_disk  # noqa: E402
from dgmm.recording import FitRecorder  # noqa: E402
from dgmm.runtime.job_server import JobServer, script_imports  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
BUNNY = REPO / ".." / "shared" / "data" / "stanford" / "bunny_res4.ply"
HAND_OVER = "from dgmm.runtime.job_server import hand_over\nhand_over()\n"
PREAMBLE = "import pickle\nfrom snakemake.logging import logger\nfrom snakemake.iocontainers import Snakemake\n"


class Phases:
    """Wall and CPU seconds between successive :meth:`mark` calls."""

    def __init__(self):
        self.rows, self._last = [], (time.perf_counter(), time.process_time())

    def mark(self, name):
        now = (time.perf_counter(), time.process_time())
        self.rows.append((name, now[0] - self._last[0], now[1] - self._last[1]))
        self._last = now


def _cpu(function, repeats=3):
    best = np.inf
    for _ in range(repeats):
        start = time.process_time()
        function()
        best = min(best, time.process_time() - start)
    return best


def start_seconds(folder, runs=10):
    """{script: (median wall, mean client CPU)} of jobs that only hand over to a job server of the sweep's preloads,
    without and with Snakemake's preamble imports before."""
    scripts = {"hand over only": HAND_OVER, "preamble, then hand over": PREAMBLE + HAND_OVER}
    server = JobServer(["snakemake.script", *script_imports(sorted((REPO / "workflow" / "scripts").glob("*.py")))])
    server.start()
    try:
        results = {}
        for name, text in scripts.items():
            path = folder / f"{len(results)}.py"
            path.write_text(text)
            subprocess.run([sys.executable, path], check=True)  # the first waits for the server's imports
            walls, before = [], resource.getrusage(resource.RUSAGE_CHILDREN)
            for _ in range(runs):
                start = time.perf_counter()
                subprocess.run([sys.executable, path], check=True)
                walls.append(time.perf_counter() - start)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu = (after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime) / runs
            results[name] = (float(np.median(walls)), cpu)
        return results
    finally:
        server.stop()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--input", default="res4-exact", help="res4-exact, res4-approx, res4-centroids, res4-vertices")
    parser.add_argument("--components", type=int, default=100)
    parser.add_argument("--init", default="kmeans")
    parser.add_argument("--variant", default="textbook")
    parser.add_argument("--seeds", type=int, default=10)
    args = parser.parse_args()
    print(f"load average at start: {os.getloadavg()}")
    folder = Path(tempfile.mkdtemp(prefix="fit-job-phases-"))
    mesh_path, eval_path = folder / "res4.ply", folder / "res4_eval.ply"
    save_ply(mesh_path, *load_mesh(BUNNY))
    save_ply(eval_path, poisson_disk(*load_mesh(mesh_path), 50_000))

    phases = Phases()
    vertices, faces = load_mesh(mesh_path)
    evaluation = np.asarray(trimesh.load(eval_path, process=False).vertices)
    phases.mark("read the mesh and the evaluation set")
    prims = build_input(args.input, vertices, faces)
    shown = trimesh.Trimesh(vertices, faces, process=False) if parse_input(args.input)[1] in SIZED else prims
    phases.mark("build the primitives")
    with threadpool_limits(1):
        recorder = FitRecorder(folder / "fit.mcap", folder / "fit.rrd", params={}, data=shown)
        phases.mark("open the recordings")
        models = []
        original_score = dgmm.mixture.GaussianMixture.score
        dgmm.mixture.GaussianMixture.score = lambda model, X, y=None: models.append(model) or 0.0  # time it apart
        try:
            _, seconds = fit_seeds(prims, evaluation, n_components=args.components, init=args.init,
                                   variant=args.variant, n_seeds=args.seeds, root_seed=0, key="phases",
                                   max_iter=25, tol=1e-12, reg_covar=1e-6, recorder=recorder)
        finally:
            dgmm.mixture.GaussianMixture.score = original_score
        phases.mark(f"fit {args.seeds} seeds, recording every iteration (the job's computation)")
        prepared = Primitives.from_points(evaluation)  # once for the seeds' scores, as fit_seeds does
        for model in models:
            model.score(prepared)
        phases.mark(f"score {args.seeds} fits on the {len(evaluation)} evaluation points")
        recorder.close()
        phases.mark("close the recordings")
        table = _cpu(lambda: models[0].score_samples(evaluation))
        e_step = dgmm.mixture.EStep(*models[0]._full_parameters())
        blocks = _cpu(lambda: np.concatenate([screened_log_normalisers(rows, SCREEN) for rows in
                                              e_step._log_rho_rows(prepared.means, prepared.covariances, 1.0)]))

    print(f"\nfit job {args.input} K={args.components} {args.init} {args.variant}, {args.seeds} seeds, 25 iterations, "
          f"1 thread ({len(prims)} primitives; fit seconds as the job records them: {sum(seconds):.3f})")
    print(f"{'phase':>72} {'wall s':>7} {'CPU s':>6}")
    for name, wall, cpu in phases.rows:
        print(f"{name:>72} {wall:7.3f} {cpu:6.3f}")
    print(f"one score of {len(evaluation)} points, CPU: {1e3 * table:.1f} ms from the moment table, {1e3 * blocks:.1f} "
          f"ms from 1 MiB log rho blocks ({blocks / table:.2f}x)")
    for name, (wall, cpu) in start_seconds(folder).items():
        print(f"job start, {name}: median wall {wall:.3f} s, client CPU {cpu:.3f} s")
    print(f"load average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
