"""
Draw a mixture's ellipsoids
===========================

A mixture's components are Gaussians; each is drawn as the ellipsoid two standard deviations along its principal
axes (:func:`dgmm.recording.covariance_ellipsoids`, the same ellipsoids the MCAP and rerun recordings carry).
Here a K=25 fit to the bunny's triangles, drawn with matplotlib over the mesh.
"""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import dgmm
from dgmm.data import REGISTRY, fetch, load_mesh
from dgmm.recording import covariance_ellipsoids

root = Path(dgmm.__file__).resolve().parents[1]
path = fetch(REGISTRY["bunny"]["res4"], mirrors=[root / "../shared/data/stanford"], cache=Path.home() / ".cache/dgmm")
vertices, faces = load_mesh(path)
gmm = dgmm.GaussianMixture(25, random_state=0).fit(dgmm.Primitives.from_mesh(vertices, faces))
print(f"bound {gmm.lower_bound_:.2f} after {gmm.n_iter_} iterations")

# %%
# ``rotations[i]`` holds component i's principal axes as columns and ``half_sizes[i]`` the ellipsoid's half-lengths
# along them: a unit sphere scaled by the half-sizes, rotated and moved to the mean is the ellipsoid.
rotations, half_sizes, _ = covariance_ellipsoids(gmm.covariances_, n_sigma=2.0)
u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 24), np.linspace(0, np.pi, 12))
sphere = np.stack([np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v)], axis=-1)  # (12, 24, 3)

fig = plt.figure(figsize=(9, 4.8))
for column, (elevation, azimuth) in enumerate([(15, 0), (15, -90)]):
    ax = fig.add_subplot(1, 2, column + 1, projection="3d")
    ax.plot_trisurf(*vertices.T, triangles=faces, color="0.85", alpha=0.25, linewidth=0)
    colours = plt.cm.tab20(np.linspace(0, 1, len(gmm.weights_)))
    for mean, rotation, sizes, colour in zip(gmm.means_, rotations, half_sizes, colours):
        surface = (sphere * sizes) @ rotation.T + mean
        ax.plot_surface(*np.moveaxis(surface, -1, 0), color=colour, alpha=0.6, linewidth=0)
    ax.view_init(elev=elevation, azim=azimuth, vertical_axis="y")
    ax.set_box_aspect(np.ptp(vertices, axis=0)[[0, 2, 1]], zoom=1.3)  # matplotlib's (x, y, z) box, y vertical
    ax.set_axis_off()
fig.suptitle("bunny res4: K=25 mixture of the exact triangles, 2-sigma ellipsoids")
fig.tight_layout()
