"""Job: render the synthetic TUM-format sequence (dgmm.odometry.synthetic): the room with the data-stage meshes."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from threadpoolctl import threadpool_limits

from dgmm.data import load_mesh
from dgmm.experiments.sweep import job_seed
from dgmm.odometry.synthetic import room_scene, write_synthetic_sequence

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
models = [vertices[faces] for vertices, faces in map(load_mesh, smk.input.meshes)]
seed = job_seed(smk.params.seed, "odometry/synthetic", 0)
with threadpool_limits(smk.threads):
    sequence = write_synthetic_sequence(smk.output.sequence, room_scene(models), n_frames=smk.params.frames,
                                        seed=seed)
print(f"{smk.output.sequence}: {len(sequence)} frames, seed {seed}", file=sys.stderr)
