"""Job: the report (Table 1, claims, figures) from the sweep's tables into the report folder."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys
from pathlib import Path

from threadpoolctl import threadpool_limits

from dgmm.experiments.report import INPUTS, build_report

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
paths = {key: smk.input[key] for key in INPUTS if key in smk.input.keys()}  # noqa: SIM118 (Namedlist: names via keys())
with threadpool_limits(smk.threads):
    build_report(paths, smk.params.figures, Path(smk.output.html).parent, seed=smk.params.seed,
                 table1_trials=smk.params.table1_trials)
print(f"report: {len(smk.params.figures)} figures from {sorted(paths)}", file=sys.stderr)
