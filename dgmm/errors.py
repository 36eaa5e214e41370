"""One exception family for dgmm: every message names the input and the problem in one line.

Errors that scikit-learn's estimator contract names also derive from the type it expects (``ValueError``,
``TypeError``; ``dgmm.mixture.NotFittedError`` is scikit-learn's ``NotFittedError``, defined beside the estimator
so that this module loads without scikit-learn), so code written for scikit-learn catches them.
A missing optional dependency raises :class:`MissingDependency` (an ``ImportError`` too), naming the pip extra
that installs it (:data:`EXTRAS`).
"""
from contextlib import contextmanager


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


class MissingDependency(DgmmError, ImportError):
    """An optional dependency is not installed: the message names the pip extra that installs it."""


EXTRAS = {
    "meshes": ("dgmm.meshes needs pymeshlab", ("pymeshlab",)),
    "recording": ("dgmm.recording needs rerun-sdk and mcap",
                  ("rerun", "mcap", "mcap_protobuf", "foxglove_schemas_protobuf", "google")),
    "odometry": ("dgmm.odometry needs pillow and isal to read depth PNGs", ("PIL", "isal")),
    "ros2": ("ROS 2 recordings need mcap, mcap-ros2-support and pyyaml", ("mcap", "mcap_protobuf", "mcap_ros2", "yaml")),
    "figures": ("dgmm.odometry.figure needs matplotlib", ("matplotlib",)),
}
"""extra of pyproject.toml -> (what needs it, the modules it installs by import name): the lean install is the core
dependencies alone (fitting, scoring, registration); each extra adds one part of the library."""


@contextmanager
def needs(extra):
    """Turn the block's failed import of one of ``extra``'s modules into a one-line :class:`MissingDependency`,
    ``dgmm.meshes needs pymeshlab: pip install 'dgmm[meshes]'``; any other import error passes unchanged."""
    what, modules = EXTRAS[extra]
    try:
        yield
    except ModuleNotFoundError as exc:
        missing = (exc.name or "").partition(".")[0]
        if missing not in modules:
            raise
        raise MissingDependency(f"{what}: pip install 'dgmm[{extra}]'", name=missing) from None
