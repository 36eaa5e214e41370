"""Atomic file output: a job that fails leaves no partial file behind."""
import os
from contextlib import contextmanager
from pathlib import Path

from dgmm.errors import InputError


def temporary_path(path):
    """Hidden name beside ``path``, unique to this process, to write to before renaming into place."""
    path = Path(path)
    return path.with_name(f".{path.name}.{os.getpid()}.part")


@contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path``; rename it to ``path`` when the block succeeds, delete it if not.

    Examples
    --------
    >>> with atomic_path("table.csv") as partial:  # doctest: +SKIP
    ...     partial.write_text("a,b\\n")
    """
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{path} is a directory: give a file name")
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = temporary_path(path)
    try:
        yield partial
        os.replace(partial, path)
    finally:
        partial.unlink(missing_ok=True)


@contextmanager
def atomic_open(path, mode="wb"):
    """Open a temporary file beside ``path`` for writing; rename it to ``path`` once closed, if the block succeeds.

    Examples
    --------
    >>> with atomic_open("model.npz") as stream:  # doctest: +SKIP
    ...     numpy.savez(stream, weights=weights)
    """
    with atomic_path(path) as partial, open(partial, mode) as stream:
        yield stream
