"""CPD speed: dgmm's rigid CPD (dgmm.registration.cpd) against pycpd's RigidRegistration, same trials, one thread.

The paper's Fig 6 problem: bunny res4, trials drawn as the workflow draws them (dgmm.experiments.trials.make_trials:
453 source and 453 target points from a dense surface sample, ±15° per axis, ±0.05 per axis), 150 iterations, tol 1e-9.
Each trial is registered by both, interleaved so that load on the shared machine hits them alike; pycpd's rigid
part is read as the workflow reads it (Kabsch of the source to pycpd's moved source). Prints the median wall and
process CPU time per registration, the CPU time ratio, the iterations, and the largest difference between the
two poses (rotation matrix entries, translation in % of the bounding-box diagonal).

Run: ``python benchmarks/cpd_speed.py [--trials 20] [--seed 0]``
"""
import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import trimesh  # noqa: E402
from pycpd import RigidRegistration  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from dgmm.experiments.trials import bounding_diagonal, make_trials  # noqa: E402
from dgmm.registration import kabsch, register_cpd  # noqa: E402

BUNNY = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "stanford" / "bunny_res4.ply"


def pycpd_rigid(source, target, max_iter=150, tol=1e-9):
    """pycpd's rigid CPD as the workflow ran it before dgmm.registration.cpd: (rotation, translation, iterations)."""
    cpd = RigidRegistration(X=target, Y=source, max_iterations=max_iter, tolerance=tol)
    moved, _ = cpd.register(None)
    return (*kabsch(source, moved), cpd.iteration)


def _timed(function):
    wall, cpu = time.perf_counter(), time.process_time()
    result = function()
    return result, time.perf_counter() - wall, time.process_time() - cpu


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    print(f"load average at start: {os.getloadavg()}")
    mesh = trimesh.load(BUNNY, process=False)
    vertices = np.asarray(mesh.vertices)
    diagonal = bounding_diagonal(vertices)
    dense = np.asarray(trimesh.sample.sample_surface(mesh, 50_000, seed=args.seed)[0])
    setups = make_trials(dense, len(vertices), range(args.trials), root_seed=args.seed, key="cpd_speed",
                         diagonal=diagonal)
    rows = {"pycpd": [], "dgmm": []}
    worst_rotation = worst_translation = 0.0
    identical = 0
    with threadpool_limits(1):
        for setup in setups:
            (rotation, translation, iterations), wall, cpu = _timed(lambda: pycpd_rigid(setup.moved, setup.target))
            rows["pycpd"].append((wall, cpu, iterations))
            ours, wall, cpu = _timed(lambda: register_cpd(setup.moved, setup.target))
            rows["dgmm"].append((wall, cpu, ours.iterations))
            worst_rotation = max(worst_rotation, np.abs(ours.rotation - rotation).max())
            worst_translation = max(worst_translation, 100 * np.abs(ours.translation - translation).max() / diagonal)
            identical += bool(np.array_equal(ours.rotation, rotation) and np.array_equal(ours.translation, translation)
                              and ours.iterations == iterations)

    print(f"\nbunny res4, {args.trials} Fig 6 trials, {len(vertices)} x {len(vertices)} points, 150 iterations, "
          "tol 1e-9, 1 thread")
    print(f"{'CPD':>8} {'wall ms':>8} {'CPU ms':>7} {'iters mean':>11}")
    for name, values in rows.items():
        a = np.array(values)
        print(f"{name:>8} {1e3 * np.median(a[:, 0]):8.1f} {1e3 * np.median(a[:, 1]):7.1f} {a[:, 2].mean():11.1f}")
    cpu = {name: np.median(np.array(values)[:, 1]) for name, values in rows.items()}
    print(f"CPU time ratio pycpd/dgmm: {cpu['pycpd'] / cpu['dgmm']:.1f}")
    print(f"poses: {identical} of {args.trials} bit-identical (rotation, translation, iterations); largest "
          f"difference {worst_rotation:.1e} in a rotation entry, {worst_translation:.1e} % of the diagonal")
    print(f"load average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
