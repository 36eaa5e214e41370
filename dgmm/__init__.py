"""dgmm: fit Gaussian mixtures directly to meshes and other geometric primitives.

Keselman & Hebert, "Direct Fitting of Gaussian Mixture Models" (2019).

>>> import trimesh, dgmm
>>> mesh = trimesh.load("bunny_res4.ply")
>>> gmm = dgmm.GaussianMixture(100, random_state=0).fit(mesh)    # exact triangles
>>> gmm.score(mesh.sample(50000))                                # mean log-likelihood per point
"""
from dgmm.errors import ConfigError, DataError, DgmmError, FitError, InputError
from dgmm.mixture import GaussianMixture
from dgmm.primitives import Primitives

__all__ = ["ConfigError", "DataError", "DgmmError", "FitError", "GaussianMixture", "InputError", "Primitives"]
__version__ = "0.1.0"
