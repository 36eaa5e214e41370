"""Job: gather the odometry jobs' ATE rows into one table and summarise their per-frame timings in another."""
import sys

from dgmm.odometry import seconds_summary
from dgmm.tables import concat_csv, read_csv, write_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
concat_csv(smk.input.ate, smk.output.ate)
rows = []
for path in smk.input.seconds:
    frames = read_csv(path)
    rows.append({"sequence": frames[0]["sequence"], "method": frames[0]["method"], **seconds_summary(frames)})
write_csv(smk.output.seconds, rows)
