# dgmm benchmark service: the paper's experiments as one Snakemake DAG.
# `snakemake --cores 2` runs the full sweep and its report; see README.md.
from snakemake.utils import min_version

min_version("8.0")


configfile: "config.yaml"


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"
include: "workflow/rules/data.smk"
include: "workflow/rules/fit.smk"
include: "workflow/rules/likelihood.smk"
include: "workflow/rules/register.smk"
include: "workflow/rules/odometry.smk"
include: "workflow/rules/report.smk"


rule all:
    input:
        get_final_output(),
