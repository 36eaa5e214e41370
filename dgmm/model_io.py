"""Save and load fitted Gaussian mixtures as ``.npz`` files.

A model file is an uncompressed NumPy ``.npz`` archive (read with ``allow_pickle=False``) holding

- ``format_version`` : int scalar, :data:`FORMAT_VERSION`;
- ``weights`` : ``(n_components,)`` component weights, positive, summing to 1;
- ``means`` : ``(n_components, d)``, any dimension ``d``;
- ``covariances`` : in scikit-learn's shape of the covariance type: ``(n_components, d, d)`` full (symmetric),
  ``(d, d)`` tied, ``(n_components, d)`` diagonal, ``(n_components,)`` spherical; positive definite;
- ``covariance_type`` : str scalar, ``full``, ``tied``, ``diag`` or ``spherical`` (a file without it is full: those
  written before it was stored);
- ``params`` : str scalar, a JSON object describing the fit (estimator settings, input, bound, ...).

Files are written to a temporary name beside the target and renamed, so a failed save leaves no partial file.
Every problem found on loading is one :class:`~dgmm.errors.DataError` line naming the file.
"""
import json
import zipfile
from pathlib import Path

import numpy as np

from dgmm.errors import DataError, FitError, InputError
from dgmm.files import atomic_open
from dgmm.mixture import GaussianMixture, _typed_shape

COVARIANCE_TYPES = ("full", "tied", "diag", "spherical")

FORMAT_VERSION = 1
"""Version written by :func:`save_model`; :func:`load_model` reads only this version."""

_WEIGHT_SUM_TOL = 1e-9
_SYMMETRY_RTOL = 1e-10


def save_model(path, model, params=None):
    """Write a fitted mixture and a description of its fit to ``path`` atomically.

    Parameters
    ----------
    path : str or path-like
        Destination; written as given (no ``.npz`` suffix is added). Missing parent folders are created.
    model : GaussianMixture
        A fitted mixture (any object with ``weights_``, ``means_`` and ``covariances_``, and ``covariance_type``
        unless full).
    params : dict, optional
        JSON-serialisable description of the fit, stored as the ``params`` JSON string.

    Raises
    ------
    InputError
        The model is not fitted or ``params`` is not JSON-serialisable.
    """
    path = Path(path)
    if not hasattr(model, "covariances_"):
        raise InputError(f"{path}: cannot save a model that is not fitted")
    try:
        text = json.dumps(params or {}, sort_keys=True, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{path}: fit parameters are not JSON-serialisable ({exc})") from None
    arrays = {
        "format_version": np.array(FORMAT_VERSION),
        "weights": np.asarray(model.weights_, dtype=np.float64),
        "means": np.asarray(model.means_, dtype=np.float64),
        "covariances": np.asarray(model.covariances_, dtype=np.float64),
        "covariance_type": np.array(getattr(model, "covariance_type", "full")),
        "params": np.array(text),
    }
    with atomic_open(path) as out:
        np.savez(out, **arrays)


def _read_arrays(path):
    """Every array of the archive at ``path`` as a dict, or a DataError saying why it cannot be read."""
    if not path.is_file():
        raise DataError(f"{path}: no such model file")
    if not zipfile.is_zipfile(path):
        raise DataError(f"{path}: not a dgmm model file (not an .npz archive)")
    try:
        with np.load(path, allow_pickle=False) as archive:
            return {name: archive[name] for name in archive.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise DataError(f"{path}: not a dgmm model file ({type(exc).__name__}: {exc})") from None


def _check_version(path, arrays):
    """Raise a DataError unless ``arrays`` carries the format version this module reads."""
    version = arrays.get("format_version")
    if version is None or version.shape != () or not np.issubdtype(version.dtype, np.integer):
        raise DataError(f"{path}: not a dgmm model file (no integer format_version)")
    if int(version) != FORMAT_VERSION:
        raise DataError(f"{path}: model format version {int(version)}, this dgmm reads version {FORMAT_VERSION}")


def _check_arrays(path, arrays):
    """Weights, means, covariances and covariance type of ``arrays`` checked for presence, shape and values.

    Returns
    -------
    weights : ndarray of shape (n_components,)
    means : ndarray of shape (n_components, d)
    covariances : ndarray in the covariance type's shape (module docstring)
    covariance_type : str
    """
    missing = [name for name in ("weights", "means", "covariances", "params") if name not in arrays]
    if missing:
        raise DataError(f"{path}: model file lacks {', '.join(missing)}")
    weights, means, covariances = (arrays[name] for name in ("weights", "means", "covariances"))
    covariance_type = str(arrays.get("covariance_type", "full"))
    if covariance_type not in COVARIANCE_TYPES:
        raise DataError(f"{path}: covariance_type must be one of {', '.join(COVARIANCE_TYPES)}, got "
                        f"{covariance_type!r}")
    if weights.ndim != 1 or len(weights) == 0:
        raise DataError(f"{path}: weights must be a non-empty 1-D array, got shape {weights.shape}")
    if means.ndim != 2 or means.shape[1] == 0:
        raise DataError(f"{path}: means must be a 2-D array (n_components, d), got shape {means.shape}")
    n_components, d = len(weights), means.shape[1]
    expected = {"weights": (n_components,), "means": (n_components, d),
                "covariances": _typed_shape(covariance_type, n_components, d)}
    for name, shape in expected.items():
        if arrays[name].shape != shape or not np.issubdtype(arrays[name].dtype, np.floating):
            raise DataError(f"{path}: {name} must be a float array of shape {shape}, got "
                            f"{arrays[name].dtype} {arrays[name].shape}")
        if not np.all(np.isfinite(arrays[name])):
            raise DataError(f"{path}: {name} contains NaN or infinite values")
    if np.any(weights <= 0) or abs(weights.sum() - 1.0) > _WEIGHT_SUM_TOL:
        raise DataError(f"{path}: weights must be positive and sum to 1")
    if covariance_type in ("full", "tied") and not np.allclose(covariances, np.swapaxes(covariances, -1, -2),
                                                               rtol=_SYMMETRY_RTOL, atol=0.0):
        raise DataError(f"{path}: covariances are not symmetric")
    return weights, means, covariances, covariance_type


def _read_params(path, value):
    """The ``params`` JSON object of a model file as a dict."""
    try:
        params = json.loads(str(value))
    except ValueError as exc:
        raise DataError(f"{path}: params is not valid JSON ({exc})") from None
    if not isinstance(params, dict):
        raise DataError(f"{path}: params must be a JSON object, got {type(params).__name__}")
    return params


def load_model(path):
    """Read a model file written by :func:`save_model`.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    model : GaussianMixture
        With ``n_components`` and the fitted attributes ``weights_``, ``means_``, ``covariances_`` and
        ``precisions_cholesky_`` set, ready for ``score``, ``score_primitives``, ``predict`` and ``sample``.
    params : dict
        The description of the fit stored with it.

    Raises
    ------
    DataError
        The file is missing, not a model file, of another format version, or holds arrays of the wrong shape or
        invalid values (non-finite, weights not summing to 1, covariances not positive definite).
    """
    path = Path(path)
    arrays = _read_arrays(path)
    _check_version(path, arrays)
    weights, means, covariances, covariance_type = _check_arrays(path, arrays)
    params = _read_params(path, arrays["params"])
    try:
        return GaussianMixture.from_parameters(weights, means, covariances, covariance_type=covariance_type), params
    except FitError:
        raise DataError(f"{path}: covariances are not positive definite") from None
