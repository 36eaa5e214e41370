"""Job: Fig 7, one top-down panel per sequence: every run's trajectory against the ground truth (a recording without
ground truth: the trajectories alone)."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from dgmm.odometry.figure import fig7_from_files, save_png

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
runs, paths = smk.params.runs, iter(smk.input.trajectories)  # sequence-major, as odometry_outputs lists them
panels = {name: (truth, {run: next(paths) for run in runs})  # truth None: a recording without ground truth
          for name, truth in zip(smk.params.sequences, smk.params.groundtruth)}
save_png(fig7_from_files(panels, plane=smk.params.plane), smk.output.png)
