"""Job: fit one (model, input, variant, K, init) over every seed; write scores, timings and the recordings."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

import trimesh
from threadpoolctl import threadpool_limits

from dgmm.data import load_mesh, load_points
from dgmm.experiments.sweep import SIZED, build_input, fit_seeds, parse_input
from dgmm.recording import FitRecorder
from dgmm.runtime.tables import write_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
w, p = smk.wildcards, smk.params
key = f"{w.model}/{w.input}/{w.variant}/k{w.k}-{w.init}"
representation = parse_input(w.input)[1]
vertices, faces = (load_points(smk.input.data), None) if representation == "points" else load_mesh(smk.input.data)
prims = build_input(w.input, vertices, faces)
shown = trimesh.Trimesh(vertices, faces, process=False) if representation in SIZED else prims
evaluation = load_points(smk.input.evaluation)
params = dict(model=w.model, input=w.input, variant=w.variant, K=int(w.k), init=w.init, seeds=p.seeds,
              max_iter=p.max_iter, tol=p.tol, reg_covar=p.reg_covar, root_seed=p.seed)

with threadpool_limits(smk.threads), FitRecorder(smk.output.mcap, smk.output.rrd, params=params, data=shown) as rec:
    rows, seconds = fit_seeds(prims, evaluation, n_components=int(w.k), init=w.init, variant=w.variant,
                              n_seeds=p.seeds, root_seed=p.seed, key=key, max_iter=p.max_iter, tol=p.tol,
                              reg_covar=p.reg_covar, recorder=rec)
job = dict(model=w.model, input=w.input, K=int(w.k), init=w.init, variant=w.variant)
write_csv(smk.output.scores, [{**job, **row} for row in rows])
write_csv(smk.output.seconds, [{**job, "seed": row["seed"], "fit_seconds": s} for row, s in zip(rows, seconds)])
print(f"{key}: {len(rows)} seeds, mean eval_ll {sum(r['eval_ll'] for r in rows) / len(rows):.4f}", file=sys.stderr)
