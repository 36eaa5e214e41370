"""Write one API reference page per public package, listing the names of its ``__all__`` with autosummary.

The pages are generated at every build (and git-ignored), so they follow the code: a name added to or removed from
a package's ``__all__`` appears in or leaves the reference without editing the docs.
"""
import importlib
import inspect
import pkgutil

from sphinx.pycode import ModuleAnalyzer

# The public packages, each a page: its docstring, then a table of its names linking to one page per name.
PACKAGES = ["dgmm", "dgmm.registration", "dgmm.recording", "dgmm.odometry"]
# Modules documented beside the packages (whole-module pages): the tools the user guide names.
MODULES = [
    "dgmm.data",  # The model registry: mesh files, their checksums and sources.
    "dgmm.meshes",  # Poisson-disk and Monte-Carlo sampling, quadric and clustering decimation (pymeshlab).
    "dgmm.model_io",  # Saving and loading fitted mixtures (.npz).
    "dgmm.odometry.synthetic",  # The synthetic TUM-format room sequence (imported on its own: trimesh).
    "dgmm.odometry.figure",  # Fig 7, the top-down trajectories (imported on its own: matplotlib).
    "dgmm.odometry.ros2_mcap",  # ROS 2 recordings in MCAP as depth sequences (imported on its own: mcap).
]


def public_names(module):
    """``module.__all__``, else the public classes and functions the module defines itself."""
    names = getattr(module, "__all__", None)
    if names is not None:
        return sorted(names, key=str.lower)
    return sorted((name for name, value in vars(module).items()
                   if not name.startswith("_") and (inspect.isclass(value) or inspect.isfunction(value))
                   and getattr(value, "__module__", None) == module.__name__), key=str.lower)


def _package_page(name):
    module = importlib.import_module(name)
    lines = [name, "=" * len(name), "", f".. automodule:: {name}", "   :no-members:", "",
             f".. currentmodule:: {name}", "", ".. autosummary::", "   :toctree: generated/", ""]
    lines += [f"   {entry}" for entry in public_names(module)]
    return "\n".join(lines) + "\n"


def _modules_page():
    title = "Other modules"
    lines = [title, "=" * len(title), "", "Modules the user guide refers to by name.", "",
             ".. autosummary::", "   :toctree: generated/", ""]
    lines += [f"   {name}" for name in MODULES]
    return "\n".join(lines) + "\n"


def write_api_pages(folder):
    """Write ``<package>.rst`` for every package of :data:`PACKAGES` and ``modules.rst`` into ``folder``."""
    pages = {f"{name}.rst": _package_page(name) for name in PACKAGES}
    pages["modules.rst"] = _modules_page()
    for filename, text in pages.items():
        path = folder / filename
        if not path.exists() or path.read_text() != text:  # unchanged pages keep their time: no rebuild
            path.write_text(text)


def constant_docstring(app, what, name, obj, options, lines):
    """``autodoc-process-docstring``: a constant a package re-exports gets the docstring written under its assignment
    in the submodule that defines it, not the docstring of its type (``tuple``'s "Built-in immutable sequence")."""
    if what != "data" or inspect.getdoc(obj) != inspect.getdoc(type(obj)):
        return
    package_name, _, attribute = name.rpartition(".")
    package = importlib.import_module(package_name)
    for info in pkgutil.iter_modules(getattr(package, "__path__", [])):
        docs = ModuleAnalyzer.for_module(f"{package_name}.{info.name}").find_attr_docs()
        if ("", attribute) in docs:
            lines[:] = list(docs[("", attribute)])
            return
    lines.clear()
