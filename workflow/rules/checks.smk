# Checks (dgmm.experiments.checks): small experiments for claims of the paper the sweeps above do not measure, run
# when config has a `checks` section (else the report says those claims are pending). Under results/tables/:
#   convergence.csv        fits run to checks.convergence.max_iter iterations from the Fig 3 sweep's seeds: eval
#                          log-likelihood at 25 and at max_iter, iterations to converge, Fig 5's fuller-model numbers
#   resampling.csv         a mesh against its copy with every triangle split in four (paper section II)
#   optimisers.csv         P2D with CG/BFGS and quaternion/rotation vector on the first Fig 6 trials
#   identities.csv         the identities the paper states (CGAL's triangle moment, the exact and approximate mean
#                          updates, hierarchical GMM updates, EM on points as scikit-learn's), each side independent
#   optimisers_seconds.csv, timing_seconds.csv   CPU times (machine dependent, kept apart from the tables above);
#                          timing_seconds.csv: one job per checks.timing entry, its settings interleaved repeat by
#                          repeat (results/checks/timing/{check}.csv), concatenated
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
        checks=lambda w: CHECKS["convergence"],
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
    resources:
        mem_mb=500,
        runtime=5,
        cpus_per_task=1,
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
        checks=lambda w: CHECKS["resampling"],
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
        checks=lambda w: CHECKS["optimisers"],
        max_angle_deg=REG["max_angle_deg"],
        max_translation=REG["max_translation"],
    script:
        "../scripts/check_optimisers.py"


rule check_identities:
    input:
        mesh=f"{DATA_DIR}/bunny/res4.ply",
    output:
        rows=f"{RESULTS}/tables/identities.csv",
    log:
        f"{RESULTS}/logs/checks/identities.log",
    benchmark:
        f"{RESULTS}/benchmarks/check_identities.tsv"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
        cpus_per_task=1,
    params:
        seed=config["seed"],
        checks=lambda w: CHECKS["identities"],
        max_iter=FIT["max_iter"],
        reg_covar=FIT["reg_covar"],
    script:
        "../scripts/check_identities.py"


# Timing checks (dgmm.experiments.checks.timing): the inputs and settings of every checks.timing entry, the sweep's
# files and settings so that every setting runs as the sweep runs it, with the entry's own (repeats, a budget). A
# check on a sequence names one of odometry.sequences (its folder name, or synthetic) and runs when the odometry
# has it, else the report says it is pending; the camera as odometry_run_params gives it.
TIMING = CHECKS["timing"] if "timing" in CHECKS else {}  # a section absent runs no timing check
RES4_MESH = {"mesh": f"{DATA_DIR}/bunny/res4.ply"}
FULL_MESH = {"mesh": f"{DATA_DIR}/bunny/full.ply"}
TIMING_ODOMETRY = dict(
    root_seed=config["seed"],
    n_components=ODO["components"],
    schedule=ODO["schedule"],
    warm_iter=ODO["warm_iter"],
    pixel_size=ODO["pixel_size"],
    icp_points=ODO["icp_points"],
)
TIMING_SWEEP = {
    "approximation": (
        RES4_MESH,
        dict(root_seed=config["seed"], n_components=REG["components"], max_iter=FIT["max_iter"]),
    ),
    "decimation": (FULL_MESH, {}),
    "sampling": (FULL_MESH, {}),
    "d2d_determinant": (RES4_MESH, dict(root_seed=config["seed"], n_components=REG["components"])),
    "cpd_vs_p2d": (
        dict(
            RES4_MESH,
            dense=f"{DATA_DIR}/bunny/res4_eval.ply",
            gmm=f"{RESULTS}/registration/bunny/res4/scaled/textbook/mesh-kmeans/gmm.npz",
        ),
        dict(
            root_seed=config["seed"],
            key="registration/bunny/res4",
            max_angle_deg=REG["max_angle_deg"],
            max_translation=REG["max_translation"],
            cpd=REG["cpd"],
            gradient=REG["gradient"],
        ),
    ),
    **{
        check: (
            {"sequence": ODO_SEQUENCES[name]["path"]},
            dict(
                TIMING_ODOMETRY,
                name=name,
                intrinsics=ODO_SEQUENCES[name]["intrinsics"] or sequence_intrinsics(name),
            ),
        )
        for check, name in ((check, options["sequence"]) for check, options in TIMING.items() if "sequence" in options)
        if name in ODO_SEQUENCES and "depth_topic" not in ODO_SEQUENCES[name]  # TUM folders (read_sequence)
    },
}
TIMING_SETUPS = {
    check: (TIMING_SWEEP[check][0], {**TIMING_SWEEP[check][1], **{k: v for k, v in options.items() if k != "sequence"}})
    for check, options in TIMING.items()
    if check in TIMING_SWEEP
}


rule check_timing:
    input:
        unpack(lambda w: TIMING_SETUPS[w.check][0]),
    output:
        rows=f"{CHECK_DIR}/timing/{{check}}.csv",
    log:
        f"{RESULTS}/logs/checks/timing/{{check}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/check_timing/{{check}}.tsv"
    wildcard_constraints:
        check="|".join(TIMING_SETUPS) or "no-timing-check",
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
        cpus_per_task=1,
    params:
        settings=lambda w: TIMING_SETUPS[w.check][1],
    script:
        "../scripts/check_timing.py"


rule timing_table:
    input:
        rows=[f"{CHECK_DIR}/timing/{check}.csv" for check in TIMING_SETUPS],
    output:
        rows=f"{RESULTS}/tables/timing_seconds.csv",
    log:
        f"{RESULTS}/logs/tables/timing_seconds.log",
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
        cpus_per_task=1,
    script:
        "../scripts/concat_tables.py"


rule checks:
    input:
        list(checks_outputs().values()),
