# Config validation and helpers shared by every rule file.
# Every rule declares resources: (mem_mb, runtime in minutes, cpus_per_task) for cluster schedulers: measured peaks
# (benchmarks/job_resources.py, README "Running on a Slurm cluster") with about 2x memory and 15x time headroom.
from snakemake.utils import validate


validate(config, schema="../schemas/config.schema.yaml")

RESULTS = config.get("results", "results")


def get_final_output():
    """Every target of `rule all`: the outputs of each stage."""
    return [*rules.data.input, *rules.fits.input, *rules.registration.input, *rules.odometry.input,
            *rules.report.output]
