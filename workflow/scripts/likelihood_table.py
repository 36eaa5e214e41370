"""Job: the fit jobs' scores.csv and seconds.csv, each row with its job's iteration cap appended (``max_iter``), into
likelihood.csv and fit_seconds.csv."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from dgmm.runtime.tables import read_csv, write_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
for name, path in smk.output.items():
    write_csv(path, [{**row, "max_iter": max_iter} for source, max_iter in zip(smk.input[name], smk.params.max_iter)
                     for row in read_csv(source)])
