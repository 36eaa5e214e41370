"""Job: same-run CPU times of the area x centroid approximation and of D2D with and without the determinant
(dgmm.experiments.checks.timing)."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from threadpoolctl import threadpool_limits

from dgmm.data import load_mesh
from dgmm.experiments.checks.timing import COLUMNS, d2d_times, em_times
from dgmm.experiments.sweep import job_seed
from dgmm.mixture import GaussianMixture
from dgmm.primitives import Primitives
from dgmm.runtime.tables import write_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
p = smk.params
vertices, faces = load_mesh(smk.input.mesh)
mesh = Primitives.from_mesh(vertices, faces)
seed = job_seed(p.seed, "checks/timing", 0)
with threadpool_limits(smk.threads):
    rows = em_times(mesh, n_components=p.components, max_iter=p.max_iter, repeats=p.checks["em_repeats"], seed=seed)
    fixed = GaussianMixture(p.components, random_state=seed).fit(mesh)
    moving = GaussianMixture(p.components, random_state=seed).fit(vertices)
    rows += d2d_times(fixed, moving, motions=p.checks["d2d_motions"], seed=seed)
write_csv(smk.output.seconds, rows, COLUMNS)
print(f"timing: {len(rows)} timed runs", file=sys.stderr)
