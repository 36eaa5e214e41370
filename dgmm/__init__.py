"""dgmm: fit Gaussian mixtures directly to meshes and other geometric primitives.

Keselman & Hebert, "Direct Fitting of Gaussian Mixture Models" (2019).

>>> import trimesh, dgmm
>>> mesh = trimesh.load("bunny_res4.ply")
>>> gmm = dgmm.GaussianMixture(100, random_state=0).fit(mesh)    # exact triangles
>>> gmm.score(mesh.sample(50000))                                # mean log-likelihood per point
"""
from dgmm.errors import ConfigError, DataError, DgmmError, FitError, InputError

__all__ = ["ConfigError", "DataError", "DgmmError", "FitError", "GaussianMixture", "InputError", "Primitives"]
__version__ = "0.1.0"


def __getattr__(name):
    """``dgmm.GaussianMixture`` and ``dgmm.Primitives``, imported on first use: scikit-learn (over a second) and
    numpy are not needed to start the command line."""
    if name == "GaussianMixture":
        from dgmm.mixture import GaussianMixture
        return GaussianMixture
    if name == "Primitives":
        from dgmm.primitives import Primitives
        return Primitives
    raise AttributeError(f"module 'dgmm' has no attribute {name!r}")
