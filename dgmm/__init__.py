"""dgmm: fit Gaussian mixtures directly to meshes and other geometric primitives.

Keselman & Hebert, "Direct Fitting of Gaussian Mixture Models" (2019).
"""
from dgmm.errors import ConfigError, DataError, DgmmError, FitError, InputError

__all__ = ["ConfigError", "DataError", "DgmmError", "FitError", "InputError"]
__version__ = "0.1.0"
