# Registration (paper §VI-A "Mesh Registration": Fig 6, Table 1's error columns): for every configured (model, mesh),
# random rigid trials registered by each method, every method on the same trials and source points. The source
# points are drawn from the Poisson-disk evaluation set of the mesh the registered mesh comes from (res4's own,
# else the full model's). Each experiment runs under its trial protocols (scaled, literal) and each mesh mixture
# under every EM variant of registration.variants (dgmm.experiments.trials.method_variants; ICP and CPD under "none").
# Under results/registration/{model}/{mesh}/{protocol}/{variant}/{method}/:
#   gmm.npz, fit.mcap, fit.rrd   P2D methods: the mixture, fitted once and used by every chunk, and its fit logs
#                                (*-c2f methods use their paper P2D's mixture; its covariance floor follows the
#                                protocol, dgmm.experiments.trials.protocol_reg_covar)
#   c{chunk}/errors.csv          one row per trial: errors, iterations, convergence (deterministic)
#   c{chunk}/seconds.csv         each trial's wall time (kept apart so that errors stay byte-identical)
#   c{chunk}/trials.mcap         every trial's true and estimated pose, errors, iterations and time (Foxglove)
#   c{chunk}/trials.rrd          the chunk's first trials: source points moving iteration by iteration
# and results/tables/registration.csv, registration_seconds.csv gather every chunk.
REG_DIR = f"{RESULTS}/registration/{{model}}/{{mesh}}/{{protocol}}/{{variant}}/{{method}}"
REG_WILDCARDS = dict(
    model="|".join(REGISTRY),
    mesh="[a-z0-9]+",
    method="|".join(METHODS),
    chunk=r"\d+",
    protocol="|".join(PROTOCOLS),
    variant=f"textbook|authors|{NO_VARIANT}",
)
C2F_SCALES = REG["c2f_scales"]
REG_MIXTURE = {key: REG[key] for key in ("components", "max_iter", "tol", "reg_covar")}


rule registration_gmm:
    input:
        mesh=f"{DATA_DIR}/{{model}}/{{mesh}}.ply",
    output:
        gmm=f"{REG_DIR}/gmm.npz",
        mcap=f"{REG_DIR}/fit.mcap",
        rrd=f"{REG_DIR}/fit.rrd",
    log:
        f"{RESULTS}/logs/registration/{{model}}/{{mesh}}/{{protocol}}/{{variant}}/{{method}}/gmm.log",
    benchmark:
        f"{RESULTS}/benchmarks/registration_gmm/{{model}}/{{mesh}}/{{protocol}}/{{variant}}/{{method}}.tsv"
    wildcard_constraints:
        **REG_WILDCARDS,
    priority: PRIORITY["registration_gmm"]
    threads: 1
    resources:
        mem_mb=1000,  # measured: 281 MB peak, 0.3-4.7 s (config.yaml)
        runtime=5,
        cpus_per_task=1,
    params:
        seed=config["seed"],
        mixture=REG_MIXTURE,
    script:
        "../scripts/registration_gmm.py"


rule registration_chunk:
    input:
        unpack(registration_mixture),
        mesh=f"{DATA_DIR}/{{model}}/{{mesh}}.ply",
        dense=dense_sample,
    output:
        errors=f"{REG_DIR}/c{{chunk}}/errors.csv",
        seconds=f"{REG_DIR}/c{{chunk}}/seconds.csv",
        mcap=f"{REG_DIR}/c{{chunk}}/trials.mcap",
        rrd=f"{REG_DIR}/c{{chunk}}/trials.rrd",
    log:
        f"{RESULTS}/logs/registration/{{model}}/{{mesh}}/{{protocol}}/{{variant}}/{{method}}/c{{chunk}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/registration_chunk/{{model}}/{{mesh}}/{{protocol}}/{{variant}}/{{method}}/c{{chunk}}.tsv"
    wildcard_constraints:
        **REG_WILDCARDS,
    priority: PRIORITY["registration_chunk"]
    threads: 1
    resources:
        mem_mb=1000,  # measured: 281 MB peak, 1-39 s (config.yaml; 50 CPD trials the longest)
        runtime=10,
        cpus_per_task=1,
    params:
        seed=config["seed"],
        trials=chunk_range,
        recorded=REG["recorded_trials"],
        max_angle_deg=REG["max_angle_deg"],
        max_translation=REG["max_translation"],
        options={
            "p2d": {"gradient": REG["gradient"]},
            "p2d-c2f": {"gradient": REG["gradient"], "scales": C2F_SCALES},
            "icp": REG["icp"],
            "cpd": REG["cpd"],
        },
    script:
        "../scripts/registration_chunk.py"


rule registration_table:
    input:
        errors=registration_outputs("errors.csv"),
        seconds=registration_outputs("seconds.csv"),
    output:
        errors=f"{RESULTS}/tables/registration.csv",
        seconds=f"{RESULTS}/tables/registration_seconds.csv",
    log:
        f"{RESULTS}/logs/tables/registration.log",
    benchmark:
        f"{RESULTS}/benchmarks/registration_table.tsv"
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
        cpus_per_task=1,
    script:
        "../scripts/concat_tables.py"


rule registration:
    input:
        rules.registration_table.output,
