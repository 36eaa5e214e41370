"""The report: its tables and claims against hand-computed values, and the whole `report` rule on synthetic tables,
rendered in headless Chromium."""
import math
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
import yaml
from matplotlib.figure import Figure

from dgmm.data import load_mesh, save_ply
from dgmm.experiments.report import claims, figure_names
from dgmm.experiments.report import layout
from dgmm.experiments.report.build import Loaded, blocks
from dgmm.experiments.report.claims import theory
from dgmm.experiments.report.claims.rules import NOTEBOOK
from dgmm.experiments.report.document import BADGE_MARKS, markdown_table, to_html, to_markdown
from dgmm.experiments.report.tables import fig2_bars, likelihood_means, registration_errors, table1, table1_mesh
from dgmm.experiments.shared_responsibility import PER_POINT_MEASURE
from dgmm.runtime.tables import read_csv, write_csv
from tests.conftest import SHARED_DATA

REPO = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
MODELS = ("armadillo", "bunny", "dragon", "happy", "lucy")
MAX_REPORT_BYTES = 40 * 1024
"""The report's markdown stays readable: at most this size (the HTML may inline the figures): about 600 bytes for
each of 67 claims with its three columns, and the captions of 12 figures."""


def ll_row(model, input_name, k, init, variant, seed, eval_ll, max_iter=25):
    return {"model": model, "input": input_name, "K": k, "init": init, "variant": variant, "seed": seed,
            "eval_ll": eval_ll, "bound": eval_ll - 1.0, "n_iter": max_iter, "max_iter": max_iter}


def reg_rows(model, mesh, method, rot, trans):
    return [{"model": model, "mesh": mesh, "method": method, "trial": i, "rotation_error_deg": r,
             "translation_error_pct": t, "iterations": 10, "converged": True}
            for i, (r, t) in enumerate(zip(rot, trans))]


# ---------------------------------------------------------------------------------------------------------
# Tables, by hand
# ---------------------------------------------------------------------------------------------------------

def test_likelihood_means_are_mean_and_population_std_over_seeds():
    rows = [ll_row("bunny", "res4-exact", 25, "kmeans", "textbook", s, v) for s, v in enumerate([1.0, 3.0])]
    rows.append(ll_row("bunny", "res4-exact", 100, "kmeans", "textbook", 0, 5.0))
    rows = [{key: str(value) for key, value in row.items()} for row in rows]  # as read from CSV
    assert likelihood_means(rows) == {("bunny", "res4-exact", "textbook", "kmeans", 25): (2.0, 1.0),
                                      ("bunny", "res4-exact", "textbook", "kmeans", 100): (5.0, 0.0)}


FIG2_ROWS = [
    {"measure": "triangle", "n": "", "draw": "0", "bound": "7.5", "expected": "7.0"},
    {"measure": "centroid", "n": "", "draw": "0", "bound": "7.9", "expected": "7.4"},
    {"measure": "area x centroid", "n": "", "draw": "0", "bound": "8.0", "expected": "7.6"},
    {"measure": "points", "n": "10", "draw": "0", "bound": "8.5", "expected": "8.0"},
    {"measure": "points", "n": "10", "draw": "1", "bound": "6.5", "expected": "6.0"},
    {"measure": "all points", "n": "1000", "draw": "0", "bound": "7.3", "expected": "7.05"},
    {"measure": PER_POINT_MEASURE, "n": "64", "draw": "0", "bound": "7.29", "expected": "7.04"},  # not a bar
]


def test_fig2_bars_average_the_draws_and_take_all_points_as_reference():
    bars, reference = fig2_bars(FIG2_ROWS, "expected")
    assert bars == [("triangle", 7.0, 0.0), ("centroid", 7.4, 0.0), ("area x centroid", 7.6, 0.0),
                    ("10 points", 7.0, 1.0)]
    assert reference == 7.05
    assert fig2_bars(FIG2_ROWS, "bound")[1] == 7.3


def test_table1_is_ours_beside_the_paper_with_errors_as_percent_of_icp():
    means = {("dragon", "quadric1000-exact", "textbook", "kmeans", 100): (8.0, 0.1),
             ("dragon", "quadric1000-vertices", "textbook", "kmeans", 100): (7.0, 0.1),
             ("dragon", "quadric1000-exact", "authors", "kmeans", 100): (99.0, 0.1),  # not Table 1's variant
             ("bunny", "res4-exact", "textbook", "kmeans", 100): (8.2, 0.1),  # the bunny's row is res4 ...
             ("bunny", "quadric1000-exact", "textbook", "kmeans", 100): (99.0, 0.1)}  # ... not quadric1000
    rows = (reg_rows("dragon", "quadric1000", "icp", [2.0, 4.0], [1.0, 1.0])
            + reg_rows("dragon", "quadric1000", "mesh-kmeans", [0.3, 0.9], [0.25, 0.25])
            + reg_rows("dragon", "quadric1000", "mesh-kmeans-c2f", [0.3, 0.3], [0.1, 0.3])
            + reg_rows("dragon", "quadric1000", "points-kmeans", [1.5, 1.5], [0.5, 1.5])
            + reg_rows("bunny", "res4", "icp", [1.0, 1.0], [1.0, 1.0])
            + reg_rows("bunny", "res4", "mesh-kmeans", [0.5, 0.5], [0.5, 0.5])
            + reg_rows("bunny", "quadric1000", "icp", [100.0, 100.0], [100.0, 100.0]))  # not the bunny's mesh
    errors = registration_errors([{key: str(value) for key, value in row.items()} for row in rows])
    table = {row["model"]: row for row in table1(means, errors)}
    assert list(table) == list(MODELS)
    dragon = table["dragon"]
    assert dragon["mesh"] == "quadric1000"
    assert (dragon["ll_points"], dragon["ll_mesh"]) == (7.0, 8.0)
    assert dragon["rot_mesh"] == pytest.approx(20.0)       # 0.6 / 3
    assert dragon["rot_mesh_c2f"] == pytest.approx(10.0)   # 0.3 / 3
    assert dragon["rot_points"] == pytest.approx(50.0)     # 1.5 / 3
    assert dragon["trans_mesh"] == pytest.approx(25.0)     # 0.25 / 1
    assert dragon["trans_mesh_c2f"] == pytest.approx(20.0)  # 0.2 / 1
    assert dragon["trans_points"] == pytest.approx(100.0)  # 1.0 / 1
    bunny = table["bunny"]
    assert bunny["mesh"] == "res4" and bunny["ll_mesh"] == 8.2 and math.isnan(bunny["ll_points"])
    assert bunny["rot_mesh"] == pytest.approx(50.0) and math.isnan(bunny["rot_mesh_c2f"])
    assert (bunny["ll_points_paper"], bunny["ll_mesh_paper"], bunny["rot_mesh_paper"]) == (7.6, 8.2, 17.0)
    assert math.isnan(table["lucy"]["ll_mesh"]) and table["lucy"]["ll_mesh_paper"] == -18.3


# ---------------------------------------------------------------------------------------------------------
# Claims, by hand
# ---------------------------------------------------------------------------------------------------------

def test_fig2_claim_compares_the_triangle_with_the_sampled_points_within_their_noise():
    rows = [dict(row) for row in FIG2_ROWS] + [
        {"measure": "points", "n": "1000", "draw": str(draw), "bound": "7.3", "expected": str(value)}
        for draw, value in enumerate((7.01, 6.99))]  # mean 7.00, sd 0.01414: band 0.0283
    claim = theory.triangle_equals_points(claims.Measurements(fig2=rows))  # triangle 7.0 − 7.0: won
    assert claim.verdict == "reproduced" and claim.grades["textbook"].verdict == "reproduced"  # no mesh EM in it
    assert claim.grades["authors"].ours == "+0.000 nat" and claim.why == "" and "0.028 nat" in claim.rule
    rows[0]["expected"] = "6.9"  # −0.1: lost; with a responsibility per point 7.04 − 7.00 = +0.04: lost too
    claim = theory.triangle_equals_points(claims.Measurements(fig2=rows))
    assert claim.verdict == "not reproduced"
    assert "the gap is +0.040 nat and the comparison is lost" in claim.why
    rows[-3]["expected"] = "7.02"  # per point +0.02: inside the band, the switch moves the comparison
    assert "+0.020 nat and the comparison is won" in theory.triangle_equals_points(
        claims.Measurements(fig2=rows)).why


def test_figures_follow_the_configured_inputs():
    pictures = ["res4", "full", "dense", "random", "clustering", "quadric", "poisson"]
    everything = ["likelihood", "fig2", "registration", *pictures]
    assert figure_names(everything, ["res4-exact", "quadric1000-exact", "bunny/res4"]) == \
        ["fig1", "fig2", "fig3", "fig3_authors", "fig4", "fig4_authors", "fig5", "fig6", "fig6_authors"]
    assert figure_names(["likelihood", "fig2", "res4"], ["res4-exact"]) == ["fig1", "fig2", "fig3", "fig3_authors"]
    assert figure_names(everything, ["res4-exact", "bunny/quadric1000"]) == ["fig1", "fig2", "fig3", "fig3_authors",
                                                                              "fig5"]


def test_summary_rows_link_each_claim_to_its_section_and_details():
    both = lambda verdict, ours="", why="": {v: claims.Grade(verdict, ours, why) for v in claims.VARIANTS}  # noqa
    evaluated = [claims.Claim("§III-A", "Fig 2", "a", "rule", "evidence", both("reproduced", "1", "ignored"), "2"),
                 claims.Claim("§IV-A", "Fig 3", "b", "rule", "evidence",
                              {"authors": claims.Grade("reproduced", "5"),
                               "textbook": claims.Grade("partly", "6", "Because of c.")}, "7", NOTEBOOK,
                              on_stored=claims.Grade("not reproduced", "0/3 won")),
                 claims.Claim("§I, §VII", "", "d", "rule", "", both("not reproduced", "3", "Because of e."), "4",
                              timings="t")]
    assert layout.figure_anchor("Fig 2") == "fig2" and layout.figure_anchor("") is None
    assert layout.summary_rows(evaluated) == [  # authors' EM (the headline) first; words need no paper column
        ["§III-A", "[a](#claim-1)", "{{reproduced}} 1", "{{reproduced}} 1", "–", ""],
        ["§IV-A", "[b](#claim-2)\nThe authors' own stored data does not bear it out either (0/3 won).\n"
                  "textbook EM: Because of c.", "{{reproduced}} 5", "{{partly}} 6", "{{not reproduced}} 0/3 won",
         "7ᴺ"],
        ["§I, §VII", "[d](#claim-3)\nBecause of e.", "{{not reproduced}} 3", "{{not reproduced}} 3", "–", ""]]
    assert layout.SUMMARY_HEADER[2:5] == ["ours, authors' EM (headline)", "ours, textbook EM", "the authors' data"]
    assert "(#timings)" in layout.claim_item(evaluated[2])  # a timing claim's numbers are only there
    page = to_html([("table", ["claim", "verdict"], [row[1:3] for row in layout.summary_rows(evaluated)],
                     "summary")], {}, "T")
    assert ('<td><a href="#claim-3">d</a><br>Because of e.</td>'
            '<td><span class="badge not-reproduced">not reproduced</span> 3</td>') in page
    assert markdown_table(["v"], [["{{partly}}"]]) == "| v |\n|---|\n| {{partly}} |"
    assert to_markdown([("table", ["v"], [["{{partly}}", "a|b\nc"]])]) == \
        "| v |\n|---|\n| 🟡 **partly** | a\\|b<br>c |\n"


def timing_rows(seconds):
    """An approximation timing check of 11 repeats: approx takes ``seconds[i]`` when exact takes 1."""
    return [{"check": "approximation", "setting": setting, "repeat": repeat, "seconds": value, "iterations": 25,
             "detail": ""} for repeat, approx in enumerate(seconds)
            for setting, value in (("exact", 1.0), ("approx", approx))]


def test_only_the_timing_block_changes_when_only_the_timings_do(tmp_path):
    pages = []
    for index, seconds in enumerate((np.linspace(0.50, 0.60, 11), np.linspace(0.40, 0.65, 11))):
        write_csv(tmp_path / f"timing{index}.csv", timing_rows(seconds))
        loaded = Loaded({"timing_seconds": tmp_path / f"timing{index}.csv"}, seed=0)
        document = blocks(loaded, [], claims.evaluate(loaded.measured))
        pages.append(to_markdown(document))
    assert pages[0] != pages[1] and "median 0.55" in pages[0] and "median 0.525" in pages[1]
    assert layout.without_timings(pages[0]) == layout.without_timings(pages[1])
    assert "{{reproduced}}" not in pages[0] and "🟢 **reproduced** interval < 0.78" in pages[0]


def test_markdown_and_html_rendering():
    assert markdown_table(["a", "b"], [["1", "2"]]) == "| a | b |\n|---|---|\n| 1 | 2 |"
    blocks = [("h1", "T"), ("p", "x < y, **bold**"), ("figure", "f", "cap")]
    assert to_markdown(blocks) == "# T\n\nx < y, **bold**\n\n![f](figures/f.png)\n\n*cap*\n"
    page = to_html(blocks, {"f": b"\x89PNG"}, "T")
    assert "<p>x &lt; y, <strong>bold</strong></p>" in page
    assert 'src="data:image/png;base64,iVBORw=="' in page


# ---------------------------------------------------------------------------------------------------------
# The rule, on synthetic tables, in Chromium
# ---------------------------------------------------------------------------------------------------------

FIG3_FIG4 = claims.FIG3_INPUTS + claims.FIG4_INPUTS
FIGURES = ("fig1", "fig2", "fig3", "fig3_authors", "fig4", "fig4_authors", "fig4_100", "fig4_100_authors", "fig5", "fig6",
           "fig6_authors")


def synthetic_results(results):
    """Tables and bunny files shaped like the sweep's, small enough for a fast report."""
    rng = np.random.default_rng(0)
    rows = []
    for index, name in enumerate(FIG3_FIG4):
        sized = name.endswith(("exact", "approx"))
        for variant in ("textbook", "authors") if sized else ("textbook",):
            for init in ("kmeans", "random"):
                for k in (25, 50, 200):  # K=100 of quadric1000-exact is Table 1's row, below
                    for seed in range(2):
                        rows.append(ll_row("bunny", name, k, init, variant, seed,
                                           7.0 + 0.3 * np.log(k / 25) - 0.2 * index + 0.05 * seed))
                        if name in claims.FIG4_INPUTS:  # Fig 4 at the authors' stored protocol too
                            rows.append(ll_row("bunny", name, k, init, variant, seed,
                                               7.1 + 0.3 * np.log(k / 25) - 0.2 * index + 0.05 * seed, 100))
    for m, model in enumerate(MODELS):
        for name, value in (("exact", 8.0 - m), ("vertices", 7.0 - m)):
            rows.append(ll_row(model, f"{table1_mesh(model)}-{name}", 100, "kmeans", "textbook", 0, value))
    write_csv(results / "tables" / "likelihood.csv", rows)
    write_csv(results / "tables" / "fig2.csv", [{k: row[k] for k in row} for row in FIG2_ROWS])
    reg = []
    for method in ("mesh-kmeans", "mesh-random", "points-kmeans", "points-random", "mesh-kmeans-c2f", "icp", "cpd"):
        reg += reg_rows("bunny", "res4", method, rng.lognormal(0, 1, 12), rng.lognormal(-2, 1, 12))
    for model in MODELS[:1] + MODELS[2:]:
        for method in ("mesh-kmeans", "mesh-kmeans-c2f", "points-kmeans", "icp"):
            reg += reg_rows(model, "quadric1000", method, rng.lognormal(0, 1, 3), rng.lognormal(-2, 1, 3))
    write_csv(results / "tables" / "registration.csv", reg)
    write_csv(results / "tables" / "registration_seconds.csv",
              [{"model": row["model"], "mesh": row["mesh"], "method": row["method"], "trial": row["trial"],
                "seconds": 0.01 if row["method"] == "cpd" else 0.02, "recorded": False} for row in reg])
    write_csv(results / "tables" / "odometry.csv", [
        odometry_row("synthetic", method, variant, ate)
        for method, variant, ate in (("gmm-pixels", "textbook", 0.01), ("gmm-points", "textbook", 0.02),
                                     ("icp", "", 0.03))])
    write_csv(results / "tables" / "odometry_seconds.csv", [
        {"sequence": "synthetic", "method": method, "variant": variant, "frames": 8, "mean_seconds_per_frame": 0.1,
         "mean_model_seconds": 0.05, "mean_registration_seconds": seconds}
        for method, variant, seconds in (("gmm-pixels", "textbook", 0.04), ("gmm-points", "textbook", 0.05),
                                         ("icp", "", 0.05))])
    write_check_tables(results / "tables")
    trajectories = Figure(figsize=(2, 2))
    trajectories.add_subplot().plot([0, 1], [0, 1])
    (results / "odometry").mkdir()
    trajectories.savefig(results / "odometry" / "fig7.png")
    vertices, faces = load_mesh(SHARED_DATA / "stanford" / "bunny_res4.ply")
    bunny = results / "data" / "bunny"
    for name in ("res4", "full", "quadric1000", "clustering1000"):
        save_ply(bunny / f"{name}.ply", vertices, faces)
    for name, n in (("full_eval", 3000), ("poisson1000", 500), ("random1000", 500)):
        save_ply(bunny / f"{name}.ply", vertices[rng.integers(len(vertices), size=n)] + rng.normal(0, 1e-3, (n, 3)))


def write_check_tables(tables):
    """The checks' tables (dgmm.experiments.checks), a row or two each."""
    write_csv(tables / "convergence.csv", [
        {"model": "bunny", "input": name, "variant": variant, "K": 100, "init": "kmeans", "seed": 0,
         "eval_ll_25": 7.0, "eval_ll_final": 7.1, "bound_25": 8.0, "bound_final": 8.1, "n_iter_within_0.1": n,
         "n_iter_within_0.01": n, "coverage_2sigma": coverage, "effective_components": 0.9}
        for name, variant, n, coverage in (("res4-exact", "textbook", 10, 0.8), ("res4-exact", "authors", 5, 0.7),
                                           ("res4-centroids", "textbook", 30, 0.5))])
    write_csv(tables / "resampling.csv", [
        {"variant": variant, "seed": 0, "eval_ll": 7.0, "eval_ll_split": 7.05, "eval_gap": 0.05, "bound": 8.0,
         "bound_split": 8.1, "bound_gap": 0.1, "component_gap": 0.0} for variant in ("textbook", "authors")])
    rows = [{"optimiser": optimiser, "rotation": rotation, "trial": 0, "rotation_error_deg": 0.5,
             "translation_error_pct": 0.1, "iterations": 20, "evaluations": 400}
            for optimiser, rotation in (("BFGS", "quaternion"), ("CG", "quaternion"), ("BFGS", "rotvec"))]
    write_csv(tables / "optimisers.csv", rows)
    write_csv(tables / "optimisers_seconds.csv", [{**{key: row[key] for key in ("optimiser", "rotation", "trial")},
                                                  "seconds": 0.2} for row in rows])
    write_csv(tables / "timing_seconds.csv", [
        {"check": check, "setting": setting, "repeat": repeat, "seconds": seconds * (1 + 0.01 * repeat),
         "iterations": 25, "detail": ""} for repeat in range(6)
        for check, setting, seconds in (("approximation", "exact", 0.04), ("approximation", "approx", 0.03),
                                        ("d2d determinant", "determinant-free", 0.4),
                                        ("d2d determinant", "with determinant", 1.6))])
    write_csv(tables / "identities.csv", [
        *({"identity": identity, "cases": 3, "max_error": 1e-17, "scale": 1.0, "detail": "", "noise": 0.0}
          for identity in ("cgal_triangle_moment", "mean_update_exact_equals_approx", "hierarchical_gmm_update",
                           "points_equal_sklearn")),
        *({"identity": identity, "cases": 3, "max_error": 0.001, "scale": 7.0, "detail": "closed 7.001, sampled 7.0",
           "noise": 0.002} for identity in ("triangle_bound_monte_carlo", "general_bound_monte_carlo"))])


def run_report(workdir, config):
    command = [str(SNAKEMAKE), "--snakefile", str(REPO / "Snakefile"), "--directory", str(workdir),
               "--configfile", str(config), "--cores", "1", "out/report.html", "--allowed-rules", "report",
               "--forcerun", "report"]
    run = subprocess.run(command, capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 0, run.stderr[-3000:]


@pytest.fixture(scope="module")
def built(tmp_path_factory):  # the tests using it are marked slow: a real Snakemake run
    """The report rule run twice on synthetic tables: (report folder, bytes of every file of the first run, figure
    names). Fig 7 is expected when tests/config.yaml configures the odometry stage."""
    workdir = tmp_path_factory.mktemp("report")
    synthetic_results(workdir / "results")
    config = yaml.safe_load((REPO / "tests" / "config.yaml").read_text())
    config["fit"]["experiments"]["figs"] = {"models": ["bunny"], "inputs": list(FIG3_FIG4), "components": [25],
                                            "inits": ["kmeans", "random"]}
    config["report"] = {"dir": "out"}
    (workdir / "config.yaml").write_text(yaml.safe_dump(config))
    run_report(workdir, workdir / "config.yaml")
    out = workdir / "out"
    first = {path.relative_to(out): path.read_bytes() for path in sorted(out.rglob("*")) if path.is_file()}
    run_report(workdir, workdir / "config.yaml")
    return out, first, FIGURES + ("fig7",) * ("odometry" in config)


def test_the_shipped_report_stays_within_its_size():
    """The committed report of the full sweep (reports/report.md, more claims and captions than a test run's)."""
    assert len((REPO / "reports" / "report.md").read_bytes()) <= MAX_REPORT_BYTES


@pytest.mark.slow
def test_report_writes_every_output(built):
    out, first, drawn = built
    names = {str(path) for path in first}
    figures = {f"figures/{name}.png" for name in drawn}
    assert names == {"report.html", "report.md", "claims.md", "table1.csv", "table1.md", "authors.csv"} | figures
    markdown = (out / "report.md").read_text()
    assert ("Pending: waits for the odometry stage" in markdown) == ("fig7" not in drawn)
    assert all(f"({figure})" in markdown for figure in figures)
    assert len(markdown.encode()) <= MAX_REPORT_BYTES
    # Every claim: once in the summary, once in its section (with both EMs' marks), once in the evidence ledger.
    marks = "[" + "".join(BADGE_MARKS.values()) + "]"
    assert len(re.findall(rf'<a id="claim-\d+"></a>{marks}{{2}} \w', markdown)) == len(claims.CLAIMS)
    ledger = (out / "claims.md").read_text()
    verdicts = "|".join(claims.VERDICTS)
    assert len(re.findall(rf"— authors' EM \S+ \*\*({verdicts})\*\*", ledger)) == len(claims.CLAIMS)
    # The summary table opens the report: one row per claim, each not reproduced saying why.
    html_page = (out / "report.html").read_text()
    summary = html_page[html_page.index("<h1>"):html_page.index('<h2 id="grading">')]
    rows = re.findall(r"<tr><td>.*?</td><td>(.*?)</td><td><span class=\"badge ([\w-]+)\">.*?</td>"
                      r"<td><span class=\"badge ([\w-]+)\">", summary)
    assert len(rows) == len(claims.CLAIMS)
    assert all(("<br>" in cell) == (authors != "reproduced" or textbook != "reproduced"
                                    or layout.CONTRADICTED in cell) for cell, authors, textbook in rows), rows


@pytest.mark.slow
def test_regenerated_report_is_byte_identical(built):
    out, first, _ = built
    for path, data in first.items():
        assert (out / path).read_bytes() == data, path


@pytest.mark.slow
def test_table1_has_five_models_with_finite_numbers(built):
    out, _, _ = built
    rows = read_csv(out / "table1.csv")
    assert [row["model"] for row in rows] == list(MODELS)
    for m, row in enumerate(rows):
        assert row["mesh"] == table1_mesh(row["model"])
        assert all(np.isfinite(float(value)) for key, value in row.items()
                   if key not in ("model", "mesh", "variant", "protocol"))
        assert (float(row["ll_mesh"]), float(row["ll_points"])) == (8.0 - m, 7.0 - m)


@pytest.mark.slow  # a browser
@pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed (CI installs Debian's `chromium`; "
                                             "`apt-get install chromium` to run this test)")
def test_every_figure_loads_and_the_headline_shows_in_the_first_screen_of_headless_chromium(built, tmp_path):
    out, _, drawn = built
    page = (out / "report.html").read_text()
    n_figures = page.count("<img ")
    # A broken image as a control, then a script that marks, once the page has loaded, every image (drawn or
    # not), every verdict badge (its bottom edge, in CSS pixels from the top of the page area) and the size of
    # the page area.
    probe = ('<img id="control" src="data:image/png;base64,AAAA"><script>window.addEventListener("load", () => {'
             'for (const img of document.images) img.dataset.ok = img.naturalWidth > 0 ? "yes" : "no";'
             'for (const badge of document.querySelectorAll(".badge")) '
             'badge.dataset.bottom = Math.ceil(badge.getBoundingClientRect().bottom);'
             'document.body.dataset.viewport = innerWidth + "x" + innerHeight;});'
             "</script></body>")
    (tmp_path / "page.html").write_text(page.replace("</body>", probe))
    run = subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                          "--no-first-run", "--disable-background-networking", "--disable-component-update",
                          "--disable-sync", f"--user-data-dir={tmp_path / 'profile'}", "--virtual-time-budget=10000",
                          "--window-size=1280,800", "--dump-dom", (tmp_path / "page.html").as_uri()],
                         capture_output=True, text=True, timeout=120, check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    tags = re.findall(r"<img[^>]*>", run.stdout)
    marks = {("control" if 'id="control"' in tag else re.search(r'alt="(\w+)"', tag).group(1)):
             re.search(r'data-ok="(\w+)"', tag).group(1) for tag in tags}
    assert len(tags) == n_figures + 1 == len(drawn) + 1
    assert marks.pop("control") == "no"
    assert marks == {name: "yes" for name in drawn}
    # The page area of a 1280×800 window (its height less the browser's own bars) holds the headline: each EM's
    # verdict counts, the badges of the report's first paragraph.
    width, height = map(int, re.search(r'data-viewport="(\d+)x(\d+)"', run.stdout).groups())
    assert width == 1280 and 600 < height <= 800
    first = re.search(r"<p>(.*?)</p>", run.stdout, re.S).group(1)
    headline = [int(value) for value in re.findall(r'class="badge [\w-]+" data-bottom="(\d+)"', first)]
    assert len(headline) >= 2 and 0 < max(headline) <= height, (headline, height)


def odometry_row(sequence, method, variant, ate, missing=""):
    """A row of odometry.csv as read back (strings)."""
    return {"sequence": sequence, "method": method, "variant": variant, "frames": "8" if method else "",
            "ate_rmse_m": str(ate), "rpe_translation_m_s": "0.1", "rpe_rotation_deg_s": "1.0",
            "missing_folder": missing}


@pytest.mark.slow
def test_report_zip_carries_every_report_output(built):
    """`snakemake --report report.zip` holds every file the rules mark as report output: Table 1, each figure, Fig 2's
    table and Fig 7."""
    out, first, drawn = built
    workdir = out.parent
    command = [str(SNAKEMAKE), "--snakefile", str(REPO / "Snakefile"), "--directory", str(workdir),
               "--configfile", str(workdir / "config.yaml"), "--report", str(workdir / "report.zip")]
    run = subprocess.run(command, capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 0, run.stderr[-3000:]
    with zipfile.ZipFile(workdir / "report.zip") as archive:
        names = {Path(name).name for name in archive.namelist()}
    expected = {"table1.csv", "fig2.csv"} | {f"{name}.png" for name in drawn if name != "fig7"}
    expected |= {"fig7.png"} if "fig7" in drawn else set()
    assert expected <= names, sorted(expected - names)


def test_fig5s_points_gmm_is_the_center_of_mass_gmm_of_the_paper(bunny_res4):
    """§IV-A contrasts the mesh GMM with "the center-of-mass GMM": Fig 5's points panel is fitted to the triangles'
    centroids (trimesh's), not to the mesh's vertices."""
    from dgmm.experiments.report.figures import pictured_mixtures
    from dgmm.experiments.sweep import job_seed
    from dgmm.mixture import GaussianMixture

    vertices, faces = np.asarray(bunny_res4.vertices), np.asarray(bunny_res4.faces)
    pictured = pictured_mixtures({"res4": (vertices, faces)}, seed=0)["points"]
    centroids = GaussianMixture(100, random_state=job_seed(0, "report/fig5/points", 0)).fit(bunny_res4.triangles_center)
    assert np.allclose(pictured.means_, centroids.means_, atol=1e-9)
