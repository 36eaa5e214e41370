"""Visual odometry with Gaussian mixtures on TUM RGB-D sequences (paper §V "Visual Odometry").

Conventions, shared by every function in this module:

- **TUM RGB-D files** (Sturm et al. 2012, cvg.cit.tum.de/data/datasets/rgbd-dataset/file_formats): text files
  whose ``#`` lines are comments; ``depth.txt`` rows are ``timestamp filename`` (filename relative to the
  sequence folder); ``groundtruth.txt`` and trajectory files rows are ``timestamp tx ty tz qx qy qz qw``, the pose
  of the camera's optical centre in the world, quaternion **scalar-last** (TUM's order; the rest of dgmm is
  scalar-first). Depth images are 16-bit PNGs, metres = value / 5000, 0 = no measurement.
- **Camera frame**: optical, x right, y down, z forward; pixel ``(u, v)`` is (column, row).
- **Poses** ``(R, t)`` map camera coordinates to the world, ``x_w = R x_c + t``; a trajectory holds one row per
  frame: ``rotations (n_frames, 3, 3)``, ``translations (n_frames, 3)``.
- **Odometry** registers frame ``k+1`` (moving) onto frame ``k`` (fixed); the transform returned maps camera
  ``k+1`` coordinates into camera ``k`` coordinates, i.e. the relative pose ``T_k⁻¹ T_{k+1}``, and the poses are
  composed from the identity at the first frame. Registration starts from the identity, as in the paper.

Methods (paper §V): ``"gmm-pixels"`` fits a K=100 GMM (25 EM iterations) to per-pixel rectangle primitives and
registers with the determinant-free D2D cost; ``"gmm-points"`` does the same with the plain back-projected points;
``"icp"`` runs point-to-point ICP on 2,500 points drawn at random from each frame's back-projection.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image, UnidentifiedImageError

from dgmm.errors import DataError, InputError
from dgmm.files import atomic_open
from dgmm.mixture import GaussianMixture
from dgmm.primitives import Primitives
from dgmm.registration import Registration, kabsch, matrix_to_quaternion, quaternion_to_matrix, register_d2d, \
    register_icp

DEPTH_SCALE = 5000.0
"""TUM depth PNG units per metre (file_formats: "depth images are scaled by a factor of 5000")."""

MAX_TIME_DIFFERENCE = 0.02
"""Largest timestamp difference (s) for two rows to be associated, TUM associate.py's default."""

PIXEL_STEP = 4
"""Back-project every 4th pixel of every 4th row: 640×480 → 160×120 (paper §V)."""


# ------------------------------------------------------------------------------------------------ camera
@dataclass(frozen=True)
class Intrinsics:
    """Pinhole intrinsics in pixels and the image size.

    Attributes
    ----------
    fx, fy, cx, cy : float
    width, height : int
    """

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int

    def rays(self, step=1):
        """Camera-frame rays ``((u − cx)/fx, (v − cy)/fy, 1)`` through every ``step``-th pixel.

        Parameters
        ----------
        step : int
            Pixels ``u = 0, step, 2 step, …`` and ``v`` likewise: the grid ``depth[::step, ::step]``.

        Returns
        -------
        rays : ndarray of shape (n_rows * n_cols, 3)
            Raster order (row-major), ``n_rows = ceil(height / step)``; a point at depth ``Z`` is ``Z * ray``.
        """
        v, u = np.mgrid[0:self.height:step, 0:self.width:step]
        return np.stack([(u.ravel() - self.cx) / self.fx, (v.ravel() - self.cy) / self.fy,
                         np.ones(u.size)], axis=1)


FR3 = Intrinsics(fx=535.4, fy=539.2, cx=320.1, cy=247.6, width=640, height=480)
"""Freiburg 3 depth camera (TUM "Intrinsic Camera Calibration", fr3 images are registered to these)."""


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
        with Image.open(path) as image:
            mode = image.mode
            raw = np.asarray(image)
    except (OSError, UnidentifiedImageError, ValueError) as exc:
        raise DataError(f"{path}: cannot read depth PNG ({type(exc).__name__}: {exc})") from None
    if mode not in ("I;16", "I;16B", "I") or raw.ndim != 2:
        raise DataError(f"{path}: not a 16-bit single-channel depth PNG (mode {mode})")
    return raw.astype(np.float64) / DEPTH_SCALE


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
    image = Image.fromarray(np.rint(depth * DEPTH_SCALE).astype(np.uint16))
    with atomic_open(path) as stream:
        image.save(stream, format="PNG")


@dataclass(frozen=True)
class TumSequence:
    """A TUM RGB-D sequence folder: its depth frames and, when present, its ground truth.

    Attributes
    ----------
    folder : pathlib.Path
    depth_timestamps : ndarray of shape (n_frames,)
    depth_files : tuple of pathlib.Path
        One per frame.
    groundtruth : Trajectory or None
        ``groundtruth.txt``; None when the folder has none (TUM's validation sequences).
    """

    folder: Path
    depth_timestamps: np.ndarray
    depth_files: tuple
    groundtruth: Trajectory | None

    def __len__(self):
        return len(self.depth_timestamps)

    def depth(self, index):
        """Depth of frame ``index`` in metres, shape (height, width)."""
        return read_depth(self.depth_files[index])

    def groundtruth_at_frames(self, max_difference=MAX_TIME_DIFFERENCE):
        """Frame indices with a ground-truth pose within ``max_difference`` s, and those poses.

        Returns
        -------
        frames : ndarray of shape (n_pairs,)
        poses : Trajectory
            Of ``n_pairs`` rows, stamped with the depth timestamps.
        """
        if self.groundtruth is None:
            raise DataError(f"{self.folder}: no groundtruth.txt")
        frames, rows = associate(self.depth_timestamps, self.groundtruth.timestamps, max_difference)
        poses = self.groundtruth.subset(rows)
        return frames, Trajectory(self.depth_timestamps[frames], poses.rotations, poses.translations)


def read_sequence(folder):
    """Read a TUM RGB-D sequence folder as published (``depth.txt``, ``depth/*.png``, ``groundtruth.txt``).

    Depth images are read lazily by ``TumSequence.depth``; ``rgb.txt`` is not used.

    Raises
    ------
    DataError
        The folder or ``depth.txt`` is missing or malformed, or lists no frames.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise DataError(f"{folder}: TUM sequence folder not found")
    listing = folder / "depth.txt"
    rows = read_rows(listing, 2)
    if not rows:
        raise DataError(f"{listing}: lists no depth frames")
    timestamps = _floats(listing, [row[:1] for row in rows])[:, 0]
    groundtruth_file = folder / "groundtruth.txt"
    groundtruth = read_trajectory(groundtruth_file) if groundtruth_file.exists() else None
    return TumSequence(folder, timestamps, tuple(folder / row[1] for row in rows), groundtruth)


# ------------------------------------------------------------------------------------ depth -> primitives
def _grid_depth(depth, intrinsics, step):
    """``depth[::step, ::step]`` flattened, after checking the image matches the intrinsics."""
    depth = np.asarray(depth, dtype=np.float64)
    if depth.shape != (intrinsics.height, intrinsics.width):
        raise InputError(f"depth must have shape ({intrinsics.height}, {intrinsics.width}), got {depth.shape}")
    return depth[::step, ::step].ravel()


def backproject(depth, intrinsics=FR3, step=PIXEL_STEP):
    """Camera-frame points of every ``step``-th pixel with a measurement.

    Parameters
    ----------
    depth : array-like of shape (height, width)
        Metres, 0 = no measurement.
    intrinsics : Intrinsics
    step : int

    Returns
    -------
    points : ndarray of shape (n_valid, 3)
        ``Z ((u − cx)/fx, (v − cy)/fy, 1)`` in raster order, zero-depth pixels dropped.
    """
    z = _grid_depth(depth, intrinsics, step)
    valid = z > 0
    return intrinsics.rays(step)[valid] * z[valid, None]


def _unit_sizes(width_x, width_y):
    return np.ones_like(width_x)


def _area_sizes(width_x, width_y):
    return width_x * width_y


# size -> function(widths in x, widths in y) -> alpha_p
PIXEL_SIZES = {"area": _area_sizes, "unit": _unit_sizes}


def pixel_primitives(depth, intrinsics=FR3, step=PIXEL_STEP, size="area"):
    """Every ``step``-th pixel as a camera-aligned rectangle primitive (paper §V, the uncertainty primitive).

    The pixel block seen at depth ``Z`` covers ``w_x = step Z / fx`` by ``w_y = step Z / fy`` metres; the
    uniform distribution over that rectangle has covariance ``diag(w_x² / 12, w_y² / 12, 0)`` in the camera frame.

    Parameters
    ----------
    depth : array-like of shape (height, width)
        Metres, 0 = no measurement.
    intrinsics : Intrinsics
    step : int
    size : {"area", "unit"}, default="area"
        ``alpha_p``: the paper defines a primitive's size as its extent ``∫_S dS`` (§"Generalization to other
        primitives"), here the footprint area ``w_x w_y``; this also undoes the ``1/Z²`` density of pixels on
        the surface. ``"unit"`` counts every pixel once, as the plain points do.

    Returns
    -------
    Primitives
        ``n_valid`` primitives in raster order, zero-depth pixels dropped.
    """
    if size not in PIXEL_SIZES:
        raise InputError(f"size must be one of {sorted(PIXEL_SIZES)}, got {size!r}")
    points = backproject(depth, intrinsics, step)
    width_x, width_y = step * points[:, 2] / intrinsics.fx, step * points[:, 2] / intrinsics.fy
    covariances = np.zeros((len(points), 3, 3))
    covariances[:, 0, 0] = width_x ** 2 / 12.0
    covariances[:, 1, 1] = width_y ** 2 / 12.0
    return Primitives(points, covariances, PIXEL_SIZES[size](width_x, width_y))


# ---------------------------------------------------------------------------------------------- odometry
def _fit_mixture(prims, rng, n_components, max_iter):
    """A K-component GMM fitted to the frame's primitives (k-means initialisation, seeded by ``rng``)."""
    return GaussianMixture(n_components, max_iter=max_iter, random_state=rng).fit(prims)


def _prepare_pixels(depth, intrinsics, rng, options):
    return _fit_mixture(pixel_primitives(depth, intrinsics, size=options["size"]), rng,
                        options["n_components"], options["max_iter"])


def _prepare_points(depth, intrinsics, rng, options):
    return _fit_mixture(Primitives.from_points(backproject(depth, intrinsics)), rng, options["n_components"],
                        options["max_iter"])


def _prepare_icp(depth, intrinsics, rng, options):
    points = backproject(depth, intrinsics)
    return points[rng.choice(len(points), size=min(options["n_icp_points"], len(points)), replace=False)]


def _register_icp(fixed, moving):
    return register_icp(moving, fixed)


# method -> (prepare(depth, intrinsics, rng, options) -> frame model, register(fixed, moving) -> Registration)
METHODS = {
    "gmm-pixels": (_prepare_pixels, register_d2d),
    "gmm-points": (_prepare_points, register_d2d),
    "icp": (_prepare_icp, _register_icp),
}


@dataclass(frozen=True)
class OdometryFrame:
    """What the odometry loop knows after a frame, handed to ``callback``.

    Attributes
    ----------
    index : int
        Frame index in the sequence.
    timestamp : float
    rotation : ndarray of shape (3, 3)
    translation : ndarray of shape (3,)
        The frame's estimated pose (camera → first camera).
    model : GaussianMixture or ndarray of shape (n_icp_points, 3)
        The frame's mixture, or its ICP points.
    prepare_seconds : float
        Time to build ``model`` (the GMM fit, or the sampling for ICP).
    registration : Registration or None
        This frame registered onto the previous one; None for the first frame.
    """

    index: int
    timestamp: float
    rotation: np.ndarray
    translation: np.ndarray
    model: object
    prepare_seconds: float
    registration: Registration | None


@dataclass(frozen=True)
class Odometry:
    """The result of ``run_odometry``.

    Attributes
    ----------
    method : str
    trajectory : Trajectory
        Estimated poses at the depth timestamps, the first one the identity.
    prepare_seconds : ndarray of shape (n_frames,)
        Per-frame model building time (GMM fit; point sampling for ICP).
    registration_seconds : ndarray of shape (n_frames - 1,)
        Per-frame registration time (``Registration.seconds``).
    registrations : tuple of Registration
        Frame ``k+1`` onto frame ``k``, ``n_frames - 1`` of them.
    """

    method: str
    trajectory: Trajectory
    prepare_seconds: np.ndarray
    registration_seconds: np.ndarray
    registrations: tuple


def run_odometry(sequence, method, frames=None, *, intrinsics=FR3, n_components=100, max_iter=25,
                 size="area", n_icp_points=2500, seed=0, callback=None):
    """Frame-to-frame visual odometry over a TUM sequence (paper §V).

    Each frame's model is built once (a GMM, or ICP's random points) and registered onto the previous frame's
    from the identity; the relative motions are composed into poses.

    Parameters
    ----------
    sequence : TumSequence
    method : {"gmm-pixels", "gmm-points", "icp"}
    frames : array-like of int, optional
        Frame indices to use, in order (e.g. ``range(300)``); all frames when omitted.
    intrinsics : Intrinsics, default=FR3
    n_components, max_iter : int
        GMM size and EM iterations (paper: K=100; 25 iterations).
    size : {"area", "unit"}
        Pixel primitive size for ``"gmm-pixels"`` (see ``pixel_primitives``).
    n_icp_points : int
        Points drawn per frame for ``"icp"`` (paper: 2,500).
    seed : int
        Frame ``k`` draws its k-means initialisation or ICP sample from ``np.random.default_rng([seed, k])``, so
        results do not depend on which frames were processed before.
    callback : callable, optional
        ``callback(frame)`` with an ``OdometryFrame`` after every frame (for logging).

    Returns
    -------
    Odometry
    """
    if method not in METHODS:
        raise InputError(f"method must be one of {sorted(METHODS)}, got {method!r}")
    indices = np.arange(len(sequence)) if frames is None else np.asarray(frames, dtype=int)
    if len(indices) < 2 or indices.min() < 0 or indices.max() >= len(sequence):
        raise InputError(f"odometry needs at least 2 frame indices in 0..{len(sequence) - 1}")
    prepare, register = METHODS[method]
    options = {"n_components": n_components, "max_iter": max_iter, "size": size, "n_icp_points": n_icp_points}
    rotations, translations = [np.eye(3)], [np.zeros(3)]
    previous, prepare_seconds, registrations = None, [], []
    for index in indices:  # sequential by nature: each pose composes the previous one
        start = time.perf_counter()
        model = prepare(sequence.depth(index), intrinsics, np.random.default_rng([seed, int(index)]), options)
        prepare_seconds.append(time.perf_counter() - start)
        registration = None if previous is None else register(previous, model)
        if registration is not None:  # T_{k+1} = T_k (T_k⁻¹ T_{k+1})
            registrations.append(registration)
            translations.append(rotations[-1] @ registration.translation + translations[-1])
            rotations.append(rotations[-1] @ registration.rotation)
        if callback is not None:
            callback(OdometryFrame(int(index), float(sequence.depth_timestamps[index]), rotations[-1],
                                   translations[-1], model, prepare_seconds[-1], registration))
        previous = model
    trajectory = Trajectory(sequence.depth_timestamps[indices], np.array(rotations), np.array(translations))
    return Odometry(method, trajectory, np.array(prepare_seconds), np.array([r.seconds for r in registrations]),
                    tuple(registrations))


# ------------------------------------------------------------------------------------------------ metric
@dataclass(frozen=True)
class TrajectoryError:
    """Absolute trajectory error after a rigid alignment (TUM's ATE, no scale).

    Attributes
    ----------
    rmse : float
        Root mean square of ``errors``, metres.
    errors : ndarray of shape (n_pairs,)
        Distance of each aligned estimated position to its ground-truth position.
    rotation : ndarray of shape (3, 3)
    translation : ndarray of shape (3,)
        The alignment ``x -> R x + t`` applied to the estimated positions.
    timestamps : ndarray of shape (n_pairs,)
        Estimated-trajectory timestamps that found a ground-truth partner.
    """

    rmse: float
    errors: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray
    timestamps: np.ndarray


def absolute_trajectory_error(estimate, reference, max_difference=MAX_TIME_DIFFERENCE):
    """ATE RMSE of an estimated trajectory against ground truth (Sturm et al. 2012, eq. 7 and 8).

    Estimated poses are paired with the nearest ground-truth timestamp within ``max_difference``; the estimated
    positions are rigidly aligned to their partners by the closed-form least-squares fit (Horn/Umeyama without
    scale, ``dgmm.registration.kabsch``), and the RMSE of the remaining position differences is returned.

    Parameters
    ----------
    estimate, reference : Trajectory
    max_difference : float

    Returns
    -------
    TrajectoryError

    Raises
    ------
    InputError
        Fewer than 3 pairs (the alignment is not determined).
    """
    first, second = associate(estimate.timestamps, reference.timestamps, max_difference)
    if len(first) < 3:
        raise InputError(f"only {len(first)} estimated poses have a ground-truth pose within {max_difference} s")
    est, ref = estimate.translations[first], reference.translations[second]
    rotation, translation = kabsch(est, ref)
    errors = np.linalg.norm(est @ rotation.T + translation - ref, axis=1)
    return TrajectoryError(float(np.sqrt(np.mean(errors ** 2))), errors, rotation, translation,
                           estimate.timestamps[first])


# ------------------------------------------------------------------------------------------------ tables
def first_frames(sequence, n_frames, max_difference=MAX_TIME_DIFFERENCE):
    """The first ``n_frames`` frames of a sequence (all of them when it is shorter) and their ground truth.

    Parameters
    ----------
    sequence : TumSequence
    n_frames : int
    max_difference : float

    Returns
    -------
    frames : ndarray of shape (n_used,)
        ``0, 1, …, min(n_frames, len(sequence)) − 1``.
    groundtruth : Trajectory
        Ground truth of those frames that have a partner within ``max_difference`` s, stamped with their depth
        timestamps.

    Raises
    ------
    DataError
        The sequence has no ``groundtruth.txt``, or fewer than 3 of the frames have a ground-truth pose (the ATE
        alignment would not be determined); the message names the file.
    """
    frames = np.arange(min(int(n_frames), len(sequence)))
    matched, poses = sequence.groundtruth_at_frames(max_difference)
    keep = matched < len(frames)
    if keep.sum() < 3:
        raise DataError(f"{sequence.folder / 'groundtruth.txt'}: only {int(keep.sum())} of the first {len(frames)} "
                        f"depth frames have a ground-truth pose within {max_difference} s")
    return frames, poses.subset(np.flatnonzero(keep))


def frame_seconds(odometry):
    """Per-frame timings of a run as table rows.

    Returns
    -------
    rows : list of dict
        One per frame: ``frame`` (position in the run), ``timestamp``, ``model_seconds`` (GMM fit, or ICP's
        point sample) and ``registration_seconds`` (onto the previous frame; ``""`` for the first frame).
    """
    registration = ["", *odometry.registration_seconds.tolist()]
    return [{"frame": index, "timestamp": f"{timestamp:.6f}", "model_seconds": float(model),
             "registration_seconds": registered}
            for index, (timestamp, model, registered) in enumerate(
                zip(odometry.trajectory.timestamps, odometry.prepare_seconds, registration))]


def seconds_summary(rows):
    """Mean timings of one run from its ``frame_seconds`` rows (numbers or the strings of a CSV file).

    Returns
    -------
    summary : dict
        ``frames``; ``mean_model_seconds`` (over frames), ``mean_registration_seconds`` (over registrations) and
        ``mean_seconds_per_frame``, their sum: the cost of adding one frame to the trajectory.
    """
    model = [float(row["model_seconds"]) for row in rows]
    registration = [float(row["registration_seconds"]) for row in rows if row["registration_seconds"] != ""]
    if not model or not registration:
        raise InputError(f"timings of {len(rows)} frames: need at least one registration")
    mean_model, mean_registration = float(np.mean(model)), float(np.mean(registration))
    return {"frames": len(model), "mean_seconds_per_frame": mean_model + mean_registration,
            "mean_model_seconds": mean_model, "mean_registration_seconds": mean_registration}
