"""
Write a rerun recording
=======================

The same recorder writes a rerun recording (``.rrd``) of the first seed: the input, the mixture's ellipsoids at
every EM iteration and the bound, on the ``iteration`` timeline, with a blueprint that opens the viewer on a 3D view
beside the bound. ``rerun fit.rrd`` (or ``dgmm view fit.rrd``) replays it; without a screen, rerun's own chunk
reader reads it back, as here.

.. image:: /recordings/fit.png
   :alt: fit.rrd of the quick start in the rerun viewer

*The quick start's* ``fit.rrd`` *in the rerun viewer (a screenshot; see* :doc:`/user_guide/recordings` *).*
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import trimesh
from rerun.chunk import RrdReader

import dgmm
from dgmm.data import REGISTRY, fetch, load_mesh
from dgmm.recording import FitRecorder

root = Path(dgmm.__file__).resolve().parents[1]
path = fetch(REGISTRY["bunny"]["res4"], mirrors=[root / "../shared/data/stanford"], cache=Path.home() / ".cache/dgmm")
vertices, faces = load_mesh(path)

folder = Path(tempfile.mkdtemp())
mesh = trimesh.Trimesh(vertices, faces, process=False)
with FitRecorder(folder / "fit.mcap", folder / "fit.rrd", data=mesh) as recorder:
    recorder.begin_seed(0)
    model = dgmm.GaussianMixture(25, max_iter=25, tol=0, random_state=0, callback=recorder)
    recorder.end_seed(model.fit(mesh))
print(f"fit.rrd: {(folder / 'fit.rrd').stat().st_size} bytes")

# %%
# Each chunk of the recording belongs to one entity; list them with the components they carry.
entities = {}
for chunk in RrdReader(folder / "fit.rrd").store().stream().to_chunks():
    names = [name for name in chunk.to_record_batch().schema.names if name not in ("rerun.controls.RowId", "log_time")]
    entities.setdefault(chunk.entity_path, set()).update(names)
for entity, names in sorted(entities.items()):
    print(entity, sorted(names))

# %%
# The recorded bound, iteration by iteration: the scalars of the recording's plot view.
rows = []
for chunk in RrdReader(folder / "fit.rrd").store().stream().to_chunks():
    batch = chunk.to_record_batch()
    if "iteration" in batch.schema.names and any("Scalar" in name for name in batch.schema.names):
        scalar = next(name for name in batch.schema.names if "Scalar" in name)
        rows += zip(batch.column("iteration").to_pylist(), batch.column(scalar).to_pylist())
iterations, values = np.array(sorted(rows), dtype=object).T
fig, ax = plt.subplots(figsize=(6, 3.5))
ax.plot(iterations, [np.ravel(value)[0] for value in values], marker=".")
ax.set_xlabel("iteration (the recording's timeline)")
ax.set_ylabel("bound")
ax.set_title("the bound, read back from fit.rrd")
fig.tight_layout()
