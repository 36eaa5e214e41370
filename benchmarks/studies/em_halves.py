"""Which half of the authors' EM moves the likelihoods: its E-step's α/α_min scaling or its unweighted M-step.

The authors' EM (leonidk/direct_gmm) differs from textbook EM in two places at once; the sweep runs both at once.
This fits the sweep's Fig 3 and Fig 4 mesh cells (bunny res4 exact and approx; quadric and clustering 1000, exact)
with each half alone (``dgmm.variants``: ``authors-estep``, ``authors-mstep``), from the sweep's seeds and job keys,
scored as the sweep scores them, beside the sweep's own textbook and authors' cells read from ``--likelihood``
(the same seeds and keys, so the same numbers). Prints a markdown row per (input, start, K): the mean evaluation
log-likelihood of the four variants over the seeds, and which half lands nearer the authors' EM.

Usage: ``python benchmarks/studies/em_halves.py --likelihood results/tables/likelihood.csv --data results/data
[--inputs res4-exact ...] [--seeds 10]``.
"""
import argparse
import os
from collections import defaultdict

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from dgmm.data import load_mesh, load_points  # noqa: E402
from dgmm.experiments.sweep import build_input, fit_seeds, parse_input  # noqa: E402
from dgmm.runtime.tables import read_csv  # noqa: E402

HALVES = ("authors-estep", "authors-mstep")
INPUTS = {"res4-exact": "res4_eval", "res4-approx": "res4_eval", "quadric1000-exact": "full_eval",
          "clustering1000-exact": "full_eval"}
"""Input -> the evaluation set the sweep scores it on (Fig 3: res4's; Fig 4: the full bunny's)."""
KS = (6, 12, 25, 50, 100, 200, 400)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--likelihood", required=True, help="the sweep's likelihood.csv (textbook and authors' cells)")
    parser.add_argument("--data", required=True, help="the sweep's results/data folder")
    parser.add_argument("--inputs", nargs="+", default=list(INPUTS))
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--root-seed", type=int, default=0)
    args = parser.parse_args()
    sweep = defaultdict(list)
    for row in read_csv(args.likelihood):
        if row["model"] == "bunny" and int(row.get("max_iter") or 25) == 25:
            sweep[row["input"], row["variant"], row["init"], int(row["K"])].append(float(row["eval_ll"]))
    print("| input | start | K | textbook | E-step half | M-step half | authors' EM | nearer the authors' |")
    print("|---|---|---|---|---|---|---|---|")
    for name in args.inputs:
        source = parse_input(name)[0]
        vertices, faces = load_mesh(f"{args.data}/bunny/{source}.ply")
        prims = build_input(name, vertices, faces)
        evaluation = load_points(f"{args.data}/bunny/{INPUTS[name]}.ply")
        for init in ("kmeans", "random"):
            for k in KS:
                means = {variant: np.mean(sweep[name, variant, init, k]) for variant in ("textbook", "authors")}
                for variant in HALVES:
                    with threadpool_limits(1):
                        rows, _ = fit_seeds(prims, evaluation, n_components=k, init=init, variant=variant,
                                            n_seeds=args.seeds, root_seed=args.root_seed,
                                            key=f"bunny/{name}/{variant}/k{k}-{init}", max_iter=25, tol=1e-12,
                                            reg_covar=1e-6)
                    means[variant] = np.mean([row["eval_ll"] for row in rows])
                nearer = min(HALVES, key=lambda half: abs(means[half] - means["authors"]))
                print(f"| {name} | {init} | {k} | {means['textbook']:.3f} | {means['authors-estep']:.3f} | "
                      f"{means['authors-mstep']:.3f} | {means['authors']:.3f} | "
                      f"{'E-step' if nearer == 'authors-estep' else 'M-step'} |", flush=True)


if __name__ == "__main__":
    main()
