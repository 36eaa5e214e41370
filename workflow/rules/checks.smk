# Checks (dgmm.experiments.checks): small experiments for claims of the paper the sweeps above do not measure, run
# when config has a `checks` section (else the report says those claims are pending). Under results/tables/:
#   convergence.csv        fits run to checks.convergence.max_iter iterations from the Fig 3 sweep's seeds: eval
#                          log-likelihood at 25 and at max_iter, iterations to converge, Fig 7's fuller-model numbers
#   resampling.csv         a mesh against its copy with every triangle split in four (paper section II)
#   optimisers.csv         P2D with CG/BFGS and quaternion/rotation vector on the first Fig 5 trials
#   optimisers_seconds.csv, timing_seconds.csv   CPU times (machine dependent, kept apart from the tables above)
CHECK_DIR = f"{RESULTS}/checks"


rule check_convergence:
    input:
        data=fit_input,
        evaluation=evaluation_set,
    output:
        rows=f"{CHECK_DIR}/convergence/{{model}}/{{input}}/{{variant}}.csv",
    log:
        f"{RESULTS}/logs/checks/convergence/{{model}}/{{input}}/{{variant}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/check_convergence/{{model}}/{{input}}/{{variant}}.tsv"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
        cpus_per_task=1,
    params:
        seed=config["seed"],
        checks=CHECKS.get("convergence"),
        tol=FIT["tol"],
        reg_covar=FIT["reg_covar"],
    script:
        "../scripts/check_convergence.py"


rule convergence_table:
    input:
        rows=convergence_outputs(),
    output:
        rows=f"{RESULTS}/tables/convergence.csv",
    log:
        f"{RESULTS}/logs/tables/convergence.log",
    threads: 1
    script:
        "../scripts/concat_tables.py"


rule check_resampling:
    input:
        mesh=lambda w: f"{DATA_DIR}/{CHECKS['resampling']['model']}/{CHECKS['resampling']['mesh']}.ply",
        evaluation=lambda w: f"{DATA_DIR}/{CHECKS['resampling']['model']}/{CHECKS['resampling']['mesh']}_eval.ply",
    output:
        rows=f"{RESULTS}/tables/resampling.csv",
    log:
        f"{RESULTS}/logs/checks/resampling.log",
    benchmark:
        f"{RESULTS}/benchmarks/check_resampling.tsv"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
        cpus_per_task=1,
    params:
        seed=config["seed"],
        checks=CHECKS.get("resampling"),
        max_iter=FIT["max_iter"],
        tol=FIT["tol"],
        reg_covar=FIT["reg_covar"],
    script:
        "../scripts/check_resampling.py"


rule check_optimisers:
    input:
        mesh=f"{DATA_DIR}/bunny/res4.ply",
        dense=f"{DATA_DIR}/bunny/res4_eval.ply",
        gmm=f"{RESULTS}/registration/bunny/res4/scaled/textbook/mesh-kmeans/gmm.npz",
    output:
        rows=f"{RESULTS}/tables/optimisers.csv",
        seconds=f"{RESULTS}/tables/optimisers_seconds.csv",
    log:
        f"{RESULTS}/logs/checks/optimisers.log",
    benchmark:
        f"{RESULTS}/benchmarks/check_optimisers.tsv"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
        cpus_per_task=1,
    params:
        seed=config["seed"],
        checks=CHECKS.get("optimisers"),
        max_angle_deg=REG["max_angle_deg"],
        max_translation=REG["max_translation"],
    script:
        "../scripts/check_optimisers.py"


rule check_timing:
    input:
        mesh=f"{DATA_DIR}/bunny/res4.ply",
    output:
        seconds=f"{RESULTS}/tables/timing_seconds.csv",
    log:
        f"{RESULTS}/logs/checks/timing.log",
    benchmark:
        f"{RESULTS}/benchmarks/check_timing.tsv"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
        cpus_per_task=1,
    params:
        seed=config["seed"],
        checks=CHECKS.get("timing"),
        components=REG["components"],
        max_iter=FIT["max_iter"],
    script:
        "../scripts/check_timing.py"


rule checks:
    input:
        list(checks_outputs().values()),
