"""The bad-input contract: one table, the one place where every public entry point and every command adds cases.

A library case calls a public function and expects a :class:`dgmm.DgmmError` subclass whose message is one line
matching a pattern. A CLI case runs the installed ``dgmm`` as a user does (a subprocess) and expects exit status
2, nothing on stdout, exactly one line on stderr (``dgmm: error: ...`` matching a pattern), and no file left in
the output folder (not even a hidden partial one). ``test_every_command_has_cases`` fails when a command is added
to ``dgmm.cli.COMMANDS`` without rows here. Ctrl-C is tested below the table (exit 130, no output left).
"""
import re
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Callable

import numpy as np
import pytest
import trimesh

from dgmm import DataError, DgmmError, FitError, GaussianMixture, InputError, Primitives, cli
from dgmm.data import load_mesh, save_ply
from dgmm.model_io import load_model, save_model
from dgmm.odometry import run_odometry
from dgmm.odometry.ros2_mcap import read_recording
from dgmm.registration import kabsch, random_trials, register_cpd, register_d2d, register_icp, register_p2d
from dgmm.odometry.tum import read_sequence

from conftest import SHARED_DATA
from tests.test_odometry_cli import small_sequence
from tests.test_odometry_mcap import DEPTH, INFO, camera_info, image, write_images

DGMM = str(Path(sys.executable).parent / "dgmm")
BUNNY = SHARED_DATA / "stanford" / "bunny_res4.ply"
UNWRITABLE = Path("/sys")  # exists on Linux and refuses new files, even to root


@dataclass(frozen=True)
class Lib:
    """A library call ``call(inputs)`` that must raise ``error`` with a one-line message matching ``match``."""

    call: Callable
    error: type
    match: str


@dataclass(frozen=True)
class Cli:
    """``dgmm ARGS`` that must fail with exit 2 and one line matching ``match``. In ARGS, ``{i}`` is the folder of
    the shared inputs (see :func:`inputs`) and ``{o}`` an empty output folder that must stay empty."""

    args: tuple
    match: str


def cli_case(*args, match):
    return Cli(tuple(map(str, args)), match)


def fit(*args, match):
    """``dgmm fit`` of the bunny to ``{o}/m.npz`` with the given changes (later options override)."""
    return cli_case("fit", BUNNY, "-k", 2, "-o", "{o}/m.npz", *args, match=match)


def odometry(folder, *args, match):
    """``dgmm odometry`` of one of the broken sequences of :func:`inputs`, writing into ``{o}``."""
    return cli_case("odometry", f"{{i}}/rgbd_dataset_freiburg3_{folder}", "--method", "icp", "-o", "{o}/t.txt",
                    "--rrd", "{o}/o.rrd", *args, match=match)


def recording(name, *args, match):
    """``dgmm odometry`` of one of the broken ROS 2 recordings of :func:`inputs` (depth on ``DEPTH``), writing
    into ``{o}``."""
    return cli_case("odometry", f"{{i}}/{name}", "--depth-topic", DEPTH, "--method", "icp", "-o", "{o}/t.txt",
                    "--mcap", "{o}/o.mcap", *args, match=match)


def points(n=200, seed=0):
    return np.random.default_rng(seed).normal(size=(n, 3))


NAN_POINTS = np.where(np.arange(600).reshape(200, 3) == 7, np.nan, points())
COPLANAR = points() * [1.0, 1.0, 0.0]


CASES = {
    # ---- dgmm.GaussianMixture
    "fit NaN": Lib(lambda c: GaussianMixture(2).fit(NAN_POINTS), InputError, "NaN"),
    "fit coordinates of 1e200": Lib(lambda c: GaussianMixture(2).fit(points() * 1e200), InputError,
                                    "up to .*e\\+200.*rescale the input"),
    "fit spread of 1e-200": Lib(lambda c: GaussianMixture(2).fit(points() * 1e-200), InputError,
                                "RMS radius .*rescale the input"),
    "fit duplicates, reg_covar=0": Lib(lambda c: GaussianMixture(2, reg_covar=0.0).fit(np.ones((20, 3))),
                                       FitError, "initialisation.*duplicate or coplanar primitives need reg_covar"),
    "fit coplanar, reg_covar=0": Lib(lambda c: GaussianMixture(2, reg_covar=0.0, random_state=0).fit(COPLANAR),
                                     FitError, "EM (initialisation|iteration \\d+).*reg_covar > 0"),
    # sqrt(trace) = sqrt(3e306): the diagonals, not the first row, whose entries are 1e306 and 0.5e306 twice
    "fit covariances of 1e306": Lib(lambda c: GaussianMixture(1).fit(Primitives.from_gaussians(
        np.zeros((4, 3)), np.tile(np.full((3, 3), 0.5e306) + 0.5e306 * np.eye(3), (4, 1, 1)), np.ones(4))),
        InputError, "RMS radius about its centre is 1.73e\\+153"),
    "fit reg_covar too large": Lib(lambda c: GaussianMixture(2, reg_covar=1e300).fit(points() * 1e-150),
                                   InputError, "reg_covar=1e\\+300 is too large"),
    "fit K above primitives": Lib(lambda c: GaussianMixture(300).fit(points()), InputError, "larger than"),
    "fit mesh of no area": Lib(lambda c: GaussianMixture(1).fit(Primitives.from_mesh(np.zeros((3, 3)), [[0, 1, 2]])),
                               InputError, "no face of positive area"),
    "score unfitted": Lib(lambda c: GaussianMixture(2).score(points()), InputError, "not fitted"),
    "score NaN": Lib(lambda c: c.model.score(NAN_POINTS), InputError, "NaN"),
    "score points too far": Lib(lambda c: c.model.score(points() + 1e152), InputError, "too far"),
    "score_primitives shape": Lib(lambda c: c.model.score_primitives(np.zeros((4, 2))), InputError,
                                  "X has 2 features, but GaussianMixture is expecting 3"),
    "sample n_samples=0": Lib(lambda c: c.model.sample(0), InputError, "n_samples=0"),
    "from_parameters not positive definite": Lib(
        lambda c: GaussianMixture.from_parameters([1.0], np.zeros((1, 3)), -np.eye(3)[None]), FitError,
        "not positive definite"),
    # ---- dgmm.Primitives
    "primitives negative size": Lib(lambda c: Primitives(points(3), np.zeros((3, 3, 3)), [1, -1, 1]), InputError,
                                    "non-negative"),
    "mesh faces out of range": Lib(lambda c: Primitives.from_mesh(points(3), [[0, 1, 5]]), InputError, "outside"),
    # ---- dgmm.registration
    "p2d NaN source": Lib(lambda c: register_p2d(NAN_POINTS, c.model), InputError, "NaN"),
    "p2d unfitted model": Lib(lambda c: register_p2d(points(), GaussianMixture(2)), InputError, "no fitted"),
    "p2d cost not finite": Lib(lambda c: register_p2d(points() + 1e151, c.model), FitError,
                               "p2d registration: the cost.*finite"),
    "d2d unfitted moving": Lib(lambda c: register_d2d(c.model, GaussianMixture(2)), InputError, "no fitted"),
    "icp empty target": Lib(lambda c: register_icp(points(), np.zeros((0, 3))), InputError, "empty|shape"),
    "cpd NaN target": Lib(lambda c: register_cpd(points(), NAN_POINTS), InputError, "NaN"),
    "kabsch row counts": Lib(lambda c: kabsch(points(5), points(6)), InputError, "as many rows"),
    "random_trials diagonal": Lib(lambda c: random_trials(3, 0, 0.0, np.zeros(3)), InputError, "diagonal"),
    # ---- files
    "load_model not a model": Lib(lambda c: load_model(c.folder / "junk.npz"), DataError, "junk.npz"),
    "save_model to a directory": Lib(lambda c: save_model(c.out, c.model), InputError, "is a directory"),
    "load_mesh missing": Lib(lambda c: load_mesh(c.folder / "missing.ply"), DataError, "missing.ply"),
    "save_ply to a directory": Lib(lambda c: save_ply(c.out, points()), InputError, "is a directory"),
    # ---- odometry
    "read_sequence no listing": Lib(lambda c: read_sequence(c.folder / "rgbd_dataset_freiburg3_nolisting"),
                                    DataError, "depth.txt"),
    "run_odometry unknown method": Lib(
        lambda c: run_odometry(read_sequence(c.folder / "rgbd_dataset_freiburg3_good"), "sift"), DgmmError,
        "sift"),
    # ---- dgmm (no command)
    "no command": cli_case(match="COMMAND"),
    # ---- dgmm fit
    "fit missing input": cli_case("fit", "{i}/missing.ply", "-k", 2, "-o", "{o}/m.npz", match="missing.ply"),
    "fit unreadable input": cli_case("fit", "{i}/junk.ply", "-k", 2, "-o", "{o}/m.npz", match="junk.ply"),
    "fit NaN input": cli_case("fit", "{i}/nan.xyz", "-k", 2, "-o", "{o}/m.npz", match="nan.xyz.*NaN"),
    "fit file of coordinates of 1e200": cli_case("fit", "{i}/huge.xyz", "-k", 2, "-o", "{o}/m.npz",
                                                 match="huge.xyz.*rescale the input"),
    "fit K=0": fit("-k", 0, match="-k/--components"),
    "fit -k above primitives": fit("-k", 100000, match="larger than"),
    "fit output is a directory": fit("-o", "{o}", match="is a directory"),
    "fit output folder missing": fit("-o", "{o}/no/such/m.npz", match="does not exist"),
    "fit output folder unwritable": fit("-o", UNWRITABLE / "m.npz", match="cannot write"),
    "fit --mcap is a directory": fit("--mcap", "{o}", match="--mcap.*is a directory"),
    "fit --rrd folder missing": fit("--rrd", "{o}/no/f.rrd", match="--rrd.*does not exist"),
    # ---- dgmm score
    "score not a model": cli_case("score", "{i}/junk.npz", BUNNY, match="junk.npz"),
    "score file of points too far": cli_case("score", "{i}/model.npz", "{i}/far.xyz", match="far.xyz.*too far"),
    "score NaN input": cli_case("score", "{i}/model.npz", "{i}/nan.xyz", match="nan.xyz.*NaN"),
    # ---- dgmm register
    "register NaN points": cli_case("register", "{i}/model.npz", "{i}/nan.xyz", match="NaN"),
    "register p2d with --target": cli_case("register", "{i}/model.npz", BUNNY, "--target", BUNNY,
                                           match="for icp and cpd"),
    "register missing model": cli_case("register", "{i}/missing.npz", BUNNY, match="missing.npz"),
    # ---- dgmm sample
    "sample n=0": cli_case("sample", "{i}/model.npz", "-n", 0, "-o", "{o}/s.ply", match="-n"),
    "sample output is a directory": cli_case("sample", "{i}/model.npz", "-n", 10, "-o", "{o}", match="directory"),
    "sample output folder unwritable": cli_case("sample", "{i}/model.npz", "-n", 10, "-o", UNWRITABLE / "s.ply",
                                                match="cannot write"),
    # ---- dgmm view
    "view missing recording": cli_case("view", "{i}/missing.rrd", match="missing.rrd"),
    # ---- dgmm odometry
    "odometry missing folder": odometry("missing", match="not found"),
    "odometry no listing": odometry("nolisting", match="depth.txt"),
    "odometry one frame": odometry("oneframe", match="at least 2"),
    "odometry output is a directory": odometry("good", "-o", "{o}", match="is a directory"),
    "odometry --mcap folder missing": odometry("good", "--mcap", "{o}/no/o.mcap", match="does not exist"),
    "odometry bad intrinsics": odometry("good", "--intrinsics", "1,2", match="intrinsics"),
    "odometry recording without --depth-topic": cli_case("odometry", "{i}/good.mcap", "-o", "{o}/t.txt",
                                                         match="good.mcap: .*--depth-topic"),
    "odometry recording missing topic": recording(
        "good.mcap", "--depth-topic", "/nope",
        match=f"good.mcap: no messages on topic /nope \\(topics: {INFO} \\(sensor_msgs/msg/CameraInfo\\), "
              f"{DEPTH} \\(sensor_msgs/msg/Image\\)\\)"),
    "odometry recording of another type": recording("good.mcap", "--depth-topic", INFO,
                                                    match=f"{INFO} message 0: a sensor_msgs/msg/CameraInfo message"),
    "odometry recording unsupported encoding": recording(
        "rgb8.mcap", match=f"rgb8.mcap: {DEPTH} message 1: encoding 'rgb8'; dgmm reads depth images in 16UC1 or 32FC1"),
    "odometry recording of two sizes": recording("sizes.mcap", match="message 2: 6x4 image; message 0 is 8x6"),
    "odometry recording without camera info": recording(
        "noinfo.mcap", match=f"noinfo.mcap: no camera info on {INFO} .*--intrinsics"),
    "odometry recording camera info of another size": recording("infosize.mcap",
                                                                match=f"{INFO}: width x height 4x3, .* 8x6"),
    "odometry recording truncated": recording("truncated.mcap", match="truncated.mcap: .*truncated or corrupt"),
    "odometry recording corrupt": recording("corrupt.mcap", match="corrupt.mcap: .*truncated or corrupt"),
    "odometry bag folder without its .mcap": recording("bag", match="bag_0.mcap: listed in .*metadata.yaml but missing"),
    "odometry recording timestamps backwards": recording(
        "backwards.mcap", match="message 2: header stamp 1.000000000 s is not after .* 2.000000000 s"),
    "odometry --groundtruth missing": recording("good.mcap", "--groundtruth", "{i}/missing.txt",
                                                match="missing.txt"),
    # ---- a recording read by the library
    "read_recording missing topic": Lib(lambda c: read_recording(c.folder / "good.mcap", "/nope"), DataError,
                                        "no messages on topic /nope"),
}


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """Shared inputs in a folder of their own: a fitted model, broken files and TUM folders."""
    folder = tmp_path_factory.mktemp("inputs")
    model = GaussianMixture(3, random_state=0).fit(trimesh.load(BUNNY, process=False))
    save_model(folder / "model.npz", model)
    (folder / "junk.npz").write_bytes(b"not a model")
    (folder / "junk.ply").write_bytes(b"ply\nnot really\n")
    np.savetxt(folder / "nan.xyz", NAN_POINTS)
    np.savetxt(folder / "huge.xyz", points() * 1e200)
    np.savetxt(folder / "far.xyz", points() + 1e152)
    small_sequence(folder / "rgbd_dataset_freiburg3_good")
    small_sequence(folder / "rgbd_dataset_freiburg3_nolisting")
    (folder / "rgbd_dataset_freiburg3_nolisting" / "depth.txt").unlink()
    small_sequence(folder / "rgbd_dataset_freiburg3_oneframe", n_frames=1)
    second = 10**9
    good = write_images(folder / "good.mcap", [image(k * second) for k in (1, 2, 3)], camera_info())
    write_images(folder / "noinfo.mcap", [image(k * second) for k in (1, 2, 3)])
    write_images(folder / "infosize.mcap", [image(k * second) for k in (1, 2, 3)], camera_info(width=4, height=3))
    write_images(folder / "rgb8.mcap", [image(second), image(2 * second, encoding="rgb8", data=bytes(144))])
    write_images(folder / "sizes.mcap", [image(second), image(2 * second), image(3 * second, width=6, height=4)])
    write_images(folder / "backwards.mcap", [image(k * second) for k in (1, 2, 1)], camera_info())
    data = good.read_bytes()
    (folder / "truncated.mcap").write_bytes(data[:len(data) // 2])
    (folder / "corrupt.mcap").write_bytes(data[:len(data) // 3] + bytes([data[len(data) // 3] ^ 0xFF])
                                          + data[len(data) // 3 + 1:])
    (folder / "bag").mkdir()
    (folder / "bag" / "metadata.yaml").write_text(
        "rosbag2_bagfile_information:\n  storage_identifier: mcap\n  relative_file_paths: [bag_0.mcap]\n")
    return SimpleNamespace(folder=folder, model=model)


def listing(folder):
    return sorted(path.relative_to(folder) for path in folder.rglob("*"))


@pytest.mark.parametrize("name", [pytest.param(name, marks=pytest.mark.slow) if isinstance(case, Cli) else name
                                  for name, case in CASES.items()])  # CLI cases start a process each
def test_bad_input_contract(name, inputs, tmp_path):
    case = CASES[name]
    out = tmp_path / "out"
    out.mkdir()
    if isinstance(case, Lib):
        with pytest.raises(case.error) as info:
            case.call(SimpleNamespace(**vars(inputs), out=out))
        assert isinstance(info.value, DgmmError)
        message = str(info.value)
        assert "\n" not in message and re.search(case.match, message), message
    else:
        if UNWRITABLE in map(Path, case.args) and not UNWRITABLE.is_dir():
            pytest.skip(f"{UNWRITABLE} does not exist here")
        args = [arg.format(i=inputs.folder, o=out) for arg in case.args]
        run = subprocess.run([DGMM, *args], capture_output=True, text=True, timeout=300)
        assert run.returncode == cli.BAD_INPUT, run.stderr
        assert run.stdout == ""
        assert run.stderr.startswith("dgmm: error: ") and run.stderr.count("\n") == 1, run.stderr
        assert re.search(case.match, run.stderr), run.stderr
    assert listing(out) == []


def test_every_command_has_cases():
    covered = {case.args[0] for case in CASES.values() if isinstance(case, Cli) and case.args}
    assert covered == set(cli.COMMANDS)


@pytest.mark.slow
def test_ctrl_c_exits_130_and_leaves_no_output(tmp_path):
    """SIGINT once the fit's recordings exist as partial files: exit 130, one line, nothing left behind."""
    args = ["fit", SHARED_DATA / "stanford" / "bunny_res2.ply", "-k", 100, "--init", "random", "--iterations", 100000,
            "-o", tmp_path / "m.npz", "--mcap", tmp_path / "m.mcap", "--rrd", tmp_path / "m.rrd"]
    # SIGINT at its default in the child: a test run started in the background (`make test &`) ignores it, and
    # Python keeps an inherited SIG_IGN instead of raising KeyboardInterrupt.
    run = subprocess.Popen([DGMM, *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 120
    while not any(tmp_path.iterdir()) and run.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert run.poll() is None, run.communicate()
    run.send_signal(signal.SIGINT)
    stdout, stderr = run.communicate(timeout=120)
    assert run.returncode == cli.INTERRUPTED and stdout == "" and stderr == "dgmm: interrupted\n"
    assert listing(tmp_path) == []
