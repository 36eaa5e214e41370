"""Job: a mesh against its copy with every triangle split in four (dgmm.experiments.checks.resampling)."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from threadpoolctl import threadpool_limits

from dgmm.data import load_mesh, load_points
from dgmm.experiments.checks.resampling import COLUMNS, resampling_rows
from dgmm.runtime.tables import write_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
p = smk.params
vertices, faces = load_mesh(smk.input.mesh)
with threadpool_limits(smk.threads):
    rows = resampling_rows(vertices, faces, load_points(smk.input.evaluation), variants=["textbook", "authors"],
                           seeds=p.checks["seeds"], root_seed=p.seed, n_components=p.checks["components"],
                           max_iter=p.max_iter, tol=p.tol, reg_covar=p.reg_covar,
                           key=f"checks/resampling/{p.checks['model']}/{p.checks['mesh']}")
write_csv(smk.output.rows, rows, COLUMNS)
print(f"resampling: {len(rows)} fits of each mesh", file=sys.stderr)
