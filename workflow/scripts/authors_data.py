"""Job: the authors' stored results, read from their notebooks (dgmm.experiments.authors_data), as one table."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from dgmm.experiments.authors_data import COLUMNS, extract
from dgmm.runtime.tables import write_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
rows = extract(smk.params.mirrors, smk.params.cache)
write_csv(smk.output.table, rows, COLUMNS)
print(f"{len(rows)} stored values", file=sys.stderr)
