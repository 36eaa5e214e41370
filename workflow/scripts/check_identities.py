"""Job: the identities the paper states, each side computed independently (dgmm.experiments.checks.identities)."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from threadpoolctl import threadpool_limits

from dgmm.data import load_mesh
from dgmm.experiments.checks.identities import COLUMNS, identity_rows
from dgmm.experiments.sweep import job_seed
from dgmm.mixture import GaussianMixture
from dgmm.primitives import Primitives
from dgmm.runtime.tables import write_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
p = smk.params
vertices, faces = load_mesh(smk.input.mesh)
seed = job_seed(p.seed, "checks/identities", 0)
with threadpool_limits(smk.threads):
    mixture = GaussianMixture(p.checks["mixture_components"], max_iter=p.max_iter, random_state=seed).fit(
        Primitives.from_mesh(vertices, faces))
    rows = identity_rows(vertices, faces, mixture, random_triangles=p.checks["random_triangles"],
                         n_components=p.checks["components"], n_iter=p.max_iter, reg_covar=p.reg_covar,
                         samples=p.checks["samples"], seed=seed)
write_csv(smk.output.rows, rows, COLUMNS)
for row in rows:
    print(f"{row['identity']}: {row['cases']} cases, largest difference {row['max_error']:.2e} of {row['scale']:.2e}",
          file=sys.stderr)
