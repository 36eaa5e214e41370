"""Job: P2D with CG and BFGS, quaternion and rotation vector, on the first Fig 6 trials
(dgmm.experiments.checks.optimisers)."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from threadpoolctl import threadpool_limits

from dgmm.data import load_mesh, load_points
from dgmm.experiments.checks.optimisers import COLUMNS, optimiser_rows
from dgmm.experiments.trials import bounding_diagonal, make_trials
from dgmm.model_io import load_model
from dgmm.runtime.tables import write_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
p = smk.params
vertices, _ = load_mesh(smk.input.mesh)
diagonal = bounding_diagonal(vertices)
setups = make_trials(load_points(smk.input.dense), len(vertices), range(p.checks["trials"]), root_seed=p.seed,
                     key="registration/bunny/res4", diagonal=diagonal, max_angle_deg=p.max_angle_deg,
                     max_translation=p.max_translation)  # Fig 6's first trials (registration_chunk.py's key)
with threadpool_limits(smk.threads):
    rows, seconds = optimiser_rows(setups, load_model(smk.input.gmm)[0], diagonal)
write_csv(smk.output.rows, rows, COLUMNS)
write_csv(smk.output.seconds, seconds)
print(f"optimisers: {len(rows)} registrations", file=sys.stderr)
