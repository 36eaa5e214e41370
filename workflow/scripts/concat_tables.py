"""Job: concatenate every input list of CSV files into the output of the same name (e.g. errors, seconds)."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from dgmm.runtime.tables import concat_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
for name, path in smk.output.items():
    concat_csv(smk.input[name], path)
