# dgmm benchmark service: the paper's experiments as one Snakemake DAG.
# `snakemake --cores 2` runs the full sweep and its report; see README.md and docs/user_guide/workflow.md.
from pathlib import Path

from snakemake.utils import min_version

from dgmm.runtime.job_server import JobServer, script_imports
from dgmm.runtime.snakemake_sigterm import install as install_sigterm_handler

min_version("9.27.1")
install_sigterm_handler()  # `kill` stops the sweep gracefully at any moment (dgmm.runtime.snakemake_sigterm)


configfile: "config.yaml"


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"
include: "workflow/rules/data.smk"
include: "workflow/rules/fit.smk"
include: "workflow/rules/likelihood.smk"
include: "workflow/rules/register.smk"
include: "workflow/rules/odometry.smk"
include: "workflow/rules/checks.smk"
include: "workflow/rules/report.smk"


# Job scripts hand over to one server per run that has imported their libraries (dgmm.runtime.job_server): a job
# starts in milliseconds instead of seconds, and the P2D kernels' compiled code is loaded once, not by each of the
# registration jobs (about 0.35 s each). threadpoolctl's first scan of the loaded libraries is made there too: a
# job's `threadpool_limits` then takes 4.5 ms instead of 15. On a cluster, run by hand, and with `job_server: false`,
# a script runs in its own process.
JOB_SCRIPTS = sorted(Path(workflow.basedir, "workflow/scripts").glob("*.py"))
JOB_SERVER = JobServer(
    [
        "snakemake.script",
        *script_imports(JOB_SCRIPTS),
        "dgmm.registration.p2d:load_p2d_kernels",
        "threadpoolctl:threadpool_info",
    ]
)


onstart:
    if workflow.local_exec and config["job_server"]:
        JOB_SERVER.start()


onsuccess:
    JOB_SERVER.stop()


onerror:
    JOB_SERVER.stop()


rule all:
    input:
        get_final_output(),
