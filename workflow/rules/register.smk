# Registration (paper §V "Mesh Registration": Fig 5, Table 1's error columns): for every configured (model, mesh),
# random rigid trials registered by each method, every method on the same trials and source points. The source
# points are drawn from the Poisson-disk evaluation set of the mesh the registered mesh comes from (res4's own,
# else the full model's). Under results/registration/{model}/{mesh}/{method}/:
#   gmm.npz, fit.mcap, fit.rrd   P2D methods: the mixture, fitted once and used by every chunk, and its fit logs
#                                (*-c2f methods register to the mixture of the same method without the suffix)
#   c{chunk}/errors.csv          one row per trial: errors, iterations, convergence (deterministic)
#   c{chunk}/seconds.csv         each trial's wall time (kept apart so that errors stay byte-identical)
#   c{chunk}/trials.mcap         every trial's true and estimated pose, errors, iterations and time (Foxglove)
#   c{chunk}/trials.rrd          the chunk's first trials: source points moving iteration by iteration
# and results/tables/registration.csv, registration_seconds.csv gather every chunk.
from dgmm.data import REGISTRY
from dgmm.trials import METHODS, mixture_source

REG = config["registration"]
REG_DIR = f"{RESULTS}/registration/{{model}}/{{mesh}}/{{method}}"


def registration_experiments():
    """(model, mesh) -> (trials, methods) over every experiment; an experiment repeated on the same mesh takes
    the most trials and every method (trials are the same for every experiment, see dgmm.trials)."""
    jobs = {}
    for experiment in REG["experiments"].values():
        for model in experiment["models"]:
            trials, methods = jobs.get((model, experiment["mesh"]), (0, []))
            methods = methods + [m for m in experiment["methods"] if m not in methods]
            jobs[model, experiment["mesh"]] = (max(trials, experiment["trials"]), methods)
    return jobs


REG_EXPERIMENTS = registration_experiments()


def chunk_range(wildcards):
    """[first, stop) trials of a chunk."""
    n_trials, size = REG_EXPERIMENTS[wildcards.model, wildcards.mesh][0], REG["trials_per_chunk"]
    first = int(wildcards.chunk) * size
    return [first, min(n_trials, first + size)]


def registration_outputs(name):
    """Path of file ``name`` of every configured chunk, ordered by model, mesh, configured method, chunk."""
    size = REG["trials_per_chunk"]
    return [f"{RESULTS}/registration/{model}/{mesh}/{method}/c{chunk}/{name}"
            for (model, mesh), (n_trials, methods) in sorted(REG_EXPERIMENTS.items())
            for method in methods for chunk in range(-(-n_trials // size))]


def dense_sample(wildcards):
    """Evaluation set of the mesh's origin: a registered mesh's own (bunny res4), else the full model's."""
    origin = wildcards.mesh if wildcards.mesh in REGISTRY[wildcards.model] else "full"
    return f"{DATA_DIR}/{wildcards.model}/{origin}_eval.ply"


def registration_mixture(wildcards):
    """The method's fitted mixture, for the methods that use one (``*-c2f``: its paper P2D's)."""
    if not METHODS[wildcards.method].needs_mixture:
        return {}
    return {"gmm": REG_DIR.format(**{**wildcards, "method": mixture_source(wildcards.method)}) + "/gmm.npz"}


REG_WILDCARDS = dict(model="|".join(REGISTRY), mesh="[a-z0-9]+", method="|".join(METHODS), chunk=r"\d+")
C2F_SCALES = REG.get("c2f_scales", [0.5, 0.25, 0.125, 0.0625, 0.0])
REG_MIXTURE = {key: REG[key] for key in ("components", "max_iter", "tol", "reg_covar", "variant")}


rule registration_gmm:
    wildcard_constraints:
        **REG_WILDCARDS,
    input:
        mesh=f"{DATA_DIR}/{{model}}/{{mesh}}.ply",
    output:
        gmm=f"{REG_DIR}/gmm.npz",
        mcap=f"{REG_DIR}/fit.mcap",
        rrd=f"{REG_DIR}/fit.rrd",
    params:
        seed=config["seed"],
        mixture=REG_MIXTURE,
    log:
        f"{RESULTS}/logs/registration/{{model}}/{{mesh}}/{{method}}/gmm.log",
    threads: 1
    script:
        "../scripts/registration_gmm.py"


rule registration_chunk:
    wildcard_constraints:
        **REG_WILDCARDS,
    input:
        unpack(registration_mixture),
        mesh=f"{DATA_DIR}/{{model}}/{{mesh}}.ply",
        dense=dense_sample,
    output:
        errors=f"{REG_DIR}/c{{chunk}}/errors.csv",
        seconds=f"{REG_DIR}/c{{chunk}}/seconds.csv",
        mcap=f"{REG_DIR}/c{{chunk}}/trials.mcap",
        rrd=f"{REG_DIR}/c{{chunk}}/trials.rrd",
    params:
        seed=config["seed"],
        trials=chunk_range,
        recorded=REG["recorded_trials"],
        max_angle_deg=REG["max_angle_deg"],
        max_translation=REG["max_translation"],
        protocol=REG.get("protocol", "scaled"),
        options={"p2d": {"gradient": REG["gradient"]}, "p2d-c2f": {"gradient": REG["gradient"], "scales": C2F_SCALES},
                 "icp": REG["icp"], "cpd": REG["cpd"]},
    log:
        f"{RESULTS}/logs/registration/{{model}}/{{mesh}}/{{method}}/c{{chunk}}.log",
    threads: 1
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
    threads: 1
    script:
        "../scripts/concat_tables.py"


rule registration:
    input:
        rules.registration_table.output,
