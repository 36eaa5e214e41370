"""The ``dgmm`` command line: fit, score, register with, sample and view Gaussian mixtures of meshes and points.

``dgmm COMMAND --help`` describes each command with an example. Inputs are any mesh or point cloud trimesh reads
(ply, obj, off, stl, xyz, ...), read as one of the input kinds of :data:`INPUT_KINDS`; models are ``.npz`` files
(:mod:`dgmm.model_io`). Every error is one line on stderr, ``dgmm: error: ...``, with exit status 2 for bad
usage, bad input and file-system errors (output paths are checked before any work starts), and 1 only for a bug
in dgmm; ``--debug`` adds the traceback. Ctrl-C exits 130. Outputs are written atomically: a failed or
interrupted command leaves none behind.
"""
import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import traceback
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from dgmm import __version__
from dgmm.errors import DataError, DgmmError, FitError, InputError, MissingDependency
from dgmm.variants import INITS, VARIANTS

# numpy, the file readers (trimesh, scipy), the estimator (scikit-learn), registration and the recorders (rerun,
# mcap) are imported by the commands that use them, so that `dgmm --help` and usage errors answer at once.

BAD_INPUT = 2
"""Exit status for bad usage (argparse's own), bad input (any :class:`~dgmm.errors.DgmmError`) and file-system
errors (``OSError``: a file that cannot be read or written)."""

FAILURE = 1
"""Exit status for a bug in dgmm (any other exception)."""

INTERRUPTED = 130
"""Exit status after Ctrl-C (128 + SIGINT, as shells report it)."""

PROGRESS_DELAY = 1.0
"""Seconds a fit runs before its progress bar appears (on a terminal only)."""

_ESTIMATOR_PARAMS = ("n_components", "init", "max_iter", "tol", "reg_covar", "variant", "random_state",
                     "memory_limit")


# ---------------------------------------------------------------------------------------------------------
# Inputs
# ---------------------------------------------------------------------------------------------------------

def _require_file(path):
    """Return ``path`` as a Path, or raise a DataError if it is not an existing file."""
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: no such file")
    return path


def _read_mesh(path):
    """The triangles of a mesh file as a ``trimesh.Trimesh`` (fitted as exact triangles, recorded as a mesh)."""
    import trimesh

    from dgmm.data import load_mesh

    vertices, faces = load_mesh(path)
    return trimesh.Trimesh(vertices, faces, process=False)


def _read_points(path):
    """The vertices (or points) of a file as an ``(n, 3)`` array."""
    from dgmm.data import load_points

    return load_points(path)


def _read_approx(path):
    """The triangles of a mesh file as area-weighted centroids: the paper's approximation (eq. 5)."""
    from dgmm.data import load_mesh
    from dgmm.primitives import Primitives

    return Primitives.from_mesh(*load_mesh(path)).without_covariances()


# kind -> (reader(path) -> data for GaussianMixture.fit and score_primitives, help text)
INPUT_KINDS = {
    "mesh": (_read_mesh, "exact triangles: centroid, area and covariance of each face"),
    "approx": (_read_approx, "area-weighted face centroids, no triangle covariance (the paper's approximation)"),
    "points": (_read_points, "the file's vertices (or points) as points"),
}


def read_input(path, kind=None):
    """Read a mesh or point-cloud file as the primitives of one input kind.

    Parameters
    ----------
    path : str or path-like
    kind : {"mesh", "approx", "points"}, optional
        See :data:`INPUT_KINDS`. By default "mesh" if the file has faces, else "points".

    Returns
    -------
    kind : str
        The kind read.
    data : trimesh.Trimesh, Primitives or ndarray of shape (n_points, 3)

    Raises
    ------
    DataError
        The file is missing, unreadable, or (for "mesh" and "approx") has no faces.
    """
    path = _require_file(path)
    if kind is not None:
        return kind, INPUT_KINDS[kind][0](path)
    try:
        return "mesh", _read_mesh(path)
    except DataError:  # not a mesh: a point cloud, whose own error is the one to show
        return "points", _read_points(path)


# ---------------------------------------------------------------------------------------------------------
# fit
# ---------------------------------------------------------------------------------------------------------

def _progress_bar(total, desc="EM", unit="it"):
    """A tqdm bar (EM iterations by default), on stderr, shown only on a terminal and only for runs that take a
    while."""
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=unit, disable=not sys.stderr.isatty(), delay=PROGRESS_DELAY,
                leave=False)


def _progress_callback(bar):
    """EM callback moving ``bar`` to the current iteration and showing the bound."""
    def advance(iteration, model):
        bar.set_postfix(bound=f"{model.history_[-1]:.6g}", refresh=False)
        bar.update(iteration - bar.n)
    return advance


def _open_recorder(stack, mcap, rrd, params, data, seed):
    """Open the recorders asked for on ``stack``.

    Returns
    -------
    callback : callable(iteration, model) or None
    finish : callable(model) or None
        To call with the fitted model before ``stack`` closes.
    """
    if mcap is None and rrd is None:
        return None, None
    from dgmm.recording import FitRecorder, RerunRecorder  # rerun and mcap: the recording extra

    if mcap is not None:
        recorder = stack.enter_context(FitRecorder(mcap, rrd, params=params, data=data))
        recorder.begin_seed(seed)
        return recorder, recorder.end_seed
    recorder = stack.enter_context(RerunRecorder(rrd))
    recorder.log_input(data)
    return recorder, None


@contextmanager
def _naming(path):
    """Prefix the InputError or FitError raised in the block with the input file it is about."""
    try:
        yield
    except (InputError, FitError) as exc:
        raise type(exc)(f"{path}: {exc}") from None


def _chain(*callbacks):
    """One EM callback calling each of ``callbacks`` that is not None, in order."""
    active = [callback for callback in callbacks if callback is not None]

    def call_all(iteration, model):
        for callback in active:
            callback(iteration, model)
    return call_all


def _fit(args):
    """Fit a mixture to ``args.input``, save it to ``args.output``, optionally record the fit."""
    from dgmm.mixture import GaussianMixture
    from dgmm.model_io import save_model
    from dgmm.primitives import as_primitives

    kind, data = read_input(args.input, args.kind)
    model = GaussianMixture(args.k, init=args.init, max_iter=args.iterations, random_state=args.seed,
                            variant=args.variant, n_jobs=args.jobs)
    if args.memory_limit is not None:
        model.set_params(memory_limit=args.memory_limit * 2**20)
    with _naming(args.input):
        n_prims = len(as_primitives(data))
    params = {"dgmm_version": __version__, "input": str(args.input), "as": kind, "n_prims": n_prims,
              **{name: getattr(model, name) for name in _ESTIMATOR_PARAMS}}
    with ExitStack() as stack:
        bar = stack.enter_context(_progress_bar(args.iterations))
        record, finish = _open_recorder(stack, args.mcap, args.rrd, params, data, args.seed)
        model.set_params(callback=_chain(_progress_callback(bar), record))
        with _naming(args.input):
            model.fit(data)
        if finish is not None:
            finish(model)
        save_model(args.output, model, {**params, "n_iter": model.n_iter_, "converged": model.converged_,
                                        "lower_bound": model.lower_bound_, "history": model.history_})
    print(f"{args.output}: {args.k} components fitted to {n_prims} primitives ({kind}) of {args.input}; "
          f"bound {model.lower_bound_:.6g} after {model.n_iter_} iterations")


def _fit_arguments(parser):
    """Arguments of ``dgmm fit``."""
    parser.add_argument("input", type=Path, metavar="INPUT", help="mesh or point cloud file")
    parser.add_argument("-k", "--components", dest="k", type=_positive_int, required=True, metavar="K",
                        help="number of mixture components")
    parser.add_argument("-o", "--output", type=_output_file, required=True, metavar="MODEL.npz",
                        help="model file to write")
    parser.add_argument("--init", choices=INITS, default="kmeans", help="initialisation (default: %(default)s)")
    _kind_argument(parser)
    parser.add_argument("--iterations", type=_positive_int, default=25, metavar="N",
                        help="maximum EM iterations (default: %(default)s)")
    parser.add_argument("--seed", type=_seed, default=0, metavar="S", help="random seed (default: %(default)s)")
    parser.add_argument("--variant", choices=tuple(VARIANTS), default="textbook",
                        help="EM variant: textbook EM, or the authors' published code (default: %(default)s)")
    parser.add_argument("--jobs", type=_positive_int, default=1, metavar="N",
                        help="threads for EM (same result for any N; default: %(default)s)")
    parser.add_argument("--memory-limit", type=_positive_int, metavar="MB",
                        help="MiB of responsibilities EM may hold at once; larger inputs stream in blocks "
                             "(default: 128)")
    parser.add_argument("--mcap", type=_output_file, metavar="F",
                        help="record every EM iteration to this MCAP file")
    parser.add_argument("--rrd", type=_output_file, metavar="F",
                        help="record the fit to this rerun recording (.rrd)")


# ---------------------------------------------------------------------------------------------------------
# score, register, sample, view
# ---------------------------------------------------------------------------------------------------------

def _score(args):
    """Print the mean log-likelihood of points, or the size-weighted triangle bound of a mesh (eq. 11)."""
    from dgmm.model_io import load_model

    model, _ = load_model(args.model)
    _, data = read_input(args.input, args.kind)
    with _naming(args.input):
        print(repr(model.score_primitives(data)))


def _score_arguments(parser):
    """Arguments of ``dgmm score``."""
    parser.add_argument("model", type=Path, metavar="MODEL", help="model file written by dgmm fit")
    parser.add_argument("input", type=Path, metavar="INPUT", help="mesh or point cloud file")
    _kind_argument(parser)


# method -> function(source points, model, target thunk) -> Registration; only point-to-point methods call target
_METHODS = {
    "p2d": lambda source, model, target: _registration().register_p2d(source, model),
    "icp": lambda source, model, target: _registration().register_icp(source, target()),
    "cpd": lambda source, model, target: _registration().register_cpd(source, target()),
}


def _registration():
    """:mod:`dgmm.registration`, imported when a command registers."""
    import dgmm.registration
    return dgmm.registration


def _register(args):
    """Register points to a model and print the pose as JSON."""
    from dgmm.model_io import load_model

    model, _ = load_model(args.model)
    _, source = read_input(args.points, "points")
    if args.method == "p2d" and (args.target is not None or args.samples is not None):
        raise InputError("--target and --samples are for icp and cpd; p2d registers to the model itself")

    def target():
        """Target points of icp and cpd: ``--target``'s points, or samples of the model."""
        if args.target is not None:
            return read_input(args.target, "points")[1]
        model.random_state = args.seed
        return model.sample(args.samples or len(source))[0]

    result = _METHODS[args.method](source, model, target)
    pose = {
        "method": result.method,
        "rotation": result.rotation.tolist(),
        "translation": result.translation.tolist(),
        "quaternion_wxyz": result.quaternion.tolist(),
        "iterations": result.iterations,
        "converged": result.converged,
        "objective": result.objective,
        "seconds": result.seconds,
    }
    print("{\n" + ",\n".join(f"  {json.dumps(key)}: {json.dumps(value)}" for key, value in pose.items()) + "\n}")


def _register_arguments(parser):
    """Arguments of ``dgmm register``."""
    parser.add_argument("model", type=Path, metavar="MODEL", help="model file written by dgmm fit")
    parser.add_argument("points", type=Path, metavar="POINTS", help="points to move (the vertices of a mesh file)")
    parser.add_argument("--method", choices=tuple(_METHODS), default="p2d",
                        help="p2d: maximise the points' likelihood under the model; icp, cpd: register the "
                             "points to target points (default: %(default)s)")
    parser.add_argument("--target", type=Path, metavar="FILE",
                        help="icp/cpd: target points (the vertices of a mesh file); default: points sampled "
                             "from the model")
    parser.add_argument("--samples", type=_positive_int, metavar="N",
                        help="icp/cpd without --target: how many points to sample from the model "
                             "(default: as many as POINTS)")
    parser.add_argument("--seed", type=_seed, default=0, metavar="S",
                        help="random seed of the model samples (default: %(default)s)")


def _sample(args):
    """Draw points from a model and write them as a PLY point cloud."""
    from dgmm.data import save_ply
    from dgmm.model_io import load_model

    model, _ = load_model(args.model)
    model.random_state = args.seed
    points, _ = model.sample(args.n)
    save_ply(args.output, points)
    print(f"{args.output}: {args.n} points sampled from {args.model}")


def _sample_arguments(parser):
    """Arguments of ``dgmm sample``."""
    parser.add_argument("model", type=Path, metavar="MODEL", help="model file written by dgmm fit")
    parser.add_argument("-n", type=_positive_int, required=True, metavar="N", help="number of points")
    parser.add_argument("-o", "--output", type=_output_file, required=True, metavar="OUT.ply",
                        help="PLY file to write")
    parser.add_argument("--seed", type=_seed, default=0, metavar="S", help="random seed (default: %(default)s)")


def viewer_command(path):
    """The command that opens ``path`` in the rerun viewer.

    The ``rerun`` program installed beside this Python (by rerun-sdk, so of the version that wrote dgmm's
    recordings) is preferred over one on ``PATH``.

    Parameters
    ----------
    path : str or path-like
        An existing ``.rrd`` recording (or any file the viewer opens, such as ``.mcap``).

    Returns
    -------
    list of str

    Raises
    ------
    DataError
        ``path`` does not exist.
    MissingDependency
        No ``rerun`` program is installed.
    """
    path = _require_file(path)
    beside = Path(sys.executable).parent / "rerun"
    program = str(beside) if beside.is_file() else shutil.which("rerun")
    if program is None:
        raise MissingDependency("the rerun viewer is not installed: pip install 'dgmm[recording]'")
    return [program, str(path)]


def _view(args):
    """Open a recording in the rerun viewer; the viewer's exit status is the command's."""
    return subprocess.run(viewer_command(args.file), check=False).returncode


def _view_arguments(parser):
    """Arguments of ``dgmm view``."""
    parser.add_argument("file", type=Path, metavar="FILE.rrd", help="rerun recording written by dgmm fit --rrd")


# ---------------------------------------------------------------------------------------------------------
# odometry
# ---------------------------------------------------------------------------------------------------------

ODOMETRY_PROTOCOLS = ("ours", "ours-unit", "authors-patch", "authors-disparity")
"""``dgmm.odometry.protocols.PROTOCOLS``' names, written out: importing it would load the odometry package at start."""


def _odometry(args):
    """Frame-to-frame odometry of a TUM folder or a ROS 2 recording: the trajectory file, optional recordings, the
    metrics as JSON."""
    import tempfile

    from dgmm.odometry import first_frames, open_sequence, run_odometry
    from dgmm.odometry.metrics import drift_metrics
    from dgmm.odometry.pixels import PIXEL_STEP
    from dgmm.odometry.tum import write_trajectory

    sequence = open_sequence(args.sequence, args.depth_topic, args.camera_info_topic, args.groundtruth)
    try:
        camera, intrinsics = sequence.camera(args.intrinsics)
    except InputError as exc:
        raise InputError(f"{exc} with --intrinsics") from None
    n_frames = len(sequence) if args.frames is None else min(args.frames, len(sequence))
    if n_frames < 2:
        raise DataError(f"{args.sequence}: odometry needs at least 2 depth frames, got {n_frames}")
    frames, groundtruth = first_frames(sequence, n_frames, require_groundtruth=False)
    options = dict(intrinsics=intrinsics, variant=args.variant, seed=args.seed, schedule=args.schedule,
                   warm_iter=args.warm_iter or None, protocol=args.protocol, size=args.pixel_size)
    params = {"dgmm_version": __version__, "sequence": sequence.name, "folder": str(args.sequence),
              "depth_topic": args.depth_topic, "method": args.method, "frames": n_frames, "intrinsics": camera,
              "variant": args.variant, "schedule": args.schedule, "warm_iter": args.warm_iter, "seed": args.seed,
              "protocol": args.protocol, "pixel_size": args.pixel_size}
    with ExitStack() as stack:
        bar = stack.enter_context(_progress_bar(n_frames, desc="odometry", unit="frame"))
        recorder = None
        if args.mcap is not None or args.rrd is not None:  # the recorder always writes MCAP: a discarded copy
            from dgmm.recording import OdometryRecorder  # rerun and mcap: the recording extra

            mcap = args.mcap or Path(stack.enter_context(tempfile.TemporaryDirectory())) / "odometry.mcap"
            recorder = stack.enter_context(OdometryRecorder(mcap, args.rrd, params=params, groundtruth=groundtruth,
                                                            intrinsics=intrinsics, camera_frame=sequence.camera_frame,
                                                            pixel_step=PIXEL_STEP))

        def advance(frame):
            bar.update()
            if recorder is not None:
                recorder(frame)
        result = run_odometry(sequence, args.method, frames, callback=advance, **options)
        if recorder is not None:
            recorder.finish(result.trajectory)
        metrics = drift_metrics(result.trajectory, sequence.groundtruth)  # all None without ground truth
        if args.output is not None:
            write_trajectory(args.output, result.trajectory,
                             header=f"dgmm {args.method} odometry of {sequence.name}, intrinsics {camera}")
    seconds = float(result.prepare_seconds.mean() + result.registration_seconds.mean())
    print(json.dumps({"sequence": sequence.name, "method": args.method, "protocol": args.protocol,
                      "pixel_size": args.pixel_size, "variant": args.variant,
                      "intrinsics": camera, "frames": n_frames, **metrics, "seconds_per_frame": seconds,
                      "cpu_seconds_per_frame": float(result.cpu_seconds.mean())}))


def _odometry_arguments(parser):
    """Arguments of ``dgmm odometry``."""
    parser.add_argument("sequence", type=Path, metavar="SEQUENCE",
                        help="TUM RGB-D sequence folder (depth.txt, depth/*.png, optional groundtruth.txt), or a "
                             "ROS 2 recording: an .mcap file or a bag folder (metadata.yaml and its .mcap files)")
    parser.add_argument("--depth-topic", metavar="TOPIC",
                        help="a recording's depth images: sensor_msgs/msg/Image or foxglove.RawImage, 16UC1 (mm) "
                             "or 32FC1 (m)")
    parser.add_argument("--camera-info-topic", metavar="TOPIC",
                        help="a recording's sensor_msgs/msg/CameraInfo, whose K gives the intrinsics (default: the "
                             "camera_info topic beside the depth topic)")
    parser.add_argument("--groundtruth", type=Path, metavar="FILE",
                        help="ground-truth poses (TUM trajectory format) to score the trajectory against (default: "
                             "a TUM folder's groundtruth.txt; without any, ATE and RPE are null)")
    parser.add_argument("--method", choices=("gmm-pixels", "gmm-points", "icp"), default="gmm-pixels",
                        help="GMM of pixel rectangles or of points with D2D registration, or point-to-point ICP on "
                             "2,500 points (default: %(default)s)")
    parser.add_argument("--frames", type=_positive_int, metavar="N", help="use the first N depth frames (default: all)")
    parser.add_argument("--variant", choices=tuple(VARIANTS), default="textbook",
                        help="EM variant: textbook EM, or the authors' published code (default: %(default)s)")
    parser.add_argument("--intrinsics", metavar="fr1|fr2|fr3|ros|FX,FY,CX,CY",
                        help="depth camera (default: a recording's camera info; a TUM folder's name, "
                             "rgbd_dataset_freiburgN_*: ros for freiburg 1 and 2, fr3 for freiburg 3)")
    parser.add_argument("--schedule", default="overlap", metavar="overlap|fast|common-view|reference",
                        help="every frame's EM start, EM iterations and D2D stages: overlap (the sweep's: few EM "
                             "iterations, D2D on what each frame sees and measures of the other), or an alternative "
                             "of the studies: fast (the same mixtures, D2D of the whole mixtures), common-view (both "
                             "frames refitted on their common view: robust under the fastest turns, 5x the CPU) or "
                             "reference (k-means + 25 EM iterations, BFGS) (default: %(default)s)")
    parser.add_argument("--pixel-size", choices=("unit", "area"), default="unit",
                        help="size of a pixel primitive in EM (gmm-pixels, protocol ours): unit (every pixel counts "
                             "once; textbook and the authors' EM are then one algorithm) or area (its footprint, "
                             "the sweep's: textbook EM then drifts more under fast turns) (default: %(default)s)")
    parser.add_argument("--protocol", choices=ODOMETRY_PROTOCOLS, default="ours",
                        help="ours: --schedule, --variant and pixel rectangles sized by their footprint; ours-unit: "
                             "ours with pixels of size 1 under textbook EM; "
                             "authors-patch, authors-disparity: the authors' notebooks (gmm-pixels of size 1, flat "
                             "patch or disparity-box covariance, scikit-learn GaussianMixture(100) defaults, BFGS "
                             "D2D; ~10x the CPU per frame; --schedule and --variant unused; authors-patch also runs "
                             "gmm-points so) (default: %(default)s)")
    parser.add_argument("--warm-iter", type=_seed, default=0, metavar="N",
                        help="EM iterations of every frame after the first, started from the previous frame's "
                             "mixture; 0 fits every frame by its schedule (default: %(default)s; a warm start "
                             "drifts more)")
    parser.add_argument("--seed", type=_seed, default=0, metavar="S", help="random seed (default: %(default)s)")
    parser.add_argument("-o", "--output", type=_output_file, metavar="TRAJECTORY.txt",
                        help="write the estimated trajectory (TUM format, depth timestamps) to this file")
    parser.add_argument("--mcap", type=_output_file, metavar="F",
                        help="record every frame and the trajectories to MCAP")
    parser.add_argument("--rrd", type=_output_file, metavar="F", help="record the run to this rerun recording (.rrd)")


# ---------------------------------------------------------------------------------------------------------
# Parser
# ---------------------------------------------------------------------------------------------------------

def _positive_int(text):
    """argparse type: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer >= 1")
    return value


def _output_file(text):
    """argparse type: a file path to write, checked before any work starts.

    It must not be a directory, and its folder must exist and accept a new file (probed with a temporary file,
    which also catches read-only file systems and missing drives).
    """
    path = Path(text)
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a directory: give a file name")
    folder = path.parent
    if not folder.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r}: folder {str(folder)!r} does not exist")
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise argparse.ArgumentTypeError(f"{text!r}: cannot write in folder {str(folder)!r} ({exc.strerror})")
    return path


def _seed(text):
    """argparse type: a non-negative integer seed."""
    if not text.isdigit():
        raise argparse.ArgumentTypeError(f"{text!r} is not a non-negative integer")
    return int(text)


def _kind_argument(parser):
    """The ``--as`` option shared by the commands that read an input file."""
    kinds = "; ".join(f"{name}: {text}" for name, (_, text) in INPUT_KINDS.items())
    parser.add_argument("--as", dest="kind", choices=tuple(INPUT_KINDS),
                        help=f"how to read INPUT ({kinds}); default: mesh if the file has faces, else points")


@dataclass(frozen=True)
class Command:
    """One subcommand: what it does, an example, its arguments and the function that runs it.

    Attributes
    ----------
    summary : str
    example : str
        Shown under ``--help``.
    add_arguments : callable(argparse.ArgumentParser)
    run : callable(argparse.Namespace) -> int or None
        Returns the exit status; None means 0.
    """

    summary: str
    example: str
    add_arguments: Callable
    run: Callable


COMMANDS = {
    "fit": Command("fit a Gaussian mixture to a mesh or a point cloud and save it",
                   "dgmm fit bunny.ply -k 25 -o bunny.npz --rrd bunny.rrd", _fit_arguments, _fit),
    "score": Command("print the mean log-likelihood of points, or the triangle bound of a mesh, under a model",
                     "dgmm score bunny.npz bunny_points.ply", _score_arguments, _score),
    "register": Command("find the rigid pose x -> R x + t that moves POINTS onto a model; print it as JSON",
                        "dgmm register bunny.npz moved_bunny.ply --method p2d", _register_arguments, _register),
    "sample": Command("draw points from a model into a PLY point cloud",
                      "dgmm sample bunny.npz -n 10000 -o bunny_samples.ply", _sample_arguments, _sample),
    "view": Command("open a rerun recording in the rerun viewer", "dgmm view bunny.rrd", _view_arguments, _view),
    "odometry": Command("frame-to-frame visual odometry of a TUM RGB-D folder or a ROS 2 recording (MCAP); print "
                        "the timings, and ATE and RPE when there is ground truth, as JSON",
                        "dgmm odometry rgbd_dataset_freiburg1_xyz --frames 100 -o trajectory.txt",
                        _odometry_arguments, _odometry),
}


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose usage errors are one line: ``dgmm: error: ... (see 'dgmm fit --help')``."""

    def error(self, message):
        self.exit(BAD_INPUT, f"dgmm: error: {message} (see '{self.prog} --help')\n")


def build_parser():
    """The ``dgmm`` argument parser, one subparser per entry of :data:`COMMANDS`."""
    parser = _Parser(prog="dgmm", description="Fit, score, register with, sample and view Gaussian mixtures of "
                                              "meshes and point clouds (Keselman & Hebert, 2019).",
                     epilog="run 'dgmm COMMAND --help' for a command's options and an example")
    parser.add_argument("--version", action="version", version=f"dgmm {__version__}")
    parser.add_argument("--debug", action="store_true", help="show the traceback of an error")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, command in COMMANDS.items():
        sub = commands.add_parser(name, help=command.summary, description=command.summary,
                                  epilog=f"example:\n  {command.example}",
                                  formatter_class=argparse.RawDescriptionHelpFormatter)
        sub.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                         help="show the traceback of an error")
        command.add_arguments(sub)
        sub.set_defaults(run=command.run)
    return parser


def _describe(exc):
    """One line describing ``exc`` for stderr."""
    if isinstance(exc, OSError) and exc.strerror:  # "x.npz: Is a directory", not "[Errno 21] Is a directory: ..."
        names = [str(name) for name in (exc.filename, exc.filename2) if name is not None]
        text = ": ".join([*names, exc.strerror])
    elif isinstance(exc, (DgmmError, OSError)):
        text = str(exc)
    else:
        text = f"unexpected {type(exc).__name__}: {exc} (run with --debug for the traceback)"
    return " ".join(text.split())


def main(argv=None):
    """Run the ``dgmm`` command line.

    Parameters
    ----------
    argv : list of str, optional
        Arguments after the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        Exit status: 0 on success, :data:`BAD_INPUT` for bad usage, input or files, :data:`INTERRUPTED` after
        Ctrl-C, :data:`FAILURE` for a bug.
    """
    args = build_parser().parse_args(argv)
    try:
        return args.run(args) or 0
    except KeyboardInterrupt:  # outputs are atomic: unwinding to here has discarded the partial ones
        print("dgmm: interrupted", file=sys.stderr)
        return INTERRUPTED
    except Exception as exc:  # every failure becomes one line (and the traceback with --debug)
        if args.debug:
            traceback.print_exc()
        print(f"dgmm: error: {_describe(exc)}", file=sys.stderr)
        return BAD_INPUT if isinstance(exc, (DgmmError, OSError)) else FAILURE


if __name__ == "__main__":
    sys.exit(main())
