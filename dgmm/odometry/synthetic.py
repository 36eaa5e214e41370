"""A synthetic TUM RGB-D sequence: ray-cast depth of a small room along a hand-held-like camera path.

Stands in for TUM fr3/long_office_household (paper §VI-D) where the real sequence is absent, in exactly its
format (see ``dgmm.odometry.tum``): ``depth.txt``, ``depth/<timestamp>.png`` (16-bit, metres × 5000, 640×480) and
``groundtruth.txt`` at 100 Hz like TUM's motion capture. No RGB images and no ``rgb.txt`` are written; nothing in
dgmm reads them.

- **Scene**: a room (floor at z = 0, world z up) with furniture-sized boxes and, optionally, scanned models (e.g.
  the Stanford bunny) scaled to ``model_height`` and standing on the table and the cabinet. Scenes are triangle
  soups in (n_triangles, 3, 3) float form.
- **Camera path**: smooth slow sinusoids in position (≈0.3 m/s) and a look-at target, a slow roll, and a small
  jitter of higher-frequency sinusoids (1–4 Hz, mm and tenths of a degree), all phases and frequencies drawn
  from the seed. Ground truth is sampled at 100 Hz; depth frame ``k`` is taken at the 100 Hz sample nearest
  ``k / 30`` s (frame intervals of 30 or 40 ms, 30 Hz on average), so each frame has an exact ground-truth row
  and association by nearest timestamp recovers it.
- **Rendering**: exact ray casting of the pixels ``u, v = 0, step, 2 step, …`` (Möller–Trumbore as three matrix
  products, since all rays of a frame share the optical centre; triangles in groups of 32, each tested only
  against the rays that meet its bounding box). Each ``step × step`` block of the 640×480 image takes its
  top-left pixel's value: with ``step=4`` the 160×120 grid the odometry reads is exact (about 0.035 s of CPU per
  frame for the room and bunny_res4, a third of it the PNG encoder); ``step=1`` renders every pixel, ~16× slower.
- **Kinect noise** (Nguyen, Izadi & Lovell 2012, axial model): ``Z + N(0, σ²)``, ``σ = 0.0012 + 0.0019 (Z −
  0.4)²`` m; 0 (no return) outside [0.4, 4.5] m, at incidence angles above 75°, where no surface is hit, and at
  1% random dropouts; then quantised to the PNG's 1/5000 m.

Every random choice comes from ``np.random.SeedSequence(seed)``: the same seed writes the same bytes.
"""
from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial.transform import Rotation

from dgmm.errors import InputError
from dgmm.odometry.pixels import FR3, PIXEL_STEP
from dgmm.odometry.sequence import groundtruth_at_frames
from dgmm.odometry.tum import Trajectory, read_sequence, write_depth, write_trajectory

TUM_EPOCH = 1341847980.0
"""First timestamp of the sequence (s), of the magnitude of fr3's Unix times, so parsing precision is exercised."""

GROUNDTRUTH_RATE = 100.0
FRAME_RATE = 30.0
ROOM_SIZE = (5.0, 4.0, 2.6)
"""Room extents in x, y, z (m), centred on x = y = 0, floor at z = 0."""

# Furniture as (centre, extents) in metres: a table, a cabinet, a shelf and two boxes.
FURNITURE = (
    ((0.0, 1.2, 0.375), (1.4, 0.8, 0.75)),
    ((-1.9, 1.45, 0.6), (0.8, 0.5, 1.2)),
    ((2.05, 0.5, 0.9), (0.4, 1.2, 1.8)),
    ((0.95, 1.6, 0.2), (0.4, 0.4, 0.4)),
    ((-0.45, 1.35, 0.85), (0.3, 0.25, 0.2)),
)
# Where models stand: (x, y, z of the supporting top), on the table and on the cabinet.
MODEL_SPOTS = ((0.25, 1.1, 0.75), (-1.9, 1.45, 1.2))

MIN_RANGE, MAX_RANGE = 0.4, 4.5
MAX_INCIDENCE_DEG = 75.0
DROPOUT = 0.01


def _box_triangles(centre, extents):
    """The 12 triangles of an axis-aligned box, shape (12, 3, 3)."""
    box = trimesh.creation.box(extents=extents)
    return box.triangles + np.asarray(centre)


def room_scene(models=(), model_height=0.45):
    """Triangles of the room, its furniture and up to two models standing on the table and the cabinet.

    Parameters
    ----------
    models : sequence of array-like of shape (n_triangles, 3, 3)
        Triangle soups with +y up, as the Stanford scans are (e.g. ``vertices[faces]``); each is turned z-up,
        scaled to ``model_height`` and set on ``MODEL_SPOTS`` in order.
    model_height : float
        Metres.

    Returns
    -------
    triangles : ndarray of shape (n_triangles, 3, 3)
    """
    if len(models) > len(MODEL_SPOTS):
        raise InputError(f"room_scene places at most {len(MODEL_SPOTS)} models, got {len(models)}")
    parts = [_box_triangles((0.0, 0.0, ROOM_SIZE[2] / 2), ROOM_SIZE)]
    parts += [_box_triangles(centre, extents) for centre, extents in FURNITURE]
    y_up_to_z_up = Rotation.from_euler("x", 90, degrees=True).as_matrix()
    for model, spot in zip(models, MODEL_SPOTS):
        triangles = np.asarray(model, dtype=np.float64)
        if triangles.ndim != 3 or triangles.shape[1:] != (3, 3) or len(triangles) == 0:
            raise InputError(f"models must be triangle soups of shape (n, 3, 3), got {triangles.shape}")
        vertices = triangles.reshape(-1, 3) @ y_up_to_z_up.T
        low, high = vertices.min(axis=0), vertices.max(axis=0)
        vertices = (vertices - [(low[0] + high[0]) / 2, (low[1] + high[1]) / 2, low[2]]) * (
            model_height / (high[2] - low[2])) + spot
        parts.append(vertices.reshape(-1, 3, 3))
    return np.concatenate(parts)


def _sinusoids(times, amplitudes, frequencies, phases):
    """``Σ_j a_jd sin(2π f_jd t + φ_jd)`` for each time and axis.

    Parameters
    ----------
    times : ndarray of shape (n_times,)
    amplitudes, frequencies, phases : ndarray of shape (n_terms, n_axes)

    Returns
    -------
    values : ndarray of shape (n_times, n_axes)
    """
    angles = 2 * np.pi * times[:, None, None] * frequencies[None] + phases[None]
    return np.einsum("jd,tjd->td", amplitudes, np.sin(angles))


def handheld_trajectory(n_samples, seed=0, rate=GROUNDTRUTH_RATE, start=TUM_EPOCH):
    """A smooth hand-held-like camera path sampled at ``rate``, looking at the table side of the room.

    Parameters
    ----------
    n_samples : int
    seed : int or numpy.random.SeedSequence
    rate : float
        Samples per second.
    start : float
        First timestamp (s).

    Returns
    -------
    Trajectory
        Camera (optical frame: x right, y down, z forward) to world poses, ``n_samples`` rows.
    """
    rng = np.random.default_rng(seed)
    times = np.arange(n_samples) / rate

    def phases(shape):
        return rng.uniform(0, 2 * np.pi, size=shape)

    # Slow sweep: periods 16, 11 and 7 s, amplitudes 0.9, 0.35, 0.15 m (peak speed ≈ 0.35 m/s).
    position = np.array([0.0, -1.1, 1.5]) + _sinusoids(
        times, np.array([[0.9, 0.35, 0.15]]), 1 / np.array([[16.0, 11.0, 7.0]]), phases((1, 3)))
    target = np.array([0.0, 1.2, 0.7]) + _sinusoids(
        times, np.array([[0.7, 0.3, 0.2]]), 1 / np.array([[13.0, 17.0, 9.0]]), phases((1, 3)))
    # Hand jitter: four sinusoids per axis at 1–4 Hz, 2 mm and 0.3° each.
    position += _sinusoids(times, np.full((4, 3), 0.002), rng.uniform(1, 4, size=(4, 3)), phases((4, 3)))
    wobble = _sinusoids(times, np.full((4, 3), np.radians(0.3)), rng.uniform(1, 4, size=(4, 3)), phases((4, 3)))
    wobble[:, 2] += np.radians(4.0) * np.sin(2 * np.pi * times / 10.0 + phases(()))  # slow roll about the view axis
    forward = target - position
    forward /= np.linalg.norm(forward, axis=1, keepdims=True)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right, axis=1, keepdims=True)
    look_at = np.stack([right, np.cross(forward, right), forward], axis=2)  # columns: x right, y down, z forward
    rotations = look_at @ Rotation.from_rotvec(wobble).as_matrix()
    return Trajectory(start + times, rotations, position)


def spinning_trajectory(n_samples, seed=0, rate=GROUNDTRUTH_RATE, start=TUM_EPOCH, peak_deg_s=90.0):
    """A camera standing still in the room, looking at the table and shaken about its optical centre (:func:`spin`).

    Parameters are those of :func:`handheld_trajectory`, and ``peak_deg_s`` the peak rate about each camera axis.

    Returns
    -------
    Trajectory
        ``n_samples`` rows, one position.
    """
    times = np.arange(n_samples) / rate
    position, target = np.array([0.0, -1.1, 1.5]), np.array([0.0, 1.2, 0.7])
    forward = (target - position) / np.linalg.norm(target - position)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    look_at = np.stack([right, np.cross(forward, right), forward], axis=1)
    return Trajectory(start + times, look_at @ spin(times, peak_deg_s, seed), np.tile(position, (n_samples, 1)))


def _triangle_groups(triangles, group_size=32, cell=0.1):
    """Indices of spatially coherent groups of at most ``group_size`` triangles.

    Triangles longer than ``cell`` (walls, furniture faces) come first, together; the rest are ordered by the
    ``cell``-sized grid cell of their centroid, so that each group has a small bounding box.

    Returns
    -------
    groups : list of ndarray of shape (<= group_size,)
    """
    extent = np.ptp(triangles, axis=1).max(axis=1)
    cells = np.floor(triangles.mean(axis=1) / cell)
    order = np.lexsort(np.column_stack([extent <= cell, cells]).T[::-1])
    return [order[start:start + group_size] for start in range(0, len(order), group_size)]


def _slab_hits(axis_rays, origin, low, high):
    """Whether each ray from ``origin`` meets the box ``[low, high]`` (slab test), shape (n_rays,).

    ``axis_rays`` has shape (3, n_rays): the rays' coordinates axis by axis, so the reductions over the three
    slabs run along whole rows (far fewer CPU cycles than along rows of three).
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        near, far = (low - origin)[:, None] / axis_rays, (high - origin)[:, None] / axis_rays
    entry = np.fmax(np.fmin(near, far).max(axis=0), 0.0)
    return np.fmin(np.fmax(near, far).min(axis=0), np.inf) >= entry


def _nearest_hits(rays, origin, triangles, block=2048):
    """Möller–Trumbore for rays sharing one origin: parameter and ``|det|`` of each ray's nearest hit.

    With ``e1, e2`` the edges from ``v0`` and ``s = o − v0``: ``det = d·(e2×e1)``, ``u det = d·(e2×s)``,
    ``v det = d·(s×e1)`` and ``t det = e2·(s×e1)``, so three matrix products serve all rays and triangles. Rays go
    in blocks of ``block``, which keeps the (rays × triangles) arrays in the CPU cache; every ray's arithmetic is
    the same whatever the block.

    Parameters
    ----------
    rays : ndarray of shape (n_rays, 3)
    origin : ndarray of shape (3,)
    triangles : ndarray of shape (n_triangles, 3, 3)
    block : int

    Returns
    -------
    t : ndarray of shape (n_rays,)
        ``origin + t ray`` is the nearest hit; ``inf`` where none.
    cosine : ndarray of shape (n_rays,)
        ``|cos|`` of the angle between the ray and the hit triangle's normal (0 where no hit).
    """
    v0 = triangles[:, 0]
    e1, e2 = triangles[:, 1] - v0, triangles[:, 2] - v0
    s = origin - v0
    q = _cross(s, e1)
    normal = _cross(e2, e1)
    vectors = (normal.T, _cross(e2, s).T, q.T)
    t_det = np.einsum("td,td->t", e2, q)
    t, cosine = np.empty(len(rays)), np.empty(len(rays))
    for start in range(0, len(rays), block):
        t[start:start + block], cosine[start:start + block] = _block_hits(rays[start:start + block], vectors, t_det,
                                                                          normal)
    return t, cosine


def _cross(a, b):
    """Row-wise cross products of (n, 3) arrays: ``np.cross``'s products and differences without its per-call cost."""
    return a[:, [1, 2, 0]] * b[:, [2, 0, 1]] - a[:, [2, 0, 1]] * b[:, [1, 2, 0]]


def _block_hits(rays, vectors, t_det, normal):
    """:func:`_nearest_hits` for one block of rays, given the triangles' ``(e2×e1, e2×s, s×e1)`` and ``t det``."""
    det, u, v = (rays @ vectors_t for vectors_t in vectors)  # u det and v det, made u and v in place
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse = 1.0 / det
        u *= inverse
        v *= inverse
        t = np.multiply(t_det, inverse, out=inverse)
    hit = np.abs(det) > 1e-12
    hit &= u >= 0
    hit &= v >= 0
    hit &= np.add(u, v, out=u) <= 1
    hit &= t > 1e-9
    t[~hit] = np.inf
    nearest = t.argmin(axis=1)
    rows = np.arange(len(rays))
    t = t[rows, nearest]
    cosine = np.abs(det[rows, nearest]) / (np.linalg.norm(normal[nearest], axis=1) * np.linalg.norm(rays, axis=1))
    return t, np.where(np.isfinite(t), cosine, 0.0)


def render_depth(triangles, rotation, translation, intrinsics=FR3, step=PIXEL_STEP):
    """Ray-cast depth ``Z`` and incidence cosine of every ``step``-th pixel (exact nearest hit).

    Triangles are tested in spatially coherent groups of 32, each only against the rays that meet its bounding
    box (a one-level bounding-volume hierarchy); ``_nearest_hits`` does the ray–triangle tests.

    Parameters
    ----------
    triangles : ndarray of shape (n_triangles, 3, 3)
        World coordinates.
    rotation : ndarray of shape (3, 3)
    translation : ndarray of shape (3,)
        Camera-to-world pose.
    intrinsics : Intrinsics
    step : int

    Returns
    -------
    depth : ndarray of shape (n_rays,)
        Camera-frame ``Z`` of the nearest hit (camera rays have unit ``z``, so ``Z`` is the ray parameter),
        ``inf`` where none; raster order of ``intrinsics.rays(step)``.
    cosine : ndarray of shape (n_rays,)
        ``|cos|`` of the angle between the ray and the hit surface's normal (0 where no hit).
    """
    rays = intrinsics.rays(step) @ np.asarray(rotation).T
    axis_rays = np.ascontiguousarray(rays.T)
    origin = np.asarray(translation, dtype=np.float64)
    depth, cosine = np.full(len(rays), np.inf), np.zeros(len(rays))
    for group in _triangle_groups(triangles):  # a few dozen groups, each vectorised over rays × triangles
        members = triangles[group]
        candidates = np.flatnonzero(_slab_hits(axis_rays, origin, members.min(axis=(0, 1)),
                                               members.max(axis=(0, 1))))
        t, group_cosine = _nearest_hits(rays[candidates], origin, members)
        nearer = t < depth[candidates]
        depth[candidates[nearer]] = t[nearer]
        cosine[candidates[nearer]] = group_cosine[nearer]
    return depth, cosine


def kinect_depth(depth, cosine, rng):
    """Kinect-like measurement of exact depths: axial noise growing with Z², missing returns as 0.

    Parameters
    ----------
    depth : ndarray of shape (n_rays,)
        Exact ``Z`` (m), ``inf`` where nothing was hit.
    cosine : ndarray of shape (n_rays,)
        Incidence cosines.
    rng : numpy.random.Generator

    Returns
    -------
    measured : ndarray of shape (n_rays,)
        Metres, 0 where there is no return.
    """
    finite = np.where(np.isfinite(depth), depth, 0.0)
    sigma = 0.0012 + 0.0019 * (finite - 0.4) ** 2  # Nguyen et al. 2012, axial noise for incidence below 60-70°
    measured = finite + sigma * rng.standard_normal(len(depth))
    valid = (np.isfinite(depth) & (depth >= MIN_RANGE) & (depth <= MAX_RANGE)
             & (cosine >= np.cos(np.radians(MAX_INCIDENCE_DEG))) & (rng.uniform(size=len(depth)) >= DROPOUT))
    return np.where(valid, measured, 0.0)


def write_synthetic_sequence(folder, triangles, n_frames=300, seed=0, intrinsics=FR3, step=PIXEL_STEP,
                             path=handheld_trajectory):
    """Render a TUM-format sequence of ``triangles`` into ``folder`` (which must not exist yet).

    Files are written to a temporary folder beside ``folder`` and renamed at the end, so a failure leaves no
    partial sequence.

    Parameters
    ----------
    folder : path-like
    triangles : ndarray of shape (n_triangles, 3, 3)
        The scene, e.g. ``room_scene([bunny_triangles])``.
    n_frames : int
        Depth frames at 30 Hz.
    seed : int
    intrinsics : Intrinsics
    step : int
        Render every ``step``-th pixel and fill ``step × step`` blocks (see the module docstring).
    path : callable, default=handheld_trajectory
        ``path(n_samples, seed=...)`` -> the ground truth at 100 Hz (:func:`handheld_trajectory`,
        :func:`spinning_trajectory`).

    Returns
    -------
    TumSequence
        The written sequence, read back.
    """
    folder = Path(folder)
    if folder.exists():
        raise InputError(f"{folder}: already exists; the synthetic sequence is written to a new folder")
    if int(n_frames) < 1:
        raise InputError(f"n_frames must be >= 1, got {n_frames}")
    triangles = np.asarray(triangles, dtype=np.float64)
    path_seed, *frame_seeds = np.random.SeedSequence(seed).spawn(1 + int(n_frames))
    samples = np.rint(np.arange(int(n_frames)) * GROUNDTRUTH_RATE / FRAME_RATE).astype(int)
    groundtruth = path(samples[-1] + 1, seed=path_seed)
    rows, cols = -(-intrinsics.height // step), -(-intrinsics.width // step)

    def image(sample, frame_seed):
        exact, cosine = render_depth(triangles, groundtruth.rotations[sample], groundtruth.translations[sample],
                                     intrinsics, step)
        measured = kinect_depth(exact, cosine, np.random.default_rng(frame_seed)).reshape(rows, cols)
        return np.repeat(np.repeat(measured, step, axis=0), step, axis=1)[:intrinsics.height, :intrinsics.width]

    return _write_tum_folder(folder, ((groundtruth.timestamps[sample], image(sample, frame_seed))
                                      for sample, frame_seed in zip(samples, frame_seeds)),
                             f"synthetic sequence: dgmm.odometry.synthetic, seed {seed}, {len(triangles)} triangles",
                             groundtruth, f"ground truth trajectory (synthetic, seed {seed})")


def _write_tum_folder(folder, images, description, groundtruth, header):
    """Write a TUM-format sequence to ``folder`` through a temporary folder beside it and a rename, so a failure
    leaves no partial sequence: ``images`` yields ``(timestamp, depth image)``, ``description`` is depth.txt's
    comment line, ``groundtruth`` and ``header`` those of groundtruth.txt. Returns the sequence read back."""
    folder.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", dir=folder.parent))
    try:
        listing = []
        for stamp, image in images:
            name = f"depth/{stamp:.6f}.png"
            write_depth(staging / name, image)
            listing.append(f"{stamp:.6f} {name}\n")
        (staging / "depth.txt").write_text(f"# depth maps\n# {description}\n# timestamp filename\n"
                                           + "".join(listing))
        write_trajectory(staging / "groundtruth.txt", groundtruth, header=header)
        os.rename(staging, folder)
    except BaseException:
        shutil.rmtree(staging)
        raise
    return read_sequence(folder)


def rotated_depth(depth, rotation, intrinsics=FR3):
    """The depth image the same camera sees when turned about its optical centre: ``x_old = R x_new``.

    A pure rotation changes no visibility, so each pixel of the turned camera looks up, along its ray turned into the
    old camera, the nearest old pixel and takes that pixel's surface point in its own coordinates. Used to make
    rotation-heavy odometry cases from real frames (motion beyond what the sequence was recorded with).

    Parameters
    ----------
    depth : array-like of shape (height, width)
        Metres, 0 = no measurement.
    rotation : array-like of shape (3, 3)
        Turned camera → old camera.
    intrinsics : Intrinsics

    Returns
    -------
    depth : ndarray of shape (height, width)
        Metres; 0 where the old image has no measurement or the ray leaves its field of view.
    """
    depth = np.asarray(depth, dtype=np.float64)
    rotation = np.asarray(rotation, dtype=np.float64)
    old_rays = intrinsics.rays() @ rotation.T
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.rint(intrinsics.fx * old_rays[:, 0] / old_rays[:, 2] + intrinsics.cx)
        v = np.rint(intrinsics.fy * old_rays[:, 1] / old_rays[:, 2] + intrinsics.cy)
    inside = (old_rays[:, 2] > 0) & (u >= 0) & (u < intrinsics.width) & (v >= 0) & (v < intrinsics.height)
    u, v = u[inside].astype(int), v[inside].astype(int)
    z_old = depth[v, u]
    old_points = z_old[:, None] * np.column_stack([(u - intrinsics.cx) / intrinsics.fx,
                                                    (v - intrinsics.cy) / intrinsics.fy, np.ones(len(u))])
    turned = np.zeros(intrinsics.width * intrinsics.height)
    turned[np.flatnonzero(inside)] = np.where(z_old > 0, old_points @ rotation[:, 2], 0.0)
    return turned.reshape(intrinsics.height, intrinsics.width)


def spin(timestamps, peak_deg_s=90.0, seed=0):
    """Rotations of a camera shaken about its optical centre: three sinusoids about the camera's axes.

    Each axis turns by ``A sin(2π f t + φ)`` with ``f`` drawn in [1, 2] Hz and the phase at random, and ``A`` such
    that the axis's peak rate is ``peak_deg_s``; the amplitude stays below 15° so the view keeps most of its content.

    Parameters
    ----------
    timestamps : array-like of shape (n_frames,)
        Seconds.
    peak_deg_s : float
        Peak angular rate about each axis (60-120 °/s is a brisk hand-held turn; fr1/xyz's own is about 30).
    seed : int

    Returns
    -------
    rotations : ndarray of shape (n_frames, 3, 3)
        Turned camera → camera (``x_camera = R x_turned``).
    """
    rng = np.random.default_rng(seed)
    times = np.asarray(timestamps, dtype=np.float64) - float(np.min(timestamps))
    frequencies = rng.uniform(1.0, 2.0, size=3)
    amplitudes = np.minimum(np.radians(peak_deg_s) / (2 * np.pi * frequencies), np.radians(15.0))
    phases = rng.uniform(0, 2 * np.pi, size=3)
    rotvecs = amplitudes * np.sin(2 * np.pi * times[:, None] * frequencies + phases)
    return Rotation.from_rotvec(rotvecs).as_matrix()


def write_spun_sequence(folder, sequence, frames, peak_deg_s=90.0, seed=0, intrinsics=FR3):
    """A TUM sequence of real frames with a fast rotation added: each depth image turned by :func:`spin`.

    Frame ``j`` is ``rotated_depth(sequence.depth(j), R_j)`` and its ground truth ``(R G_j, t_j)``, ``(G_j, t_j)``
    the source's; written to ``folder`` (which must not exist) through a temporary folder and a rename.

    Parameters
    ----------
    folder : path-like
    sequence : TumSequence
        With ground truth.
    frames : array-like of int
        Source frames, in order; each must have a ground-truth pose (``dgmm.odometry.sequence.groundtruth_at_frames``).
    peak_deg_s, seed
        See :func:`spin`.
    intrinsics : Intrinsics
        The source's.

    Returns
    -------
    TumSequence
    """
    folder = Path(folder)
    if folder.exists():
        raise InputError(f"{folder}: already exists; the spun sequence is written to a new folder")
    matched, poses = groundtruth_at_frames(sequence)
    rows = np.searchsorted(matched, frames)
    if np.any(rows >= len(matched)) or np.any(matched[np.minimum(rows, len(matched) - 1)] != frames):
        raise InputError("write_spun_sequence: every frame needs a ground-truth pose")
    timestamps = sequence.depth_timestamps[frames]
    turns = spin(timestamps, peak_deg_s, seed)
    truth = poses.subset(rows)
    return _write_tum_folder(folder, ((stamp, rotated_depth(sequence.depth(frame), turn, intrinsics))
                                      for frame, stamp, turn in zip(frames, timestamps, turns)),
                             f"{sequence.folder.name} spun at {peak_deg_s} deg/s "
                             f"(dgmm.odometry.synthetic, seed {seed})",
                             Trajectory(timestamps, truth.rotations @ turns, truth.translations),
                             f"ground truth of {sequence.folder.name}, spun (seed {seed})")
