# Data stage (paper §IV "Mesh Input Data", "Mesh Decimation"): for every configured model, under results/data/{model}/
#   full.ply                 the model's mesh as registered, unreferenced vertices removed (bunny: also res4.ply)
#   {mesh}_eval.ply          Poisson-disk evaluation points of each such mesh (data.eval_points of them)
#   {method}{budget}.ply     fitting inputs from full.ply: quadric / clustering decimations, Poisson / random samples
from dgmm.meshes import REDUCTIONS

# Kept to this stage's rules: other stages use the same wildcard names with their own values.
DATA_WILDCARDS = dict(
    model="|".join(REGISTRY),
    mesh="|".join(sorted({mesh for meshes in REGISTRY.values() for mesh in meshes})),
    method="|".join(REDUCTIONS),
    budget=r"\d+",
)


rule data:
    input:
        data_targets(),


rule data_mesh:
    output:
        mesh=f"{DATA_DIR}/{{model}}/{{mesh}}.ply",
    log:
        f"{RESULTS}/logs/data/{{model}}/{{mesh}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/data_mesh/{{model}}/{{mesh}}.tsv"
    wildcard_constraints:
        **DATA_WILDCARDS,
    priority: PRIORITY["data"]
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
        cpus_per_task=1,
    params:
        sha256=lambda w: REGISTRY[w.model][w.mesh].sha256,
        mirrors=[data_dir(path) for path in DATA["mirrors"]],
        cache=data_dir(DATA["cache"]),
    script:
        "../scripts/data_mesh.py"


rule data_eval:
    input:
        mesh=f"{DATA_DIR}/{{model}}/{{mesh}}.ply",
    output:
        points=f"{DATA_DIR}/{{model}}/{{mesh}}_eval.ply",
    log:
        f"{RESULTS}/logs/data/{{model}}/{{mesh}}_eval.log",
    benchmark:
        f"{RESULTS}/benchmarks/data_eval/{{model}}/{{mesh}}.tsv"
    wildcard_constraints:
        **DATA_WILDCARDS,
    priority: PRIORITY["data"]
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
        cpus_per_task=1,
    params:
        method="poisson",
        budget=DATA["eval_points"],
    script:
        "../scripts/data_reduce.py"


rule data_reduce:
    input:
        mesh=f"{DATA_DIR}/{{model}}/full.ply",
    output:
        reduced=f"{DATA_DIR}/{{model}}/{{method}}{{budget}}.ply",
    log:
        f"{RESULTS}/logs/data/{{model}}/{{method}}{{budget}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/data_reduce/{{model}}/{{method}}{{budget}}.tsv"
    wildcard_constraints:
        **DATA_WILDCARDS,
    priority: PRIORITY["data"]
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
        cpus_per_task=1,
    params:
        method=lambda w: w.method,
        budget=lambda w: int(w.budget),
    script:
        "../scripts/data_reduce.py"
