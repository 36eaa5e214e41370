"""Job: one input's fits run to 100 iterations from the fitting sweep's seeds (dgmm.experiments.checks.convergence)."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from threadpoolctl import threadpool_limits

from dgmm.data import load_mesh, load_points
from dgmm.experiments.checks.convergence import COLUMNS, convergence_rows
from dgmm.experiments.sweep import build_input, parse_input
from dgmm.runtime.tables import write_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
w, p = smk.wildcards, smk.params
points = parse_input(w.input)[1] == "points"
vertices, faces = (load_points(smk.input.data), None) if points else load_mesh(smk.input.data)
with threadpool_limits(smk.threads):
    rows = convergence_rows(build_input(w.input, vertices, faces), load_points(smk.input.evaluation), model=w.model,
                            input_name=w.input, variant=w.variant, components=p.checks["components"],
                            inits=p.checks["inits"], seeds=p.checks["seeds"], root_seed=p.seed,
                            max_iter=p.checks["max_iter"], tol=p.tol, reg_covar=p.reg_covar)
write_csv(smk.output.rows, rows, COLUMNS)
print(f"{w.model}/{w.input}/{w.variant}: {len(rows)} fits", file=sys.stderr)
