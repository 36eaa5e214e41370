"""Job: gather the odometry jobs' ATE and RPE rows into one table (a configured sequence whose folder is missing is
a row with its path and no numbers: pending), and summarise their per-frame timings in another."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from dgmm.odometry import seconds_summary
from dgmm.runtime.tables import read_csv, write_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
rows = [row for path in smk.input.ate for row in read_csv(path)]
columns = list(rows[0])
pending = [{**dict.fromkeys(columns, ""), "sequence": name, "missing_folder": folder}
           for name, folder in smk.params.missing.items()]
write_csv(smk.output.ate, [{**row, "missing_folder": ""} for row in rows] + pending, columns=[*columns, "missing_folder"])
summaries = []
for path in smk.input.seconds:
    frames = read_csv(path)
    job = {key: frames[0].get(key, "") for key in ("sequence", "method", "variant", "protocol")}
    summaries.append({**job, **seconds_summary(frames)})
write_csv(smk.output.seconds, summaries)
