# The authors' stored results (their notebooks' printed outputs, found in data.mirrors like the meshes): the values
# the report sets beside ours (dgmm.experiments.authors_data).
rule authors_data:
    output:
        table=f"{RESULTS}/tables/authors.csv",
    log:
        f"{RESULTS}/logs/authors_data.log",
    threads: 1
    resources:
        mem_mb=200,  # measured: under a second, a few MB
        runtime=5,
        cpus_per_task=1,
    params:
        mirrors=[data_dir(path) for path in DATA["mirrors"]],
        cache=data_dir(DATA["cache"]),
    script:
        "../scripts/authors_data.py"


# Report (issue 6): Table 1, the paper's claims with verdicts and the figures, under report.dir (default reports/):
#   report.md, claims.md (the evidence ledger), report.html (both, self-contained), table1.csv, table1.md,
#   authors.csv (the authors' stored values, committed beside the report), figures/{name}.png; only report.md's timing block changes between runs of one commit
# Inputs: every stage's tables, the configured checks' tables; figures whose inputs are not configured are left out
# and their sections say they are pending.
rule report:
    input:
        **report_inputs(),
    output:
        html=f"{REPORT_DIR}/report.html",
        markdown=f"{REPORT_DIR}/report.md",
        claims=f"{REPORT_DIR}/claims.md",
        table1=report(f"{REPORT_DIR}/table1.csv", caption="../report/table1.rst", category="Table 1"),
        table1_md=f"{REPORT_DIR}/table1.md",
        authors=f"{REPORT_DIR}/authors.csv",
        figures=[
            report(f"{REPORT_DIR}/figures/{name}.png", caption=f"../report/{name}.rst", category="Figures")
            for name in report_figures()
        ],
    log:
        f"{RESULTS}/logs/report.log",
    benchmark:
        f"{RESULTS}/benchmarks/report.tsv"
    threads: 1
    resources:
        mem_mb=1000,  # measured: 380 MB peak, 12 s on the full bunny
        runtime=10,
        cpus_per_task=1,
    params:
        seed=config["seed"],
        figures=report_figures(),
        table1_trials=table1_trials(),
    script:
        "../scripts/report.py"
