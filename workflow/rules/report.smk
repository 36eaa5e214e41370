# Report (issue 6): Table 1, the paper's claims with verdicts and the figures, under report.dir (default reports/):
#   report.html (self-contained), report.md, table1.csv, table1.md, figures/{name}.png
# Inputs follow the configured stages: registration and odometry only when config has their sections; figures whose
# inputs are not configured are left out and their sections say they are pending.
from dgmm.report import figure_names

REPORT_DIR = config.get("report", {}).get("dir", "reports")
PICTURE_BUDGET = 1000  # Fig 7 shows the paper's 1000-primitive decimations and samples


def report_inputs():
    """Named inputs of the report: the tables of the configured stages and the bunny files the pictures use."""
    inputs = {"likelihood": rules.likelihood_table.output.likelihood, "fig2": rules.fig2.output.table}
    if "registration" in config:
        inputs["registration"] = rules.registration_table.output.errors
    if "odometry" in config:
        inputs.update(odometry=f"{RESULTS}/tables/odometry.csv", fig6=f"{RESULTS}/odometry/fig6.png")
    if "bunny" in DATA["models"]:
        inputs.update(res4=f"{DATA_DIR}/bunny/res4.ply", full=f"{DATA_DIR}/bunny/full.ply",
                      dense=f"{DATA_DIR}/bunny/full_eval.ply")
        if PICTURE_BUDGET in DATA["budgets"]:
            inputs.update({method: f"{DATA_DIR}/bunny/{method}{PICTURE_BUDGET}.ply" for method in DATA["methods"]})
    return inputs


def report_figures():
    """Names of the figures the configured stages allow."""
    configured = {name for e in FIT["experiments"].values() if "bunny" in e["models"] for name in e["inputs"]}
    if "registration" in config:
        configured |= {f"{model}/{mesh}" for model, mesh in REG_EXPERIMENTS}
    return figure_names(report_inputs(), configured)


rule report:
    input:
        **report_inputs(),
    output:
        html=f"{REPORT_DIR}/report.html",
        markdown=f"{REPORT_DIR}/report.md",
        table1=report(f"{REPORT_DIR}/table1.csv", caption="../report/table1.rst", category="Table 1"),
        table1_md=f"{REPORT_DIR}/table1.md",
        figures=[report(f"{REPORT_DIR}/figures/{name}.png", caption=f"../report/{name}.rst", category="Figures")
                 for name in report_figures()],
    params:
        seed=config["seed"],
        figures=report_figures(),
    log:
        f"{RESULTS}/logs/report.log",
    threads: 1
    resources:
        mem_mb=1000,  # measured: 380 MB peak, 12 s on the full bunny
        runtime=10,
        cpus_per_task=1,
    script:
        "../scripts/report.py"
