"""Job: fetch a registered mesh (mirror, cache or download), check its sha256 and write it as canonical PLY."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from dgmm.data import REGISTRY, fetch, load_mesh, save_ply

sys.stderr = open(snakemake.log[0], "w")  # noqa: F821 (snakemake is injected)
remote = REGISTRY[snakemake.wildcards.model][snakemake.wildcards.mesh]  # noqa: F821
path = fetch(remote, snakemake.params.mirrors, snakemake.params.cache)  # noqa: F821
vertices, faces = load_mesh(path)
print(f"{path}: {len(vertices)} vertices, {len(faces)} faces", file=sys.stderr)
save_ply(snakemake.output.mesh, vertices, faces)  # noqa: F821
