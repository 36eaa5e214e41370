"""One exception family for dgmm: every message names the input and the problem in one line.

Errors that scikit-learn's estimator contract names also derive from the type it expects (``ValueError``,
``TypeError``; ``dgmm.mixture.NotFittedError`` is scikit-learn's ``NotFittedError``, defined beside the estimator
so that this module loads without scikit-learn), so code written for scikit-learn catches them.
"""


class DgmmError(Exception):
    """Base class of every error dgmm raises on purpose."""


class InputError(DgmmError, ValueError):
    """Bad array, mesh or parameter given to the library (shape, NaN, empty, degenerate, out of range)."""


class InputTypeError(InputError, TypeError):
    """An input of a type the library does not take (a sparse matrix, where scikit-learn raises TypeError)."""


class DataError(DgmmError):
    """A data file is missing, corrupt, empty or fails its checksum."""


class ConfigError(DgmmError):
    """A workflow configuration value is missing or invalid."""


class FitError(DgmmError):
    """EM or a registration could not continue (a covariance that is not positive definite, a bound or a cost that
    is not finite): the message names the iteration and what to change."""
