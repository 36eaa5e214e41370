"""Job: Fig 6, one top-down panel per sequence: every run's trajectory against the ground truth."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys
from pathlib import Path

from dgmm.odometry.figure import fig6_from_files, save_png

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
runs, paths = smk.params.runs, iter(smk.input.trajectories)  # sequence-major, as odometry_outputs lists them
panels = {name: (Path(folder) / "groundtruth.txt", {run: next(paths) for run in runs})
          for name, folder in zip(smk.params.sequences, smk.input.sequences)}
save_png(fig6_from_files(panels, plane=smk.params.plane), smk.output.png)
