"""Streamed EM's block size against its two-thread speed-up, measured interleaved in one process.

On a shared or virtual machine, one- and two-thread times taken minutes apart move by up to 20%, more than the
effect of the block size. Here every repetition runs, in turn, each block size on one and on two threads from
the same start (a one-iteration k-means fit), and each configuration's time per iteration is the median of its
gaps between EM iterations over all repetitions. Meshes: ``benchmarks/em_scale.py``'s subdivided bunnies
(run it, or ``em_scale.py --levels 0 1 2 --components 100 --iterations 2``, first to make them).

Usage: ``python benchmarks/studies/em_block_size.py [--mib 2 8] [--workdir results/em_scale]``
"""
import argparse
import os
import time
from pathlib import Path

import numpy as np

import dgmm.em_blocks
from dgmm import GaussianMixture, Primitives

REPO = Path(__file__).resolve().parents[2]
# (subdivision level, K, repetitions, EM iterations per fit)
CASES = [(0, 1000, 5, 4), (1, 100, 5, 4), (1, 1000, 3, 4), (2, 100, 3, 4), (2, 1000, 2, 3)]


def iteration_gaps(prims, start, n_components, n_jobs, iterations):
    """Seconds between successive EM iterations of a fit from ``start``'s parameters."""
    times = []
    GaussianMixture(n_components, max_iter=iterations, tol=0, n_jobs=n_jobs, weights_init=start.weights_,
                    means_init=start.means_, precisions_init=np.linalg.inv(start.covariances_),
                    callback=lambda iteration, model: times.append(time.perf_counter())).fit(prims)
    return list(np.diff(times))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--mib", type=float, nargs="+", default=[2, 8], help="block sizes to compare, MiB")
    parser.add_argument("--workdir", type=Path, default=REPO / "results" / "em_scale")
    args = parser.parse_args()
    print("| triangles | K | " + " | ".join(f"{m:g} MiB: 1 / 2 threads (s), speed-up" for m in args.mib) + " |")
    print("|---:|---:|" + "---|" * len(args.mib))
    for level, k, repetitions, iterations in CASES:
        with np.load(args.workdir / f"bunny_sub{level}.npz") as mesh:
            prims = Primitives.from_mesh(mesh["vertices"], mesh["faces"])
        start = GaussianMixture(k, max_iter=1, random_state=0).fit(prims)
        gaps = {}
        for _ in range(repetitions):
            for mib in args.mib:
                dgmm.em_blocks.CACHE_BLOCK_BYTES = int(mib * 2**20)
                for jobs in (1, 2):
                    gaps.setdefault((mib, jobs), []).extend(iteration_gaps(prims, start, k, jobs, iterations))
        median = {key: float(np.median(value)) for key, value in gaps.items()}
        cells = [f"{median[m, 1]:.3f} / {median[m, 2]:.3f}, {median[m, 1] / median[m, 2]:.2f}x" for m in args.mib]
        print(f"| {len(prims):,} | {k} | " + " | ".join(cells) + f" |  (load {os.getloadavg()[0]:.2f})", flush=True)


if __name__ == "__main__":
    main()
