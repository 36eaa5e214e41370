"""The lean install: the wheel holds the library alone, its core dependencies fit and score a mesh, and every extra
the library can miss is named in the one-line error its absence raises.

The slow test builds the wheel and the sdist from a copy of the sources, installs the wheel into a new venv (its
core dependencies resolved by pip, nothing inherited from this environment) and runs the library and ``dgmm fit``
there.
"""
import importlib
import shutil
import subprocess
import sys
import tomllib
import zipfile
from email.parser import Parser

import pytest
import trimesh

from dgmm.errors import EXTRAS, MissingDependency, needs
from dgmm.mixture import GaussianMixture

from conftest import REPO, SHARED_DATA

PYPROJECT = tomllib.loads((REPO / "pyproject.toml").read_text())
EXTRA_MODULES = ("snakemake", "rerun", "mcap", "mcap_ros2", "pymeshlab", "matplotlib", "PIL", "isal", "yaml", "pycpd",
                 "jsonschema")
CORE = {"numpy", "scipy", "scikit-learn", "threadpoolctl", "numba", "trimesh", "tqdm"}

LEAN_PROBE = """
import sys
import trimesh
import dgmm
from dgmm.registration import register_p2d
mesh = trimesh.creation.icosphere(subdivisions=2)
gmm = dgmm.GaussianMixture(8, random_state=0).fit(mesh)
print(gmm.score_primitives(mesh))
print(sorted(name for name in {modules!r} if name in sys.modules))
try:
    import dgmm.recording
except dgmm.DgmmError as exc:
    print(exc)
"""


def _requirement_name(text):
    """The project name of a requirement string: ``scikit-learn`` of ``scikit-learn>=1.7; extra == "x"``."""
    return text.split(";")[0].split("[")[0].split("<")[0].split(">")[0].split("=")[0].strip().lower()


def test_every_extra_named_by_an_error_is_in_pyproject_and_make_installs_them_all():
    extras = PYPROJECT["project"]["optional-dependencies"]
    assert set(EXTRAS) <= set(extras)
    assert extras["all"] == [f"dgmm[{','.join(name for name in extras if name in {*EXTRAS, 'workflow'})}]"]
    assert "-e '.[all," in (REPO / "Makefile").read_text()


@pytest.fixture
def fresh_dgmm_modules():
    """Let a test import dgmm's modules anew; its own copies are dropped after it, the session's put back."""
    saved = {name: module for name, module in sys.modules.items() if name.startswith("dgmm.")}
    yield
    for name in [name for name in sys.modules if name.startswith("dgmm.")]:
        del sys.modules[name]
    sys.modules.update(saved)


@pytest.mark.parametrize("missing, module, extra", [
    ("pymeshlab", "dgmm.meshes", "meshes"),
    ("rerun", "dgmm.recording", "recording"),
    ("mcap", "dgmm.recording", "recording"),
    ("PIL", "dgmm.odometry", "odometry"),
    ("isal", "dgmm.odometry.depth_png", "odometry"),
    ("mcap_ros2", "dgmm.odometry.ros2_mcap", "ros2"),
    ("matplotlib", "dgmm.odometry.figure", "figures"),
])
def test_a_missing_extra_is_one_line_naming_it(monkeypatch, fresh_dgmm_modules, missing, module, extra):
    for name in [missing, *(name for name in sys.modules if name.startswith(missing + "."))]:
        monkeypatch.setitem(sys.modules, name, None)  # its imports now fail as if it were not installed
    for name in [name for name in sys.modules if name == module or name.startswith(module + ".")]:
        del sys.modules[name]
    with pytest.raises(MissingDependency) as info:
        importlib.import_module(module)
    assert str(info.value) == f"{EXTRAS[extra][0]}: pip install 'dgmm[{extra}]'"
    assert isinstance(info.value, ImportError) and info.value.name == missing


def test_a_missing_module_of_no_extra_passes_unchanged():
    with pytest.raises(ModuleNotFoundError) as info:
        with needs("meshes"):
            import dgmm_no_such_module  # noqa: F401
    assert not isinstance(info.value, MissingDependency)


def _run(*args, cwd):
    """Run a command of the lean venv; its CompletedProcess (text), failing the test on a non-zero status."""
    run = subprocess.run([str(arg) for arg in args], capture_output=True, text=True, cwd=cwd, timeout=300)
    assert run.returncode == 0, run.stderr
    return run


@pytest.fixture(scope="module")
def dist(tmp_path_factory):
    """The wheel and the sdist, built from a copy of the sources (the repository's own egg-info stays out)."""
    root = tmp_path_factory.mktemp("dist")
    source = root / "source"
    shutil.copytree(REPO / "dgmm", source / "dgmm", ignore=shutil.ignore_patterns("__pycache__"))
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(REPO / name, source / name)
    _run(sys.executable, "-m", "build", "--outdir", root / "out", source, cwd=root)
    return next((root / "out").glob("*.whl")), next((root / "out").glob("*.tar.gz"))


@pytest.mark.slow
def test_the_wheel_holds_the_library_and_requires_only_the_core(dist):
    wheel, sdist = dist
    with zipfile.ZipFile(wheel) as archive:
        names = archive.namelist()
        metadata = Parser().parsestr(archive.read(next(n for n in names if n.endswith(".dist-info/METADATA"))).decode())
    assert {"dgmm/__init__.py", "dgmm/cli.py", "dgmm/mixture.py", "dgmm/registration/p2d.py"} <= set(names)
    assert not [name for name in names if name.startswith(("dgmm/experiments/", "dgmm/runtime/"))]
    requires = metadata.get_all("Requires-Dist")
    assert {_requirement_name(text) for text in requires if "extra ==" not in text} == CORE
    assert set(EXTRAS) | {"all", "workflow"} <= set(metadata.get_all("Provides-Extra"))
    sdist_names = subprocess.run(["tar", "tzf", sdist], capture_output=True, text=True, check=True).stdout.split()
    assert not [name for name in sdist_names if "/dgmm/experiments/" in name or "/dgmm/runtime/" in name]


@pytest.mark.slow
def test_the_lean_install_fits_a_mesh_and_imports_no_extra(dist, tmp_path):
    venv = tmp_path / "venv"
    _run(sys.executable, "-m", "venv", venv, cwd=tmp_path)
    _run(venv / "bin" / "python", "-m", "pip", "install", "--quiet", dist[0], cwd=tmp_path)

    lines = _run(venv / "bin" / "python", "-c", LEAN_PROBE.format(modules=EXTRA_MODULES), cwd=tmp_path).stdout
    bound, imported, recording = lines.splitlines()
    mesh = trimesh.creation.icosphere(subdivisions=2)
    here = GaussianMixture(8, random_state=0).fit(mesh).score_primitives(mesh)
    assert float(bound) == pytest.approx(here, rel=1e-6) and imported == "[]"  # this repository's fit, to rounding
    assert recording == "dgmm.recording needs rerun-sdk and mcap: pip install 'dgmm[recording]'"

    dgmm = venv / "bin" / "dgmm"
    bunny = SHARED_DATA / "stanford" / "bunny_res4.ply"
    fitted = _run(dgmm, "fit", bunny, "-k", 4, "-o", "bunny.npz", cwd=tmp_path).stdout
    assert "4 components fitted to 948 primitives (mesh)" in fitted
    assert float(_run(dgmm, "score", "bunny.npz", bunny, cwd=tmp_path).stdout) > 0
    recorded = subprocess.run([dgmm, "fit", bunny, "-k", "4", "-o", "b.npz", "--rrd", "b.rrd"], capture_output=True,
                              text=True, cwd=tmp_path, timeout=120)
    assert (recorded.returncode, recorded.stderr) == (
        2, "dgmm: error: dgmm.recording needs rerun-sdk and mcap: pip install 'dgmm[recording]'\n")
    assert not (tmp_path / "b.npz").exists()
