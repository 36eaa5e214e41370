# Likelihood tables (Figs 2, 3, 4, Table 1) under results/tables/:
#   likelihood.csv    every fit's seeds: model, input, K, init, variant, seed, eval_ll, bound, n_iter, max_iter (the
#                     job's iteration cap: fit.max_iter, or its experiment's own, e.g. Fig 4 at 100)
#   fit_seconds.csv   the same keys with each fit's wall time, then max_iter
#   fig2.csv          Fig 2: likelihood expressions of one K=50 fit to dense samples of bunny res4
FIG2 = config["fig2"]


rule likelihood_table:
    input:
        likelihood=fit_outputs("scores.csv"),
        seconds=fit_outputs("seconds.csv"),
    output:
        likelihood=f"{RESULTS}/tables/likelihood.csv",
        seconds=f"{RESULTS}/tables/fit_seconds.csv",
    log:
        f"{RESULTS}/logs/tables/likelihood.log",
    benchmark:
        f"{RESULTS}/benchmarks/likelihood_table.tsv"
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
        cpus_per_task=1,
    params:
        max_iter=[job[-1] for job in fit_jobs()],  # of each input file, in fit_outputs' order
    script:
        "../scripts/likelihood_table.py"


rule fig2:
    input:
        mesh=f"{DATA_DIR}/{FIG2['model']}/{FIG2['mesh']}.ply",
    output:
        table=report(f"{RESULTS}/tables/fig2.csv", caption="../report/fig2_table.rst", category="Tables"),
        mcap=f"{RESULTS}/fig2/fit.mcap",
        rrd=f"{RESULTS}/fig2/fit.rrd",
    log:
        f"{RESULTS}/logs/fig2.log",
    benchmark:
        f"{RESULTS}/benchmarks/fig2.tsv"
    priority: PRIORITY["fig2"]
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
        cpus_per_task=1,
    params:
        seed=config["seed"],
        fig2=FIG2,
        max_iter=FIT["max_iter"],
        tol=FIT["tol"],
        reg_covar=FIT["reg_covar"],
    script:
        "../scripts/fig2.py"


rule fits:
    input:
        rules.likelihood_table.output,
        rules.fig2.output.table,
