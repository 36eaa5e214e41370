"""Sphinx configuration of the dgmm documentation (``make docs`` builds it into ``docs/_build/html``)."""
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))

import dgmm  # noqa: E402  (installed in the project's .venv)
from api_pages import constant_docstring, write_api_pages  # noqa: E402

project = "dgmm"
author = "the dgmm developers"
copyright = "2026, the dgmm developers"  # noqa: A001  (Sphinx's name)
release = version = dgmm.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "config_schema",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
# docs/examples/ holds the gallery's sources; sphinx-gallery turns them into the pages of auto_examples/.
exclude_patterns = ["_build", "examples"]
templates_path = ["_templates"]
myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath", "amsmath"]

# API reference: one page per public package, its names read from the package's __all__ at build time.
write_api_pages(DOCS / "api")
autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"members": True, "member-order": "bysource"}
autodoc_typehints = "none"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "reset_modules": ("matplotlib",),
}

html_theme = "pydata_sphinx_theme"
html_title = "dgmm"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "header_links_before_dropdown": 8,
}
html_show_sourcelink = False


def setup(app):
    app.connect("autodoc-process-docstring", constant_docstring)
