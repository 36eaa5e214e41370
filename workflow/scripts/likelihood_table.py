"""Job: gather every fit job's per-seed rows into the tidy likelihood and timing tables."""
import sys

from dgmm.tables import concat_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
concat_csv(smk.input.scores, smk.output.likelihood)
concat_csv(smk.input.seconds, smk.output.seconds)
