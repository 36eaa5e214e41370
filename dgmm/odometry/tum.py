"""TUM RGB-D benchmark files (Sturm et al. 2012, cvg.cit.tum.de/data/datasets/rgbd-dataset/file_formats).

- Text files whose ``#`` lines are comments; ``depth.txt`` rows are ``timestamp filename`` (filename relative to
  the sequence folder); ``groundtruth.txt`` and trajectory files rows are ``timestamp tx ty tz qx qy qz qw``, the
  pose of the camera's optical centre in the world, quaternion **scalar-last** (TUM's order; the rest of dgmm is
  scalar-first).
- Depth images are 16-bit PNGs, metres = value / 5000, 0 = no measurement.
- Poses ``(R, t)`` map camera coordinates to the world, ``x_w = R x_c + t``; a trajectory holds one row per frame:
  ``rotations (n_frames, 3, 3)``, ``translations (n_frames, 3)``.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from dgmm.errors import DataError, InputError, needs
from dgmm.files import atomic_open
from dgmm.odometry.depth_png import decode_gray16, encode_gray16
from dgmm.odometry.pixels import parse_intrinsics, sequence_intrinsics
from dgmm.registration import matrix_to_quaternion, quaternion_to_matrix

with needs("odometry"):
    from PIL import Image, UnidentifiedImageError

DEPTH_SCALE = 5000.0
"""TUM depth PNG units per metre (file_formats: "depth images are scaled by a factor of 5000")."""

MAX_TIME_DIFFERENCE = 0.02
"""Largest timestamp difference (s) for two rows to be associated, TUM associate.py's default."""


# ------------------------------------------------------------------------------------------------ poses
@dataclass(frozen=True)
class Trajectory:
    """Timestamped camera poses (camera → world), one row per frame.

    Attributes
    ----------
    timestamps : ndarray of shape (n_frames,)
        Seconds.
    rotations : ndarray of shape (n_frames, 3, 3)
    translations : ndarray of shape (n_frames, 3)
        Camera positions in the world.
    """

    timestamps: np.ndarray
    rotations: np.ndarray
    translations: np.ndarray

    def __post_init__(self):
        n = len(self.timestamps)
        if np.shape(self.rotations) != (n, 3, 3) or np.shape(self.translations) != (n, 3):
            raise InputError(f"trajectory of {n} timestamps needs rotations ({n}, 3, 3) and translations ({n}, 3), "
                             f"got {np.shape(self.rotations)} and {np.shape(self.translations)}")

    def __len__(self):
        return len(self.timestamps)

    def subset(self, indices):
        """The frames at ``indices`` (array-like of ints), in that order."""
        return Trajectory(self.timestamps[indices], self.rotations[indices], self.translations[indices])


# ------------------------------------------------------------------------------------------------ files
def read_rows(path, n_columns):
    """Rows of a TUM text file, comments and blank lines skipped.

    Parameters
    ----------
    path : path-like
    n_columns : int
        Whitespace-separated fields per row (TUM's associate.py also accepts commas; so does this).

    Returns
    -------
    rows : list of list of str
        One list of ``n_columns`` fields per data row, in file order.

    Raises
    ------
    DataError
        The file is missing or a row has another number of fields.
    """
    path = Path(path)
    try:
        lines = path.read_text().splitlines()
    except OSError as exc:
        raise DataError(f"{path}: cannot read ({exc.strerror or exc})") from None
    rows = []
    for number, line in enumerate(lines, start=1):
        fields = line.replace(",", " ").split()
        if not fields or fields[0].startswith("#"):
            continue
        if len(fields) != n_columns:
            raise DataError(f"{path}:{number}: expected {n_columns} fields, got {len(fields)}")
        rows.append(fields)
    return rows


def _floats(path, rows):
    """Rows of numeric fields as a float64 array of shape (n_rows, n_columns), or a DataError naming ``path``."""
    try:
        return np.array(rows, dtype=np.float64).reshape(len(rows), -1)
    except ValueError as exc:
        raise DataError(f"{path}: non-numeric field ({exc})") from None


def read_trajectory(path):
    """Read a TUM trajectory file (``timestamp tx ty tz qx qy qz qw`` rows) as a Trajectory.

    Raises
    ------
    DataError
        Missing file, malformed row, no rows, or a zero quaternion.
    """
    values = _floats(path, read_rows(path, 8))
    if len(values) == 0:
        raise DataError(f"{path}: no poses")
    quaternions = values[:, [7, 4, 5, 6]]  # TUM (qx, qy, qz, qw) -> dgmm's scalar-first (w, x, y, z)
    if np.any(np.linalg.norm(quaternions, axis=1) == 0) or not np.all(np.isfinite(values)):
        raise DataError(f"{path}: zero quaternion or non-finite value")
    return Trajectory(values[:, 0], quaternion_to_matrix(quaternions), values[:, 1:4])


def write_trajectory(path, trajectory, header="estimated trajectory"):
    """Write a Trajectory as a TUM trajectory file (through a temporary file and a rename).

    Parameters
    ----------
    path : path-like
    trajectory : Trajectory
    header : str
        First comment line.
    """
    quaternions = matrix_to_quaternion(trajectory.rotations).reshape(-1, 4)[:, [1, 2, 3, 0]]  # -> TUM x, y, z, w
    table = np.column_stack([trajectory.timestamps, trajectory.translations, quaternions])
    text = f"# {header}\n# timestamp tx ty tz qx qy qz qw\n" + "".join(
        f"{row[0]:.6f} " + " ".join(f"{value:.9f}" for value in row[1:]) + "\n" for row in table)
    with atomic_open(path) as stream:
        stream.write(text.encode())


def associate(first, second, max_difference=MAX_TIME_DIFFERENCE):
    """Pair each timestamp of ``first`` with the nearest one of ``second`` within ``max_difference``.

    TUM's associate.py pairs greedily by increasing difference, each stamp used once; with ground truth at
    100 Hz and depth at 30 Hz the nearest stamp is the greedy choice, which is what this returns.

    Parameters
    ----------
    first : array-like of shape (n_first,)
    second : array-like of shape (n_second,)
        Sorted increasing (TUM files are).
    max_difference : float

    Returns
    -------
    first_indices, second_indices : ndarray of shape (n_pairs,)
        Rows of ``first`` with a partner, in order, and their nearest row of ``second``.
    """
    first, second = np.asarray(first, dtype=np.float64), np.asarray(second, dtype=np.float64)
    if len(second) == 0 or np.any(np.diff(second) < 0):
        raise InputError("associate needs a non-empty, sorted second list of timestamps")
    right = np.minimum(np.searchsorted(second, first), len(second) - 1)
    left = np.maximum(right - 1, 0)
    nearest = np.where(np.abs(second[left] - first) <= np.abs(second[right] - first), left, right)
    keep = np.abs(second[nearest] - first) < max_difference
    return np.flatnonzero(keep), nearest[keep]


def read_depth(path):
    """Read a 16-bit TUM depth PNG as metres (value / 5000, 0 where there is no measurement).

    Returns
    -------
    depth : ndarray of shape (height, width)

    Raises
    ------
    DataError
        The file is missing, not an image, or not 16-bit single-channel.
    """
    try:
        data = Path(path).read_bytes()
        raw = decode_gray16(data, str(path))  # TUM's own frames, fast; others through PIL
        if raw is None:  # read again by PIL, whose errors name the file
            with Image.open(path) as image:
                mode = image.mode
                raw = np.asarray(image)
            if mode not in ("I;16", "I;16B", "I") or raw.ndim != 2:
                raise DataError(f"{path}: not a 16-bit single-channel depth PNG (mode {mode})")
    except (OSError, UnidentifiedImageError, ValueError) as exc:
        raise DataError(f"{path}: cannot read depth PNG ({type(exc).__name__}: {exc})") from None
    return np.true_divide(raw, DEPTH_SCALE, dtype=np.float64)


def write_depth(path, depth):
    """Write depth in metres as a 16-bit TUM PNG (value = round(5000 Z), 0 = no measurement).

    Parameters
    ----------
    path : path-like
    depth : array-like of shape (height, width)
        Metres, 0 for missing; at most 65535 / 5000 ≈ 13.1 m.
    """
    depth = np.asarray(depth, dtype=np.float64)
    if depth.ndim != 2 or not np.all(np.isfinite(depth)) or depth.min() < 0 or depth.max() > 65535 / DEPTH_SCALE:
        raise InputError(f"depth must be a finite 2-D array in [0, {65535 / DEPTH_SCALE}] m")
    with atomic_open(path) as stream:  # Sub-filtered rows, as TUM's: read back fast (dgmm.odometry.depth_png)
        stream.write(encode_gray16(np.rint(depth * DEPTH_SCALE).astype(np.uint16)))


@dataclass(frozen=True)
class TumSequence:
    """A TUM RGB-D sequence folder: its depth frames and, when present, its ground truth.

    One of the two readers of ``dgmm.odometry.sequence.DepthSequence`` (the other reads ROS 2 recordings).

    Attributes
    ----------
    folder : pathlib.Path
    depth_timestamps : ndarray of shape (n_frames,)
    depth_files : tuple of pathlib.Path
        One per frame.
    groundtruth : Trajectory or None
        ``groundtruth.txt`` (or the file given to ``read_sequence``); None when there is none (TUM's validation
        sequences).
    groundtruth_file : pathlib.Path or None
        The file ``groundtruth`` was read from.
    """

    folder: Path
    depth_timestamps: np.ndarray
    depth_files: tuple
    groundtruth: Trajectory | None
    groundtruth_file: Path | None

    camera_frame = "camera"
    """TUM's files name no frame: the depth camera's is ``camera``."""

    @property
    def name(self):
        """The folder's name (``rgbd_dataset_freiburg1_xyz``), which tells the camera."""
        return self.folder.resolve().name

    def __len__(self):
        return len(self.depth_timestamps)

    def depth(self, index):
        """Depth of frame ``index`` in metres, shape (height, width)."""
        return read_depth(self.depth_files[index])

    def depth_frames(self, indices):
        """Depth of each frame of ``indices``, in that order (``DepthSequence``: read one at a time)."""
        return map(self.depth, indices)

    def frame_source(self, index):
        """The depth PNG of frame ``index``."""
        return str(self.depth_files[index])

    def camera(self, intrinsics=None):
        """The depth camera: ``intrinsics`` (``fr1|fr2|fr3|ros|FX,FY,CX,CY``, 640×480) or, by default, the one
        the folder's name tells (``rgbd_dataset_freiburgN_*``: ``dgmm.odometry.pixels.sequence_intrinsics``).

        Returns
        -------
        text : str
        intrinsics : dgmm.odometry.pixels.Intrinsics
        """
        text = intrinsics or sequence_intrinsics(self.name)
        return text, parse_intrinsics(text)


def read_sequence(folder, groundtruth=None):
    """Read a TUM RGB-D sequence folder as published (``depth.txt``, ``depth/*.png``, ``groundtruth.txt``).

    Depth images are read lazily by ``TumSequence.depth``; ``rgb.txt`` is not used.

    Parameters
    ----------
    folder : path-like
    groundtruth : path-like, optional
        A TUM trajectory file to use as ground truth in place of the folder's ``groundtruth.txt``.

    Raises
    ------
    DataError
        The folder or ``depth.txt`` is missing or malformed, or lists no frames; a ground-truth file given that
        cannot be read.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise DataError(f"{folder}: TUM sequence folder not found")
    listing = folder / "depth.txt"
    rows = read_rows(listing, 2)
    if not rows:
        raise DataError(f"{listing}: lists no depth frames")
    timestamps = _floats(listing, [row[:1] for row in rows])[:, 0]
    if groundtruth is None and (folder / "groundtruth.txt").exists():
        groundtruth = folder / "groundtruth.txt"
    groundtruth = None if groundtruth is None else Path(groundtruth)
    return TumSequence(folder, timestamps, tuple(folder / row[1] for row in rows),
                       None if groundtruth is None else read_trajectory(groundtruth), groundtruth)
