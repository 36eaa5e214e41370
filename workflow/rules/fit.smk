# Fitting sweep (paper Figs 3, 4 and Table 1's likelihood columns): one job per (model, input, variant, K, init),
# seeds looped inside the job. Under results/fits/{model}/{input}/{variant}/k{K}-{init}/:
#   scores.csv   one row per seed: eval_ll, bound, n_iter (deterministic)
#   seconds.csv  wall time of each seed's fit (kept apart so that scores stay byte-identical across runs)
#   fit.mcap     per-iteration bounds and times of every seed, the run's parameters, final mixtures (Foxglove)
#   fit.rrd      the first seed's input and its mixture at every EM iteration (`rerun fit.rrd` replays it)
# An experiment that caps EM otherwise than fit.max_iter (fit.experiments.*.max_iter, e.g. Fig 4 at the authors' 100)
# runs its fits as jobs of rule fit_capped, under .../k{K}-{init}-i{max_iter}/, from the same seeds: the first
# fit.max_iter iterations of each are those of the fit.max_iter job.
FIT_DIR = f"{RESULTS}/fits/{{model}}/{{input}}/{{variant}}/k{{k}}-{{init}}"
FIT_JOB = "{model}/{input}/{variant}/k{k}-{init}"


wildcard_constraints:
    input=r"[a-z0-9]+-[a-z]+",
    variant="textbook|authors",
    k=r"\d+",
    init="kmeans|random",
    max_iter=r"\d+",


rule fit:
    input:
        data=fit_input,
        evaluation=evaluation_set,
    output:
        scores=f"{FIT_DIR}/scores.csv",
        seconds=f"{FIT_DIR}/seconds.csv",
        mcap=f"{FIT_DIR}/fit.mcap",
        rrd=f"{FIT_DIR}/fit.rrd",
    log:
        f"{RESULTS}/logs/fits/{{model}}/{{input}}/{{variant}}/k{{k}}-{{init}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/fit/{{model}}/{{input}}/{{variant}}/k{{k}}-{{init}}.tsv"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
        cpus_per_task=1,
    params:
        seed=config["seed"],
        seeds=FIT["seeds"],
        max_iter=FIT["max_iter"],
        tol=FIT["tol"],
        reg_covar=FIT["reg_covar"],
    script:
        "../scripts/fit.py"


use rule fit as fit_capped with:
    output:
        scores=f"{FIT_DIR}-i{{max_iter}}/scores.csv",
        seconds=f"{FIT_DIR}-i{{max_iter}}/seconds.csv",
        mcap=f"{FIT_DIR}-i{{max_iter}}/fit.mcap",
        rrd=f"{FIT_DIR}-i{{max_iter}}/fit.rrd",
    log:
        f"{RESULTS}/logs/fits/{FIT_JOB}-i{{max_iter}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/fit/{FIT_JOB}-i{{max_iter}}.tsv"
    params:
        max_iter=lambda wildcards: int(wildcards.max_iter),
