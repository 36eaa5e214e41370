"""EM at scale: seconds per iteration and peak memory against the number of triangles, 1 and 2 threads.

The full Stanford bunny (69,451 triangles) subdivided by trimesh 0–3 times: about 70k, 280k, 1.1M and 4.4M
triangles, fitted as exact triangles with K = 100 and 1000 (k-means start, seed 0) on ``--jobs`` threads;
the same numbers of points (the triangle centroids) through scikit-learn's ``GaussianMixture`` where its
``(n, K)`` arrays fit in ``--sklearn-max-gb``. Every measurement runs in a fresh process, so its peak resident
set size (``VmHWM``: interpreter, libraries, mesh and fit) is its own (``ru_maxrss`` is not: Linux carries
the parent's peak over ``fork`` and ``exec``). Seconds per iteration are the
fastest gap between two EM callbacks (dgmm), or scikit-learn's fit time over its iterations + 1 (its extra
E-steps, from a given start so no k-means); ``init`` is dgmm's time to the first callback minus one iteration
(moment table and k-means start). The load average is printed beside every row: on a shared machine the
thread speed-up is only meaningful when the load is below the core count.

Usage::

    python benchmarks/em_scale.py                         # every size, K and thread count, 4 iterations
    python benchmarks/em_scale.py --levels 0 1 --components 100 --iterations 3
    python benchmarks/em_scale.py --plot-only             # redraw the plot from the results CSV

Meshes are cached as .npz in ``--workdir`` (default ``results/em_scale``, git-ignored); ``--ply`` also writes
the largest mesh as PLY there, for ``dgmm fit``. Results go to ``WORKDIR/em_scale.csv`` (appended) and the plot
to ``docs/benchmark/em_scale.png``.
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
FIELDS = ["library", "n_prims", "k", "jobs", "seconds_per_iteration", "init_seconds", "peak_rss_mb", "load_1min"]


def mesh_path(workdir, level):
    return Path(workdir) / f"bunny_sub{level}.npz"


def make_meshes(workdir, levels, ply):
    """The full bunny from the data registry, subdivided ``level`` times, cached as .npz."""
    import trimesh

    from dgmm.data import REGISTRY, fetch, load_mesh, save_ply

    Path(workdir).mkdir(parents=True, exist_ok=True)
    source = fetch(REGISTRY["bunny"]["full"], mirrors=[REPO.parent / "shared" / "data" / "stanford"],
                   cache=Path("~/.cache/dgmm").expanduser())
    vertices, faces = load_mesh(source)
    for level in range(max(levels) + 1):
        path = mesh_path(workdir, level)
        if level in levels and not path.exists():
            np.savez(path, vertices=vertices, faces=faces.astype(np.int32))
        if level == max(levels) and ply:
            save_ply(Path(workdir) / f"bunny_sub{level}.ply", vertices, faces)
        if level < max(levels):
            vertices, faces = trimesh.remesh.subdivide(vertices, faces)


def measure_dgmm(path, k, jobs, iterations):
    """One dgmm fit of the mesh at ``path``: seconds per iteration and to the first iteration."""
    from dgmm import GaussianMixture, Primitives

    with np.load(path) as mesh:
        prims = Primitives.from_mesh(mesh["vertices"], mesh["faces"])
    times = []
    start = time.perf_counter()
    GaussianMixture(k, max_iter=iterations, tol=0, random_state=0, n_jobs=jobs,
                    callback=lambda iteration, model: times.append(time.perf_counter())).fit(prims)
    per_iteration = float(np.min(np.diff(times))) if len(times) > 1 else float("nan")
    return len(prims), per_iteration, times[0] - start - per_iteration


def measure_sklearn(path, k, jobs, iterations):
    """One scikit-learn fit of the triangle centroids, from a start drawn from the data (no k-means)."""
    from sklearn.mixture import GaussianMixture as SklearnGaussianMixture
    from threadpoolctl import threadpool_limits

    with np.load(path) as mesh:
        points = mesh["vertices"][mesh["faces"]].mean(axis=1)
    rng = np.random.default_rng(0)
    start = dict(weights_init=np.full(k, 1.0 / k), means_init=points[rng.choice(len(points), k, replace=False)],
                 precisions_init=np.tile(np.eye(3) / points.var(axis=0).mean() * k ** (2 / 3), (k, 1, 1)))
    with threadpool_limits(jobs), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # not converged
        begin = time.perf_counter()
        SklearnGaussianMixture(k, max_iter=iterations, tol=0, **start).fit(points)
        seconds = time.perf_counter() - begin
    return len(points), seconds / (iterations + 1), float("nan")


def peak_rss_mb():
    """Peak resident set size of this process's memory (``VmHWM``), in MB."""
    status = Path("/proc/self/status").read_text()
    return int(status.split("VmHWM:")[1].split()[0]) / 1024


def run_one(args):
    """Child process: one measurement, printed as a JSON row."""
    measure = measure_sklearn if args.one == "sklearn" else measure_dgmm
    n_prims, per_iteration, init = measure(args.mesh, args.k, args.jobs, args.iterations)
    peak_mb = peak_rss_mb()
    print(json.dumps(dict(library=args.one, n_prims=n_prims, k=args.k, jobs=args.jobs,
                          seconds_per_iteration=round(per_iteration, 4), init_seconds=round(init, 3),
                          peak_rss_mb=round(peak_mb, 1), load_1min=round(os.getloadavg()[0], 2))))


def measure_in_child(library, path, k, jobs, iterations):
    command = [sys.executable, __file__, "--one", library, "--mesh", str(path), "--k", str(k), "--jobs", str(jobs),
               "--iterations", str(iterations)]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed:\n{result.stderr}")
    return json.loads(result.stdout.strip().splitlines()[-1])


def plot(rows, png):
    """Log-log seconds per iteration and peak RSS against n_prims, one line per (library, K, threads)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = list({(r["library"], r["n_prims"], r["k"], r["jobs"]): r for r in rows}.values())  # latest of each
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    lines = sorted({(r["library"], int(r["k"]), int(r["jobs"])) for r in rows})
    for library, k, jobs in lines:
        points = sorted((int(r["n_prims"]), float(r["seconds_per_iteration"]), float(r["peak_rss_mb"]))
                        for r in rows if (r["library"], int(r["k"]), int(r["jobs"])) == (library, k, jobs))
        n, seconds, memory = np.array(points).T
        style = dict(marker="o" if library == "dgmm" else "s", linestyle="-" if library == "dgmm" else "--",
                     label=f"{library} K={k}, {jobs} thread{'s' if jobs > 1 else ''}")
        axes[0].loglog(n, seconds, **style)
        axes[1].loglog(n, memory / 1024, **style)
    all_n = np.array(sorted({int(r["n_prims"]) for r in rows}), dtype=float)
    if len(all_n) > 1:
        ref = [float(r["seconds_per_iteration"]) for r in rows if int(r["n_prims"]) == all_n[0]]
        axes[0].loglog(all_n, min(ref) * all_n / all_n[0], color="grey", linewidth=0.8, label="∝ n (linear)")
    axes[0].set(xlabel="primitives (triangles; points for scikit-learn)", ylabel="seconds per EM iteration")
    axes[1].set(xlabel="primitives (triangles; points for scikit-learn)", ylabel="peak RSS (GB)")
    axes[1].axhline(2.0, color="grey", linewidth=0.8, linestyle=":")
    for ax in axes:
        ax.grid(True, which="both", linewidth=0.3)
    axes[0].legend(fontsize=6.5)
    loads = [float(r["load_1min"]) for r in rows]
    fig.suptitle(f"EM on the subdivided bunny (load average {min(loads):.1f}–{max(loads):.1f} on "
                 f"{os.cpu_count()} cores)", fontsize=9)
    fig.tight_layout()
    Path(png).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(png, dpi=80)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--levels", type=int, nargs="+", default=[0, 1, 2, 3], help="subdivisions of the bunny")
    parser.add_argument("--components", type=int, nargs="+", default=[100, 1000])
    parser.add_argument("--jobs", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--iterations", type=int, default=4,
                        help="EM iterations per fit (>= 2; the fastest gap between two is timed)")
    parser.add_argument("--sklearn-max-gb", type=float, default=3.0,
                        help="run scikit-learn where 4 (n, K) float64 arrays fit in this (default: %(default)s)")
    parser.add_argument("--workdir", type=Path, default=REPO / "results" / "em_scale")
    parser.add_argument("--png", type=Path, default=REPO / "docs" / "benchmark" / "em_scale.png")
    parser.add_argument("--ply", action="store_true", help="also write the largest mesh as PLY")
    parser.add_argument("--plot-only", action="store_true")
    parser.add_argument("--one", choices=["dgmm", "sklearn"], help=argparse.SUPPRESS)
    parser.add_argument("--mesh", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--k", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        args.jobs = args.jobs[0] if isinstance(args.jobs, list) else args.jobs
        return run_one(args)

    table = args.workdir / "em_scale.csv"
    if not args.plot_only:
        make_meshes(args.workdir, args.levels, args.ply)
        new = not table.exists()
        with open(table, "a", newline="") as stream:
            writer = csv.DictWriter(stream, FIELDS)
            if new:
                writer.writeheader()
            print(" ".join(f"{name:>12}" for name in FIELDS), flush=True)
            for level in args.levels:
                for k in args.components:
                    for jobs in args.jobs:
                        libraries = ["dgmm"]
                        n = len(np.load(mesh_path(args.workdir, level))["faces"])
                        if 4 * 8 * n * k <= args.sklearn_max_gb * 1e9:
                            libraries.append("sklearn")
                        for library in libraries:
                            row = measure_in_child(library, mesh_path(args.workdir, level), k, jobs, args.iterations)
                            writer.writerow(row)
                            stream.flush()
                            print(" ".join(f"{row[name]:>12}" for name in FIELDS), flush=True)
    with open(table, newline="") as stream:
        plot(list(csv.DictReader(stream)), args.png)
    print(f"results in {table}, plot in {args.png}")


if __name__ == "__main__":
    main()
