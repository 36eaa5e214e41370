# Fitting sweep (paper Figs 3, 4 and Table 1's likelihood columns): one job per (model, input, variant, K, init),
# seeds looped inside the job. Under results/fits/{model}/{input}/{variant}/k{K}-{init}/:
#   scores.csv   one row per seed: eval_ll, bound, n_iter (deterministic)
#   seconds.csv  wall time of each seed's fit (kept apart so that scores stay byte-identical across runs)
#   fit.mcap     per-iteration bounds and times of every seed, the run's parameters, final mixtures (Foxglove)
#   fit.rrd      the first seed's input and its mixture at every EM iteration (`rerun fit.rrd` replays it)
from dgmm.sweep import parse_input, variants_for

FIT = config["fit"]
FIT_DIR = f"{RESULTS}/fits/{{model}}/{{input}}/{{variant}}/k{{k}}-{{init}}"


def fit_jobs():
    """(model, input, variant, K, init) of every configured fit, each once."""
    jobs = set()
    for experiment in FIT["experiments"].values():
        for model in experiment["models"]:
            for input_name in experiment["inputs"]:
                for variant in variants_for(input_name, FIT["variants"]):
                    for k in experiment["components"]:
                        for init in experiment["inits"]:
                            jobs.add((model, input_name, variant, k, init))
    return sorted(jobs)


def fit_outputs(name):
    pattern = FIT_DIR.replace("{{", "{").replace("}}", "}") + f"/{name}"
    return [pattern.format(model=m, input=i, variant=v, k=k, init=n) for m, i, v, k, n in fit_jobs()]


def evaluation_set(wildcards):
    """Fig 3 inputs (made from res4) are scored on res4's evaluation set, all others on the full model's."""
    source = parse_input(wildcards.input)[0]
    mesh = source if source in ("full", "res4") else "full"
    return f"{DATA_DIR}/{wildcards.model}/{mesh}_eval.ply"


wildcard_constraints:
    input=r"[a-z0-9]+-[a-z]+",
    variant="textbook|authors",
    k=r"\d+",
    init="kmeans|random",


rule fit:
    input:
        data=lambda w: f"{DATA_DIR}/{w.model}/{parse_input(w.input)[0]}.ply",
        evaluation=evaluation_set,
    output:
        scores=f"{FIT_DIR}/scores.csv",
        seconds=f"{FIT_DIR}/seconds.csv",
        mcap=f"{FIT_DIR}/fit.mcap",
        rrd=f"{FIT_DIR}/fit.rrd",
    params:
        seed=config["seed"],
        seeds=FIT["seeds"],
        max_iter=FIT["max_iter"],
        tol=FIT["tol"],
        reg_covar=FIT["reg_covar"],
    log:
        f"{RESULTS}/logs/fits/{{model}}/{{input}}/{{variant}}/k{{k}}-{{init}}.log",
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
        cpus_per_task=1,
    script:
        "../scripts/fit.py"
