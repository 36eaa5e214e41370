"""Job: one timing check, its settings interleaved repeat by repeat (dgmm.experiments.checks.timing)."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from threadpoolctl import threadpool_limits

from dgmm.data import load_mesh, load_points
from dgmm.experiments.checks.interleaved import COLUMNS
from dgmm.experiments.checks.timing import TIMING_CHECKS
from dgmm.model_io import load_model
from dgmm.odometry import read_sequence
from dgmm.runtime.tables import write_csv

LOADERS = {"mesh": load_mesh, "dense": load_points, "gmm": lambda path: load_model(path)[0], "sequence": read_sequence}

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
check = smk.wildcards.check
inputs = {name: LOADERS[name](path) for name, path in smk.input.items()}
with threadpool_limits(smk.threads):
    rows = TIMING_CHECKS[check](**inputs, **smk.params.settings)
write_csv(smk.output.rows, rows, COLUMNS)
print(f"timing {check}: {len(rows)} timed runs", file=sys.stderr)
