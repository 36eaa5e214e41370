"""Job: Fig 2. Fit K components to dense random samples of a mesh, then compare likelihood expressions: the
triangle bound, centroids, area × centroids, the triangles with a responsibility per point, and n sampled points
(several draws per n)."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

import trimesh
from threadpoolctl import threadpool_limits

from dgmm import GaussianMixture, Primitives
from dgmm.data import load_mesh
from dgmm.experiments.shared_responsibility import PER_POINT_MEASURE, SUBDIVISIONS, per_point_likelihoods
from dgmm.experiments.sweep import expected_log_likelihood, job_seed, representation_likelihoods
from dgmm.recording import FitRecorder
from dgmm.runtime.tables import write_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
p, cfg = smk.params, smk.params.fig2
vertices, faces = load_mesh(smk.input.mesh)
mesh = trimesh.Trimesh(vertices, faces, process=False)


def surface_points(n, key, draw):
    """n points uniform on the mesh surface, from the seed of (key, draw)."""
    return trimesh.sample.sample_surface(mesh, n, seed=job_seed(p.seed, key, draw))[0]


dense = surface_points(cfg["points"], "fig2/fit", 0)
params = dict(model=cfg["model"], mesh=cfg["mesh"], K=cfg["components"], points=cfg["points"], init="kmeans",
              max_iter=p.max_iter, tol=p.tol, reg_covar=p.reg_covar, root_seed=p.seed)
with threadpool_limits(smk.threads), FitRecorder(smk.output.mcap, smk.output.rrd, params=params, data=mesh) as rec:
    rec.begin_seed(0)
    model = GaussianMixture(cfg["components"], max_iter=p.max_iter, tol=p.tol, reg_covar=p.reg_covar,
                            random_state=job_seed(p.seed, "fig2/fit", 0), callback=rec).fit(dense)
    rec.end_seed(model)

    rows = [{"measure": name, "n": "", "draw": 0, "bound": bound, "expected": expected}
            for name, (bound, expected) in representation_likelihoods(model, vertices, faces).items()]
    bound, expected = per_point_likelihoods(model, vertices, faces)
    rows.append({"measure": PER_POINT_MEASURE, "n": SUBDIVISIONS ** 2, "draw": 0, "bound": bound,
                 "expected": expected})
    for n in cfg["sizes"]:
        for draw in range(cfg["draws"]):
            points = Primitives.from_points(surface_points(n, f"fig2/points/{n}", draw))
            rows.append({"measure": "points", "n": n, "draw": draw, "bound": model.score_primitives(points),
                         "expected": expected_log_likelihood(model, points)})
    fitted = Primitives.from_points(dense)
    rows.append({"measure": "all points", "n": len(dense), "draw": 0, "bound": model.score_primitives(fitted),
                 "expected": expected_log_likelihood(model, fitted)})
write_csv(smk.output.table, rows)
