"""Job: register one chunk of one (model, mesh)'s trials with one method; write errors, timings, recordings."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from threadpoolctl import threadpool_limits

from dgmm.data import load_mesh, load_points
from dgmm.experiments.trials import COLUMNS, bounding_diagonal, make_trials, run_trials
from dgmm.model_io import load_model
from dgmm.recording import RegistrationRecorder
from dgmm.runtime.tables import write_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
w, p = smk.wildcards, smk.params
vertices, _ = load_mesh(smk.input.mesh)
diagonal = bounding_diagonal(vertices)
indices = range(*p.trials)
setups = make_trials(load_points(smk.input.dense), len(vertices), indices, root_seed=p.seed,
                     key=f"registration/{w.model}/{w.mesh}", diagonal=diagonal, max_angle_deg=p.max_angle_deg,
                     max_translation=p.max_translation, protocol=w.protocol)
mixture = load_model(smk.input.gmm)[0] if "gmm" in smk.input.keys() else None
params = dict(model=w.model, mesh=w.mesh, method=w.method, variant=w.variant, chunk=int(w.chunk),
              trials=list(p.trials), n_points=len(vertices), diagonal=diagonal, protocol=w.protocol,
              options=dict(p.options), root_seed=p.seed)

recorded = indices[:p.recorded]
with threadpool_limits(smk.threads), RegistrationRecorder(smk.output.mcap, smk.output.rrd, params=params,
                                                          mixture=mixture, recorded_trials=recorded) as rec:
    rows, seconds = run_trials(w.method, setups, diagonal, mixture=mixture, options=p.options, recorder=rec)
job = dict(model=w.model, mesh=w.mesh, protocol=w.protocol, variant=w.variant, method=w.method)
write_csv(smk.output.errors, [{**job, **row} for row in rows], [*job, *COLUMNS])
write_csv(smk.output.seconds, [{**job, "trial": row["trial"], "seconds": s, "recorded": row["trial"] in recorded}
                               for row, s in zip(rows, seconds)])
print(f"{w.model}/{w.mesh}/{w.method} c{w.chunk}: {len(rows)} trials", file=sys.stderr)
