"""The package's three floors, read from its imports: the library (``dgmm.*``) imports neither the paper's experiments
(``dgmm.experiments``) nor the workflow's runtime (``dgmm.runtime``); the runtime does not import the experiments; and
neither imports the workflow's job scripts (``workflow/scripts/``) or Snakemake's script API. The experiments build
on the library and write their tables through the runtime's tidy CSVs (``dgmm.runtime.tables``).

Every ``import`` and ``from … import`` is read with :mod:`ast`, at module level or inside a function (the library
imports its heavy dependencies lazily), relative ones resolved against the importing module.
"""
import ast

import pytest

from conftest import REPO

EXPERIMENTS, RUNTIME = "dgmm.experiments", "dgmm.runtime"
JOB_SCRIPTS = frozenset(path.stem for path in (REPO / "workflow" / "scripts").glob("*.py"))
MAX_TOP_LEVEL_MODULES = 13


def module_name(path, root):
    """``dgmm.a.b`` for ``root/dgmm/a/b.py`` (``dgmm.a`` for ``root/dgmm/a/__init__.py``)."""
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported_names(path, name):
    """The absolute names of the modules ``path`` (module ``name``) imports, anywhere in its code."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module
            names.add(module)
            names.update(f"{module}.{alias.name}" for alias in node.names)  # `from dgmm import experiments`
    return names


def within(name, prefix):
    return name == prefix or name.startswith(prefix + ".")


def floor(name):
    return next((prefix for prefix in (EXPERIMENTS, RUNTIME) if within(name, prefix)), "library")


def layer_violations(root):
    """``module imports name (rule)`` for every import of the package under ``root/dgmm`` that crosses a floor
    the wrong way."""
    violations = []
    for path in sorted((root / "dgmm").rglob("*.py")):
        name = module_name(path, root)
        for imported in sorted(imported_names(path, name)):
            if floor(name) == "library" and (within(imported, EXPERIMENTS) or within(imported, RUNTIME)):
                violations.append(f"{name} imports {imported} (the library imports no other floor)")
            elif floor(name) == RUNTIME and within(imported, EXPERIMENTS):
                violations.append(f"{name} imports {imported} (the runtime imports no experiment)")
            elif imported.split(".")[0] in JOB_SCRIPTS or within(imported, "snakemake.script"):
                violations.append(f"{name} imports {imported} (no module imports the workflow's job scripts)")
    return violations


def test_no_module_imports_across_floors():
    assert layer_violations(REPO) == []


# Within the library: the numba kernels sit below the code that calls them, the recorders beside the odometry.
BELOW = {"dgmm.compiled": ("dgmm.mixture", "dgmm.registration", "dgmm.odometry", "dgmm.recording"),
         "dgmm.recording": ("dgmm.odometry",)}


def test_the_kernels_and_the_recorders_import_nothing_above_them():
    upward = [f"{name} imports {imported}" for path in sorted((REPO / "dgmm").rglob("*.py"))
              for name in [module_name(path, REPO)] for lower, uppers in BELOW.items() if within(name, lower)
              for imported in sorted(imported_names(path, name)) if any(within(imported, up) for up in uppers)]
    assert upward == []


def kernel_imports(root):
    """``module imports name`` for every import of the library by a module of ``root/dgmm/compiled``: numba's cache
    checks only the file of the function it compiled, so a kernel calling another module's kernel would run that
    callee's stale compiled code after an edit (each module holds everything its kernels call)."""
    return [f"{name} imports {imported}" for path in sorted((root / "dgmm" / "compiled").glob("*.py"))
            for name in [module_name(path, root)]
            for imported in sorted(imported_names(path, name)) if within(imported, "dgmm")]


def test_each_kernel_module_imports_nothing_of_the_library():
    assert kernel_imports(REPO) == []


def test_a_kernel_module_importing_another_is_named(tmp_path):
    (tmp_path / "dgmm" / "compiled").mkdir(parents=True)
    (tmp_path / "dgmm" / "compiled" / "scoring.py").write_text("import numba\nfrom .e_step import screen_block\n")
    assert kernel_imports(tmp_path) == ["dgmm.compiled.scoring imports dgmm.compiled.e_step",
                                        "dgmm.compiled.scoring imports dgmm.compiled.e_step.screen_block"]


def test_the_top_level_holds_the_library_s_modules_and_the_floors():
    top = sorted(path.name for path in (REPO / "dgmm").glob("*.py"))
    packages = sorted(path.name for path in (REPO / "dgmm").iterdir() if (path / "__init__.py").is_file())
    assert len(top) <= MAX_TOP_LEVEL_MODULES, top
    assert {"experiments", "runtime", "registration", "odometry", "recording"} <= set(packages)


@pytest.mark.parametrize("module, source, crossing", [
    ("mixture.py", "import dgmm.experiments.sweep\n", "dgmm.experiments.sweep"),
    ("odometry/loop.py", "def f():\n    from dgmm.runtime.tables import write_csv\n", "dgmm.runtime.tables"),
    ("odometry/loop.py", "from ..experiments import trials\n", "dgmm.experiments"),
    ("meshes.py", "from dgmm import experiments\n", "dgmm.experiments"),
    ("runtime/tables.py", "from dgmm.experiments.report import build\n", "dgmm.experiments.report"),
    ("experiments/sweep.py", "import fit\n", "fit"),
    ("experiments/sweep.py", "from snakemake.script import snakemake\n", "snakemake.script"),
])
def test_a_planted_crossing_is_named(tmp_path, module, source, crossing):
    for package in ("dgmm", "dgmm/odometry", "dgmm/runtime", "dgmm/experiments"):
        (tmp_path / package).mkdir(parents=True, exist_ok=True)
        (tmp_path / package / "__init__.py").write_text("")
    (tmp_path / "dgmm" / module).write_text(source)
    violations = layer_violations(tmp_path)
    assert len(violations) >= 1 and all(v.startswith(module_name(tmp_path / "dgmm" / module, tmp_path)) for v in
                                        violations)
    assert any(f" imports {crossing} " in v for v in violations), violations


def test_imports_within_a_floor_and_downwards_are_allowed(tmp_path):
    for package in ("dgmm", "dgmm/experiments", "dgmm/runtime"):
        (tmp_path / package).mkdir(parents=True)
        (tmp_path / package / "__init__.py").write_text("")
    (tmp_path / "dgmm" / "experiments" / "sweep.py").write_text("from dgmm.mixture import GaussianMixture\n"
                                                                "from dgmm.runtime.tables import write_csv\n"
                                                                "from . import trials\n")
    (tmp_path / "dgmm" / "runtime" / "tables.py").write_text("from dgmm.files import atomic_path\n")
    assert layer_violations(tmp_path) == []
