"""Job: fit the Gaussian mixture of one P2D registration method on one model's mesh under one trial protocol."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

import trimesh
from threadpoolctl import threadpool_limits

from dgmm.data import load_mesh
from dgmm.experiments.sweep import job_seed
from dgmm.experiments.trials import bounding_diagonal, fit_mixture, protocol_reg_covar
from dgmm.model_io import save_model
from dgmm.recording import FitRecorder

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
w, p = smk.wildcards, smk.params
key = f"registration/{w.model}/{w.mesh}/{w.method}"
vertices, faces = load_mesh(smk.input.mesh)
settings = dict(p.mixture)
settings["reg_covar"] = protocol_reg_covar(settings["reg_covar"], bounding_diagonal(vertices), w.protocol)
seed = job_seed(p.seed, key, 0)
params = dict(model=w.model, mesh=w.mesh, protocol=w.protocol, method=w.method, variant=w.variant, **settings,
              seed=seed, root_seed=p.seed)
n_components = settings.pop("components")
shown = trimesh.Trimesh(vertices, faces, process=False)

with threadpool_limits(smk.threads), FitRecorder(smk.output.mcap, smk.output.rrd, params=params, data=shown) as rec:
    rec.begin_seed(0)
    model = fit_mixture(w.method, vertices, faces, n_components=n_components, variant=w.variant, seed=seed,
                        callback=rec, **settings)
    rec.end_seed(model)
save_model(smk.output.gmm, model, {**params, "n_iter": model.n_iter_, "bound": model.lower_bound_})
print(f"{key}: {model.n_iter_} iterations, bound {model.lower_bound_:.4f}", file=sys.stderr)
