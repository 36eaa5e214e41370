"""The model registry: which files the paper's experiments use, where to find them, how to read and write them.

A registry entry names one mesh file, its sha256, the public copy it can be downloaded from and the Stanford page it
comes from. `fetch` looks for the file in the mirror directories, then in the local cache, then downloads it into
the cache; every copy is checked against its sha256 before use. Meshes are read in the file's own units.

Point sets are ``(n_points, 3)`` float arrays, meshes ``(n_vertices, 3)`` float vertices with ``(n_faces, 3)``
integer faces. Files are binary PLY (trimesh), written to a temporary name and renamed so that a failed job
leaves no partial file.
"""
import hashlib
import sys
import urllib.error
import urllib.request
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh
from tqdm import tqdm

from dgmm.errors import DataError
from dgmm.files import atomic_open, atomic_path

STANFORD = "http://graphics.stanford.edu/data/3Dscanrep/"
CREDIT = "Stanford University Computer Graphics Laboratory, The Stanford 3D Scanning Repository"


@dataclass(frozen=True)
class RemoteFile:
    """One registered mesh file.

    Attributes
    ----------
    filename : str
        Name of the file in a mirror directory or in the cache.
    sha256 : str
        Hex digest every copy must match.
    url : str
        Download address of a public copy byte-identical to the registered file.
    source : str
        Page the model originally comes from (credit and licence terms).
    note : str
        What the file is, in one line.
    """

    filename: str
    sha256: str
    url: str
    source: str
    note: str


def _github(repo, commit, path):
    """Raw-content address of ``path`` in ``repo`` at ``commit`` (pinned, so the bytes cannot change)."""
    return f"https://raw.githubusercontent.com/{repo}/{commit}/{path}"


_AUTHORS = ("leonidk/direct_gmm", "6735bef868dc3ba061ca544f5e95ce2fed09f70a")

# model -> mesh kind -> file. "full" is the model's mesh; the bunny also has Stanford's res4 decimation.
REGISTRY = {
    "armadillo": {"full": RemoteFile(
        "armadillo.obj", "fd25edd020bef63a5999073774ef4f0775d6ce96b7b17370e69019585f953508",
        _github("Profactor/continuous-remeshing", "11fd2218ed86f54ee65c9aa536d0a79af36ee947", "data/armadillo.obj"),
        STANFORD, "Stanford Armadillo, MeshLab quadric decimation to 99976 faces, scanner units (about mm)")},
    "bunny": {
        "full": RemoteFile(
            "bunny.ply", "b1acc63bece78444aa2e15bdcc72371a201279b98c6f5d4b74c993d02f0566fe",
            _github(*_AUTHORS, "bunny/bun_zipper.ply"),
            STANFORD, "Stanford Bunny bun_zipper.ply as Stanford ships it, metres"),
        "res4": RemoteFile(
            "bunny_res4.ply", "2ca4b1c9206eb2768f10eeb06f30d2dcf576c21f69243335660c896605d1f0ab",
            _github(*_AUTHORS, "bunny/bun_zipper_res4.ply"),
            STANFORD, "Stanford Bunny bun_zipper_res4.ply, Stanford's own decimation (948 faces), metres"),
    },
    "dragon": {"full": RemoteFile(
        "dragon.ply", "edef7a2ed05ee8b4f951c3cf136e8a97a37db8b20bf762987b354a810ab8e615",
        _github("Martincho07/IG-mini-PT", "90ab725c8bb95a9093b3598931e26f4b0e43b371", "models/dragon_vrip_res3.ply"),
        STANFORD, "Stanford Dragon dragon_vrip_res3.ply re-saved by MeshLab, metres")},
    "happy": {"full": RemoteFile(
        "happy.ply", "1ae6755fd78860baae9b54db8720dec506314f5a419b2294dded860f1a99b5ac",
        _github("hummat/hummat.github.io", "5ed66a30cb8aab7cb3c48384eb00034e294e271d", "data/happy_vrip_res3.ply"),
        STANFORD, "Stanford Happy Buddha happy_vrip_res3.ply, metres")},
    "lucy": {"full": RemoteFile(
        "lucy.ply", "c57a95174c3c24d87c1ce8b44f48cbf0a5fcab47ce938880ec2acd497a478eb3",
        _github("pyvista/vtk-data", "113b8b53b8b1f480efa234a93bb7b964b8f906dc", "Data/lucy.ply"),
        STANFORD, "Stanford Lucy, VTK decimation to 99970 faces, millimetres")},
}


def sha256sum(path):
    """Hex sha256 digest of the file at ``path``, read in 1 MiB blocks."""
    digest = hashlib.sha256()
    with open(path, "rb") as stream:
        for block in iter(lambda: stream.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _verified(path, remote, name=None):
    """Return ``path`` if its sha256 matches ``remote``; a mismatch is an error (naming ``name`` or the path)."""
    actual = sha256sum(path)
    if actual != remote.sha256:
        raise DataError(f"{name or path}: sha256 {actual} does not match the registered {remote.sha256}")
    return path


def _download(remote, destination):
    """Download ``remote.url`` to ``destination`` through a temporary file, checking its sha256 before the rename.

    The progress bar (on stderr) is shown only on a terminal.
    """
    with atomic_path(destination) as partial:
        with open(partial, "wb") as out, urllib.request.urlopen(remote.url, timeout=30) as response:
            size = int(response.headers.get("Content-Length") or 0) or None
            with tqdm(total=size, unit="B", unit_scale=True, desc=remote.filename,
                      disable=not sys.stderr.isatty()) as bar:
                for block in iter(lambda: response.read(1 << 16), b""):
                    out.write(block)
                    bar.update(len(block))
        _verified(partial, remote, f"{remote.filename} from {remote.url}")
    return destination


def fetch(remote, mirrors=(), cache=None):
    """Path of a verified local copy of ``remote``: from a mirror, else the cache, else downloaded into the cache.

    Parameters
    ----------
    remote : RemoteFile
        The registered file.
    mirrors : sequence of path-like
        Read-only directories searched first, in order.
    cache : path-like, optional
        Directory of downloaded files; without it nothing is downloaded.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    DataError
        The copy found fails its sha256, or no copy exists and the download fails (the message names the file,
        every directory searched and the URL).
    """
    searched = [Path(d) for d in mirrors] + ([Path(cache)] if cache is not None else [])
    for directory in searched:
        candidate = directory / remote.filename
        if candidate.is_file():
            return _verified(candidate, remote)
    where = ", ".join(str(d) for d in searched) or "no directory"
    if cache is None:
        raise DataError(f"{remote.filename}: not found in {where} and no cache to download {remote.url} into")
    try:
        return _download(remote, Path(cache) / remote.filename)
    except (urllib.error.URLError, OSError) as exc:
        raise DataError(f"{remote.filename}: not found in {where}; download from {remote.url} failed ({exc})") from None


def load_mesh(path):
    """Read a mesh file in its own units, keeping only the vertices its faces use.

    Loaded without trimesh's processing (no merging or reordering), so vertex counts are the file's own minus its
    unreferenced vertices (the original bunny ships 1,113 of them).

    Returns
    -------
    vertices : ndarray of shape (n_vertices, 3)
    faces : ndarray of shape (n_faces, 3)

    Raises
    ------
    DataError
        The file is missing, unreadable, not a triangle mesh, or has no faces.
    """
    try:
        mesh = trimesh.load(path, process=False, force="mesh")
    except Exception as exc:  # trimesh raises many types on bad files; all mean the same to the caller
        raise DataError(f"{path}: cannot read mesh ({type(exc).__name__}: {exc})") from None
    faces = np.asarray(getattr(mesh, "faces", np.empty((0, 3))))
    if faces.ndim != 2 or len(faces) == 0:
        raise DataError(f"{path}: mesh has no faces")
    if faces.shape[1] != 3 or not np.all(np.isfinite(mesh.vertices)):
        raise DataError(f"{path}: not a triangle mesh with finite vertices")
    mesh.remove_unreferenced_vertices()
    return np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int64)


def load_points(path):
    """Read a point set (the vertices of a PLY file) as an ``(n_points, 3)`` float array.

    Raises
    ------
    DataError
        The file is missing, unreadable or holds no finite points.
    """
    try:
        cloud = trimesh.load(path, process=False)
        points = np.asarray(cloud.vertices, dtype=float)
    except Exception as exc:  # as in load_mesh
        raise DataError(f"{path}: cannot read points ({type(exc).__name__}: {exc})") from None
    if points.ndim != 2 or points.shape[1] != 3 or len(points) == 0:
        raise DataError(f"{path}: no 3-D points")
    if not np.all(np.isfinite(points)):
        raise DataError(f"{path}: points contain NaN or infinite coordinates")
    return points


def save_ply(path, vertices, faces=None):
    """Write a mesh, or a point set when ``faces`` is None, as binary PLY through a temporary file and a rename.

    Parameters
    ----------
    path : path-like
    vertices : array-like of shape (n_vertices, 3)
    faces : array-like of shape (n_faces, 3), optional
    """
    if faces is None:
        blob = trimesh.PointCloud(np.asarray(vertices)).export(file_type="ply")
    else:
        blob = trimesh.Trimesh(np.asarray(vertices), np.asarray(faces), process=False).export(file_type="ply")
    with atomic_open(path) as out:
        out.write(blob)
