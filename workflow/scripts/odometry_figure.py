"""Job: Fig 6, the top-down view of every method's trajectory against the ground truth."""
import sys
from pathlib import Path

from dgmm.odometry_plot import fig6_from_files, save_png

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
trajectories = dict(zip(smk.params.methods, smk.input.trajectories))
figure = fig6_from_files(Path(smk.input.sequence) / "groundtruth.txt", trajectories, plane=smk.params.plane,
                         sequence=smk.params.sequence)
save_png(figure, smk.output.png)
