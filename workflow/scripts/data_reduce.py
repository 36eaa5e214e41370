"""Job: one pymeshlab sampling or decimation of a mesh to a budget (one per process: its samplers take no seed)."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from dgmm.data import load_mesh, save_ply
from dgmm.meshes import REDUCTIONS

sys.stderr = open(snakemake.log[0], "w")  # noqa: F821 (snakemake is injected)
method, budget = snakemake.params.method, snakemake.params.budget  # noqa: F821
vertices, faces = REDUCTIONS[method](*load_mesh(snakemake.input.mesh), budget)  # noqa: F821
print(f"{method} {budget}: {len(vertices)} vertices, {0 if faces is None else len(faces)} faces", file=sys.stderr)
save_ply(snakemake.output[0], vertices, faces)  # noqa: F821
