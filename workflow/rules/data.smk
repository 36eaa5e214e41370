# Data stage (paper §IV "Mesh Input Data", "Mesh Decimation"): for every configured model, under results/data/{model}/
#   full.ply                 the model's mesh as registered, unreferenced vertices removed (bunny: also res4.ply)
#   {mesh}_eval.ply          Poisson-disk evaluation points of each such mesh (data.eval_points of them)
#   {method}{budget}.ply     fitting inputs from full.ply: quadric / clustering decimations, Poisson / random samples
import os

from dgmm.data import REGISTRY
from dgmm.meshes import REDUCTIONS

DATA = config["data"]
DATA_DIR = f"{RESULTS}/data"


def data_dir(path):
    """A configured directory: "~" expanded, relative paths taken from the repository root (not the working dir)."""
    return os.path.normpath(os.path.join(workflow.basedir, os.path.expanduser(path)))


def data_targets():
    """Every file the data stage builds for the configured models."""
    targets = []
    for model in DATA["models"]:
        for mesh in REGISTRY[model]:
            targets += [f"{DATA_DIR}/{model}/{mesh}.ply", f"{DATA_DIR}/{model}/{mesh}_eval.ply"]
        targets += expand(f"{DATA_DIR}/{model}/{{method}}{{budget}}.ply", method=DATA["methods"], budget=DATA["budgets"])
    return targets


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
    wildcard_constraints:
        **DATA_WILDCARDS,
    output:
        mesh=f"{DATA_DIR}/{{model}}/{{mesh}}.ply",
    params:
        sha256=lambda w: REGISTRY[w.model][w.mesh].sha256,
        mirrors=[data_dir(path) for path in DATA["mirrors"]],
        cache=data_dir(DATA["cache"]),
    log:
        f"{RESULTS}/logs/data/{{model}}/{{mesh}}.log",
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
        cpus_per_task=1,
    script:
        "../scripts/data_mesh.py"


rule data_eval:
    wildcard_constraints:
        **DATA_WILDCARDS,
    input:
        mesh=f"{DATA_DIR}/{{model}}/{{mesh}}.ply",
    output:
        points=f"{DATA_DIR}/{{model}}/{{mesh}}_eval.ply",
    params:
        method="poisson",
        budget=DATA["eval_points"],
    log:
        f"{RESULTS}/logs/data/{{model}}/{{mesh}}_eval.log",
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
        cpus_per_task=1,
    script:
        "../scripts/data_reduce.py"


rule data_reduce:
    wildcard_constraints:
        **DATA_WILDCARDS,
    input:
        mesh=f"{DATA_DIR}/{{model}}/full.ply",
    output:
        reduced=f"{DATA_DIR}/{{model}}/{{method}}{{budget}}.ply",
    params:
        method=lambda w: w.method,
        budget=lambda w: int(w.budget),
    log:
        f"{RESULTS}/logs/data/{{model}}/{{method}}{{budget}}.log",
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
        cpus_per_task=1,
    script:
        "../scripts/data_reduce.py"
