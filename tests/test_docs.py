"""The documentation: ``make docs``'s build runs with no warning, its gallery's examples run and leave their
figures in the site, the API pages name every public name, and no internal link of the site or the README is broken.

Links are checked on the built HTML by parsing it here (every relative ``href`` and ``src`` must name a file of the
site and, with a ``#fragment``, an ``id`` in that file), not by trusting Sphinx's own reference resolution.
"""
import ast
import importlib
import os
import re
import subprocess
import sys
import time
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

from conftest import REPO

DOCS = REPO / "docs"
sys.path.insert(0, str(DOCS / "_ext"))
from api_pages import PACKAGES, public_names  # noqa: E402

SPHINX_BUILD = str(Path(sys.executable).parent / "sphinx-build")
ONE_THREAD = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}  # as make docs
MARKDOWN_LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
STATED_CONSTANT = re.compile(r"`(?P<module>dgmm(?:\.\w+)*)\.(?P<name>_?[A-Z][A-Z0-9_]*)` = (?P<value>[-+0-9.e]+\b)")
MAX_PAGE_BYTES = 30_000


class LinksAndIds(HTMLParser):
    """The relative links (``href``, ``src``) of an HTML page and the ids (``id``, ``name``) it defines."""

    def __init__(self):
        super().__init__()
        self.links, self.ids = [], set()

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        self.ids.update(attrs[key] for key in ("id", "name") if attrs.get(key) and tag != "meta")
        for key in ("href", "src"):
            target = attrs.get(key)
            if target and not urlsplit(target).scheme and not target.startswith("//"):
                self.links.append(target)


def parse(path):
    parser = LinksAndIds()
    parser.feed(path.read_text(encoding="utf-8"))
    return parser


def broken_links(site):
    """``page: link`` for every relative link of ``site`` whose file or fragment does not exist."""
    site = site.resolve()
    pages = {path: parse(path) for path in site.rglob("*.html")}
    themes = site / "_static"  # the theme's own templates, copied as they are
    broken = []
    for page, parsed in pages.items():
        if page.is_relative_to(themes):
            continue
        for link in parsed.links:
            parts = urlsplit(link)
            target = (page.parent / unquote(parts.path)).resolve() if parts.path else page
            if target.is_dir():
                target = target / "index.html"
            if not target.is_file():
                broken.append(f"{page.relative_to(site)}: {link}")
            elif parts.fragment and target.suffix == ".html" and unquote(parts.fragment) not in pages[target].ids:
                broken.append(f"{page.relative_to(site)}: {link} (no such anchor)")
    return broken


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The site built as ``make docs`` builds it (every gallery example run, even if unchanged since the last
    build), into a temporary folder."""
    out = tmp_path_factory.mktemp("docs")
    start = time.perf_counter()
    result = subprocess.run([SPHINX_BUILD, "-W", "--keep-going", "-q", "-b", "html", "-d", str(out / "doctrees"),
                             "-D", "sphinx_gallery_conf.run_stale_examples=1", str(DOCS), str(out / "html")],
                            capture_output=True, text=True, cwd=REPO, timeout=600, env=os.environ | ONE_THREAD)
    assert result.returncode == 0, result.stderr[-5000:]
    print(f"docs built in {time.perf_counter() - start:.0f} s")
    return out / "html"


@pytest.mark.slow  # builds the whole site and runs the gallery (about a minute)
def test_site_has_no_broken_internal_link(site):
    assert (site / "index.html").is_file()
    assert broken_links(site) == []


@pytest.mark.slow
def test_gallery_examples_ran_and_left_their_figures(site):
    examples = sorted(path.stem for path in (DOCS / "examples").glob("plot_*.py"))
    assert len(examples) >= 5
    for name in examples:
        page = (site / "auto_examples" / f"{name}.html").read_text(encoding="utf-8")
        figures = re.findall(rf'src="(\.\./_images/sphx_glr_{name}_\d+\.png)"', page)
        assert figures, f"{name}: no figure in its page"
        assert all((site / "auto_examples" / figure).stat().st_size > 5000 for figure in figures), name
        assert "sphx-glr-script-out" in page, f"{name}: printed nothing"


@pytest.mark.slow
def test_api_reference_lists_every_public_name(site):
    for package in PACKAGES:
        names = public_names(importlib.import_module(package))
        assert names, package
        page = (site / "api" / f"{package}.html").read_text(encoding="utf-8")
        for name in names:
            assert (site / "api" / "generated" / f"{package}.{name}.html").is_file(), f"{package}.{name}"
            assert f'href="generated/{package}.{name}.html' in page, f"{package}.{name} not listed"


def markdown_sources():
    """The README, the docs' markdown pages (not the build's) and the benchmark studies' index."""
    pages = [path for path in DOCS.rglob("*.md") if not {"_build", "auto_examples"} & set(path.parts)]
    return [REPO / "README.md", REPO / "benchmarks" / "studies" / "README.md", *sorted(pages)]


def test_readme_and_docs_sources_link_to_files_that_exist():
    """Plain markdown links of the README and the docs' pages (read on GitHub as well as in the site)."""
    for source in markdown_sources():
        for link in MARKDOWN_LINK.findall(source.read_text(encoding="utf-8")):
            if urlsplit(link).scheme:
                continue
            path = urlsplit(link).path
            assert not path or (source.parent / path).exists(), f"{source.relative_to(REPO)}: {link}"


def test_readme_is_a_front_page():
    assert len((REPO / "README.md").read_bytes()) <= 10_500


def test_no_docs_page_is_over_30_kb():
    for source in markdown_sources():
        assert len(source.read_bytes()) <= MAX_PAGE_BYTES, f"{source.relative_to(REPO)}"


def stated_constants(text):
    """``(module, name, stated value)`` for every "`dgmm.module.NAME` = value" of a page."""
    return [(match["module"], match["name"], match["value"]) for match in STATED_CONSTANT.finditer(text)]


def test_constants_stated_in_the_docs_are_the_code_s():
    """A page that gives a constant's value as "`dgmm.module.NAME` = value" gives the value in the code."""
    stated = [(source, *entry) for source in markdown_sources() for entry in stated_constants(source.read_text())]
    assert len(stated) >= 5  # docs/studies/odometry_constants.md states five
    for source, module, name, value in stated:
        actual = getattr(importlib.import_module(module), name)
        where = f"{source.relative_to(REPO)}: {module}.{name} = {value}"
        assert actual == ast.literal_eval(value), f"{where}, not {actual!r}"


def test_a_stated_constant_is_read_with_its_module_and_value():
    text = "the stride `dgmm.odometry.pixels.PIXEL_STEP` = 4 (pixels), `dgmm.em_blocks.CACHE_BLOCK_BYTES` = 8388608."
    assert stated_constants(text) == [("dgmm.odometry.pixels", "PIXEL_STEP", "4"),
                                      ("dgmm.em_blocks", "CACHE_BLOCK_BYTES", "8388608")]


def test_link_check_finds_missing_files_and_anchors(tmp_path):
    """The checker itself, on a two-page site with one good link, one to a missing page and one to a missing
    anchor (a checker that finds nothing would pass the site test)."""
    (tmp_path / "sub").mkdir()
    (tmp_path / "index.html").write_text('<a href="sub/page.html#here">ok</a> <a href="gone.html">x</a>'
                                         '<img src="sub/page.html"> <a href="https://example.org/x.html">ext</a>')
    (tmp_path / "sub" / "page.html").write_text('<h1 id="here">t</h1><a href="../index.html#nowhere">y</a>'
                                                '<a href="#here">z</a>')
    assert sorted(broken_links(tmp_path)) == ["index.html: gone.html",
                                              "sub/page.html: ../index.html#nowhere (no such anchor)"]


def test_configuration_page_documents_every_key():
    """Every key of the schema has a description (the configuration page is generated from them), and every key
    of config.yaml and tests/config.yaml is on the page."""
    import yaml
    from config_schema import _keys, schema_rst

    schema = yaml.safe_load((REPO / "workflow/schemas/config.schema.yaml").read_text())
    undescribed = [".".join(path) for path, sub, _ in _keys(schema) if not sub.get("description")]
    assert undescribed == [], "add a description to these keys of config.schema.yaml"
    page = "\n".join(schema_rst(schema, {}))

    def keys(config, path=()):
        for name, value in config.items():
            named = path and path[-1] == "experiments"  # user-named entries: documented as <name>
            dotted = path + ("<name>",) if named else path + (name,)
            if not named:
                yield ".".join(dotted)
            if isinstance(value, dict):
                yield from keys(value, dotted)

    for config in ("config.yaml", "tests/config.yaml"):
        for key in keys(yaml.safe_load((REPO / config).read_text())):
            assert f"``{key}``" in page or f"rubric:: {key}" in page, f"{config}: {key} is not on the page"


def test_the_odometry_page_describes_the_default_schedule_as_the_code_runs_it():
    """The user guide's bullet on ``overlap`` (the default of ``run_odometry`` and the sweep) gives the schedule's
    own numbers."""
    import inspect

    from dgmm.odometry import SCHEDULES, run_odometry

    default = inspect.signature(run_odometry).parameters["schedule"].default
    schedule = SCHEDULES[default]
    words = {1: "one", 2: "two", 3: "three", 4: "four"}
    solvers = {"gauss-newton": "Gauss-Newton D2D", "bfgs": "BFGS D2D"}
    bullet = next(line for line in (DOCS / "user_guide" / "odometry.md").read_text().split("\n- ")
                  if line.startswith(f"`{default}` (the default)"))
    bullet = " ".join(bullet.split())
    for phrase in (f"seeds from {schedule.seed_sample:,} primitives",
                   f"{schedule.lloyd_iter} Lloyd and {schedule.em_iter} EM iterations",
                   f"widened by {schedule.overlap_scales[0]:g} RMS radii",
                   f"up to {words[schedule.cut_rounds]} rounds", solvers[schedule.solver]):
        assert phrase in bullet, phrase
