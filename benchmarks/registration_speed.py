"""Registration speed: P2D and D2D with the paper's BFGS against the Gauss-Newton solver, same trials, one thread.

A scikit-learn GMM (K=100, k-means, 100 iterations, tol 1e-5; the registration GMMs of paper §V) is fitted to the
vertices of bunny res4. P2D: each trial draws a fresh surface sample of as many points as the mesh has vertices,
moves it by a random rigid trial (±15°, ±0.05 per axis) and registers it back with every solver (BFGS with the
analytic gradient on the numba kernels and on numpy's cost, BFGS with forward differences as in the paper if
``--numeric``, Gauss-Newton), interleaved so that load on the shared machine hits them alike. D2D (odometry's inner
loop): a second K=100 GMM fitted to such a sample, moved by a small trial (±3°, ±0.005 per axis, frame-to-frame
motion), registered onto the first.

Times are medians of wall and process CPU time per registration; the load average is printed beside them.

Run: ``python benchmarks/registration_speed.py [--trials 20] [--components 100] [--seed 0] [--numeric]``
"""
import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402
from types import SimpleNamespace  # noqa: E402

import numpy as np  # noqa: E402
import trimesh  # noqa: E402
from sklearn.mixture import GaussianMixture  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from dgmm import registration as reg  # noqa: E402

BUNNY = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "stanford" / "bunny_res4.ply"


def _moved_mixture(mixture, trial):
    """The mixture of a GMM's variable moved by ``trial``."""
    c, r, t = trial.centre, trial.rotation, trial.translation
    covariances = r @ mixture.covariances_ @ r.T
    return SimpleNamespace(weights_=mixture.weights_, means_=(mixture.means_ - c) @ r.T + c + t,
                           covariances_=covariances,
                           precisions_cholesky_=np.linalg.inv(np.linalg.cholesky(covariances)).transpose(0, 2, 1))


def _timed(register):
    wall, cpu = time.perf_counter(), time.process_time()
    result = register()
    return result, time.perf_counter() - wall, time.process_time() - cpu


def _report(title, rows):
    print(f"\n{title}")
    print(f"{'solver':>22} {'wall ms':>8} {'CPU ms':>7} {'iters':>6} {'rot° mean':>10} {'trans% mean':>12}")
    for name, values in rows.items():
        a = np.array(values)
        print(f"{name:>22} {1e3 * np.median(a[:, 0]):8.1f} {1e3 * np.median(a[:, 1]):7.1f} {a[:, 2].mean():6.1f} "
              f"{a[:, 3].mean():10.4f} {a[:, 4].mean():12.4f}")
    cpu = {name: np.median(np.array(values)[:, 1]) for name, values in rows.items()}
    base = next(iter(cpu))
    print("CPU time ratios to the first row: " + ", ".join(f"{name} {cpu[name] / cpu[base]:.2f}" for name in cpu))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--components", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--numeric", action="store_true", help="also BFGS with forward differences (slow)")
    args = parser.parse_args()
    print(f"load average at start: {os.getloadavg()}")

    mesh = trimesh.load(BUNNY, process=False)
    vertices = np.asarray(mesh.vertices)
    diagonal = float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))
    mixture = GaussianMixture(args.components, init_params="kmeans", tol=1e-5, max_iter=100,
                              random_state=args.seed).fit(vertices)
    rng = np.random.default_rng(args.seed)
    p2d = {"BFGS analytic (paper)": dict(solver="bfgs"), "BFGS analytic, numpy": dict(solver="bfgs", compiled=False)}
    if args.numeric:
        p2d["BFGS numeric"] = dict(solver="bfgs", gradient="numeric")
    p2d["Gauss-Newton"] = dict(solver="gauss-newton")
    d2d = {"BFGS analytic (paper)": "bfgs", "Gauss-Newton": "gauss-newton"}
    p2d_rows, d2d_rows = {name: [] for name in p2d}, {name: [] for name in d2d}
    with threadpool_limits(1):
        for _ in range(args.trials):
            sample = np.asarray(trimesh.sample.sample_surface(mesh, len(vertices), seed=rng)[0])
            trial = reg.random_trials(1, rng, diagonal, sample.mean(axis=0))[0]
            for name, options in p2d.items():
                result, wall, cpu = _timed(lambda: reg.register_p2d(trial.apply(sample), mixture, **options))
                p2d_rows[name].append((wall, cpu, result.iterations, *reg.registration_errors(result, trial, diagonal)))
            other = GaussianMixture(args.components, init_params="kmeans", tol=1e-5, max_iter=100,
                                    random_state=args.seed).fit(sample)
            small = reg.random_trials(1, rng, diagonal, sample.mean(axis=0), max_angle_deg=3.0,
                                      max_translation=0.005)[0]
            moving = _moved_mixture(other, small)
            for name, solver in d2d.items():
                result, wall, cpu = _timed(lambda: reg.register_d2d(mixture, moving, solver=solver))
                d2d_rows[name].append((wall, cpu, result.iterations, *reg.registration_errors(result, small, diagonal)))

    print(f"\nbunny res4, sklearn GMM K={args.components} on {len(vertices)} vertices, {args.trials} trials, "
          f"{len(vertices)} source points")
    _report("P2D (±15°, ±0.05 per axis)", p2d_rows)
    _report(f"D2D, two K={args.components} mixtures (±3°, ±0.005 per axis)", d2d_rows)
    print(f"load average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
