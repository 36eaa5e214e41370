"""
Register a turned bunny: P2D against ICP
========================================

The paper's registration experiment in small: points of the bunny's surface are moved by random rigid motions of
the authors' protocol (Euler angles within ±15°, translations within ±0.05 per axis) and registered back,

* by P2D (point-to-distribution): maximise the likelihood of the moved points under a K=100 mixture fitted to the
  mesh's exact triangles, with the paper's BFGS from the identity;
* by the authors' point-to-point ICP, with nearest neighbours both ways, onto an independent draw of surface points.

Errors are the residual rotation angle and how far the residual pose moves the points' centroid, in % of the
bounding-box diagonal, as in the paper's Fig 6.
"""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import dgmm
from dgmm.data import REGISTRY, fetch, load_mesh
from dgmm.meshes import poisson_disk
from dgmm.registration import random_trials, register_icp, register_p2d, registration_errors

root = Path(dgmm.__file__).resolve().parents[1]
path = fetch(REGISTRY["bunny"]["res4"], mirrors=[root / "../shared/data/stanford"], cache=Path.home() / ".cache/dgmm")
vertices, faces = load_mesh(path)
diagonal = np.linalg.norm(np.ptp(vertices, axis=0))

# The target mixture (the registration experiments' settings: 100 iterations, tol 1e-5), and two independent draws
# of as many surface points as the mesh has vertices: the source, and ICP's target.
mixture = dgmm.GaussianMixture(100, max_iter=100, tol=1e-5, random_state=0).fit(dgmm.Primitives.from_mesh(vertices,
                                                                                                            faces))
rng = np.random.default_rng(0)
surface = poisson_disk(vertices, faces, 10_000)
source, target = (surface[rng.choice(len(surface), len(vertices), replace=False)] for _ in range(2))

# %%
# Ten trials; each method registers the moved source back (P2D onto the mixture, ICP onto the target points).
trials = random_trials(10, seed=1, diagonal=diagonal, centre=source.mean(axis=0))
errors = {"P2D (mesh mixture)": [], "ICP (both ways)": []}
for trial in trials:
    moved = trial.apply(source)
    for name, result in [("P2D (mesh mixture)", register_p2d(moved, mixture)),
                         ("ICP (both ways)", register_icp(moved, target))]:
        errors[name].append(registration_errors(result, trial, diagonal))
for name, rows in errors.items():
    rotation, translation = np.mean(rows, axis=0)
    print(f"{name:20s} rotation {rotation:.3f} deg, translation {translation:.3f} % of the diagonal (mean)")

# %%
# The first trial: the moved source (grey), and where each method puts it back, over the original points (black).
moved = trials[0].apply(source)
fig, axes = plt.subplots(1, 3, figsize=(10, 3.6), sharex=True, sharey=True)
panels = [("moved source", moved), ("P2D", register_p2d(moved, mixture).apply(moved)),
          ("ICP", register_icp(moved, target).apply(moved))]
for ax, (title, points) in zip(axes, panels):
    ax.scatter(*source[:, :2].T, s=2, c="k", label="source before the motion")
    ax.scatter(*points[:, :2].T, s=2, c="tab:orange" if title != "moved source" else "0.6", label=title)
    ax.set_title(title)
    ax.set_aspect("equal")
    ax.set_axis_off()
fig.tight_layout()
