"""Assemble the report: Table 1, the claims and every figure whose inputs exist, into ``reports/``.

Inputs are named files (the keys of ``INPUTS``); a figure is drawn when all the inputs it needs are given and,
for the likelihood figures, when the sweep fits at least one of its inputs. Everything else is a section that
says it is pending. Outputs: ``report.md``, ``claims.md`` (the evidence ledger), ``report.html`` (both, self-contained),
``table1.csv``, ``table1.md`` and ``figures/{name}.png``, all written atomically; everything but the timing block of
``report.md`` and ``report.html`` is byte-reproducible.
"""
import io
import math
import re
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

from dgmm.data import load_mesh, load_points
from dgmm.experiments.authors_data import COLUMNS as AUTHORS_COLUMNS
from dgmm.experiments.report import claims, figures, layout, paper, tables
from dgmm.experiments.report.authors import AuthorsData, authors_measurements
from dgmm.experiments.report.claims.rules import SECTION_TITLES, first_section
from dgmm.experiments.report.document import markdown_table, to_html, to_markdown
from dgmm.files import atomic_path
from dgmm.runtime.tables import read_csv, write_csv

INPUTS = {
    # key: what it is (said when a section waits for it)
    "likelihood": "the fitting sweep's likelihood.csv",
    "authors": "the authors' stored results authors.csv (rule authors_data)",
    "fig2": "the Fig 2 table fig2.csv",
    "registration": "the registration stage (config section `registration`)",
    "odometry": "the odometry stage's odometry.csv (config section `odometry`)",
    "fig7": "the odometry stage's trajectory figure (config section `odometry`)",
    "registration_seconds": "the registration stage's registration_seconds.csv",
    "odometry_seconds": "the odometry stage's odometry_seconds.csv",
    "convergence": "the convergence check's convergence.csv (config section `checks.convergence`)",
    "resampling": "the resampling check's resampling.csv (config section `checks.resampling`)",
    "optimisers": "the optimisers check's optimisers.csv (config section `checks.optimisers`)",
    "optimisers_seconds": "the optimisers check's optimisers_seconds.csv (config section `checks.optimisers`)",
    "timing_seconds": "the timing check's timing_seconds.csv (config section `checks.timing`)",
    "identities": "the identities check's identities.csv (config section `checks.identities`)",
    "res4": "bunny res4 from the data stage",
    "full": "the full bunny from the data stage",
    "dense": "the full bunny's evaluation points",
    "random": "random samples of the bunny (data.methods: random)",
    "clustering": "the clustering decimation of the bunny (data.methods: clustering)",
    "quadric": "the quadric decimation of the bunny (data.methods: quadric)",
    "poisson": "Poisson-disk samples of the bunny (data.methods: poisson)",
}
POINT_SETS = ("dense", "random", "poisson")
TITLE = "Direct Fitting of Gaussian Mixture Models: reproduction report"


@dataclass(frozen=True)
class FigureSpec:
    """One figure of the report.

    Attributes
    ----------
    name : str
        File stem under ``figures/`` and the HTML anchor.
    title : str
    needs : tuple of str
        Keys of ``INPUTS`` it reads.
    configured : tuple of str
        Experiments it plots (fitting inputs such as ``res4-exact``, registered meshes such as ``bunny/res4``);
        it is drawn only when the config runs one of them (empty: no condition).
    draw : callable
        ``draw(loaded)`` with ``loaded`` a :class:`Loaded`: a :class:`matplotlib.figure.Figure`, or the PNG bytes
        of a figure another stage drew.
    caption : str
        What the figure shows and which mark is which.
    """

    name: str
    title: str
    needs: tuple
    configured: tuple
    draw: object
    caption: str


class Loaded:
    """The report's inputs, each read on first use.

    Parameters
    ----------
    paths : dict
        ``key -> path`` for keys of ``INPUTS``.
    seed : int
        Root seed of the mixtures fitted for Fig 5.
    table1_trials : int, optional
        Table 1 averages each model's first this many registration trials (config
        ``registration.experiments.table1.trials``; §VI-C's 25); None: every trial.
    """

    def __init__(self, paths, seed, table1_trials=None):
        self.paths, self.seed, self.table1_trials = dict(paths), seed, table1_trials

    @cached_property
    def means(self):
        return self.means_at(tables.TEXT_MAX_ITER)

    def means_at(self, max_iter):
        """:func:`~.tables.likelihood_means` of the fits capped at ``max_iter`` iterations (None without
        likelihood.csv)."""
        return self.measured.at_iterations(max_iter).means if "likelihood" in self.paths else None

    @cached_property
    def authors(self):
        """The authors' stored results (None: not given)."""
        return AuthorsData(read_csv(self.paths["authors"])) if "authors" in self.paths else None

    @cached_property
    def cells(self):
        """Every stored value of the authors' beside ours (() without their table)."""
        if self.authors is None:
            return []
        return self.authors.cells(self.measured)

    def stored(self):
        """The authors' data as the claims read it (None without their table)."""
        return None if self.authors is None else authors_measurements(self.authors, self.measured)

    @cached_property
    def fig2(self):
        return read_csv(self.paths["fig2"]) if "fig2" in self.paths else None

    @cached_property
    def registration(self):
        return read_csv(self.paths["registration"]) if "registration" in self.paths else None

    def errors_of(self, protocol="scaled", variant="textbook"):
        """Registration errors of one trial protocol and EM variant (None while registration is pending)."""
        return None if self.registration is None else tables.registration_errors(self.registration, protocol, variant)

    @cached_property
    def settings(self):
        """(protocol, variant) of every Table 1 shown: those registered, else scaled trials with textbook EM."""
        return tables.registration_settings(self.registration) if self.registration else [("scaled", "textbook")]

    @cached_property
    def tables1(self):
        """Table 1 under every setting, each model's registration over its first ``table1_trials`` trials:
        ``(protocol, variant) -> rows``."""
        return {(protocol, variant): tables.table1(
                    self.means or {}, tables.table1_errors(self.errors_of(protocol, variant), self.table1_trials),
                    variant, protocol)
                for protocol, variant in self.settings}

    @cached_property
    def bunny_all_trials(self):
        """The bunny's Table 1 row over all of Fig 6's trials (our protocol before it took the paper's 25), per
        setting: ``(protocol, variant) -> row`` (none when Table 1 already averages every trial)."""
        if self.table1_trials is None:
            return {}
        rows = {setting: tables.table1(self.means or {}, self.errors_of(*setting), setting[1], setting[0])
                for setting in self.settings}
        return {setting: {**row, "mesh": f"{row['mesh']}, all trials"} for setting, table in rows.items()
                for row in table if row["model"] == tables.FIG6_MESH[0]}

    @cached_property
    def odometry(self):
        return read_csv(self.paths["odometry"]) if "odometry" in self.paths else None

    @cached_property
    def meshes(self):
        return {key: (load_points(self.paths[key]), None) if key in POINT_SETS else load_mesh(self.paths[key])
                for key in figures.MESH_KEYS if key in self.paths}

    @cached_property
    def measured(self):
        """What the claims read: every table of ``claims.TABLES`` among the inputs."""
        return claims.Measurements(**{name: read_csv(self.paths[name]) for name in claims.TABLES
                                      if name in self.paths}, table1_trials=self.table1_trials)


EM_LABELS = {"textbook": "textbook EM", "authors": "the authors' EM"}
LIKELIHOOD_FIGURES = (
    # number, title, inputs, what is scored, the fits' iteration cap, whether the authors stored this protocol
    (3, "mesh information (bunny res4)", claims.FIG3_INPUTS, "res4's evaluation points", tables.TEXT_MAX_ITER, True),
    (4, "decimation and sampling (full bunny)", claims.FIG4_INPUTS, "the full bunny's evaluation points, fits to "
     "about 1000 primitives", tables.TEXT_MAX_ITER, False),
    (4, "decimation and sampling (full bunny)", claims.FIG4_INPUTS, "the full bunny's evaluation points, fits to "
     "about 1000 primitives", tables.STORED_MAX_ITER, True),
)
"""Figs 3 and 4, each drawn per EM of the mesh mixtures; Fig 4 at the text's 25 iterations and at the authors'
stored 100, their stored means overlaid where they ran that protocol."""


def _likelihood_figure(number, title, inputs, scored, cap, stored, variant):
    """The :class:`FigureSpec` of Fig 3 or 4 for one iteration cap and one EM (see :data:`LIKELIHOOD_FIGURES`)."""
    protocol = "" if number == 3 else (f" at the text's {cap} iterations" if cap == tables.TEXT_MAX_ITER
                                       else f" at {cap} iterations, as the authors' stored data")
    suffix = "" if cap == tables.TEXT_MAX_ITER else f"_{cap}"
    at = "" if cap == tables.TEXT_MAX_ITER else f"@{cap}"  # the workflow's name of an experiment at another cap

    def draw(data):
        overlay = data.authors.curves(f"fig{number}") if data.authors and stored else None
        return figures.likelihood_vs_k(tables.likelihood_curves(data.means_at(cap), "bunny", inputs), inputs,
                                       variant, figures.BAND_SD[number], overlay)

    return FigureSpec(
        f"fig{number}{suffix}{'_authors' if variant == 'authors' else ''}",
        f"Fig {number}: {title}{protocol}, mesh mixtures from {EM_LABELS[variant]}", ("likelihood",),
        tuple(f"{name}{at}" for name in inputs), draw,
        f"Mean log-likelihood of {scored} vs K (log scale), fits of up to {cap} EM iterations; band "
        f"±{figures.BAND_SD[number]:g} standard deviation(s) over seeds; y {figures.Y_LIMITS[0]:g} to "
        f"{figures.Y_LIMITS[1]:g} nats, as the authors drew it. Meshes dashed ({EM_LABELS[variant]}), points solid "
        "(textbook EM)" + ("; crosses: the authors' stored means (authors.csv)." if stored else
                           f"; the authors stored Fig 4 at {tables.STORED_MAX_ITER} iterations only (next figures)."))


FIGURES = (
    FigureSpec("fig1", "Fig 1: triangles and their covariances", ("res4",), (),
               lambda data: figures.fig1_triangles(data.meshes),
               "Bunny res4 (left) and the triangles of its head (right), each with the ellipse of its covariance "
               f"(the uniform distribution over the triangle, eq. 10) drawn at {figures.N_SIGMA}σ."),
    FigureSpec("fig2", "Fig 2: likelihood expressions agree", ("fig2",), (),
               lambda data: figures.fig2_expressions(data.fig2),
               "One GMM fitted to dense samples of bunny res4, scored by each expression. **Bars**: the paper's "
               "quantity Σᵢ ηᵢₚ log ρᵢₚ per unit size; orange the mesh expressions (triangle: eq. 8), blue n sampled "
               "points (±1 std over draws). **Diamonds**: our EM bound (with the entropy). **Red lines**: all the "
               "fitted points (solid: the paper's quantity, dashed: mean log-likelihood). The y axis does not start "
               "at zero."),
    *(_likelihood_figure(*figure, variant) for figure in LIKELIHOOD_FIGURES for variant in ("textbook", "authors")),
    FigureSpec("fig5", "Fig 5: input and output representations", figures.MESH_KEYS, (),
               lambda data: figures.fig5_representations(data.meshes, figures.pictured_mixtures(data.meshes,
                                                                                                 data.seed)),
               "The full bunny, its 1000-primitive decimations and samples, the dense evaluation set, and K=100 "
               f"GMMs ({figures.N_SIGMA:g}σ ellipsoids) fitted in the report job (k-means start, 25 "
               "iterations, seeded) to res4's vertices (points GMM) and to its triangles (mesh GMM)."),
    *(FigureSpec(name, f"Fig 6: registration (bunny), mesh mixtures from {label}", ("registration",),
                 ("/".join(tables.FIG6_MESH),),
                 lambda data, variant=variant: figures.fig6_registration(data.errors_of("scaled", variant),
                                                                         seed=data.seed),
                 "Rotation and translation error of every random rigid trial (scaled protocol) per method (dots), "
                 "box and whisker (notch: median's confidence interval, whiskers 1.5 IQR), our mean (green dot) and "
                 "the paper's mean (red cross). mesh/points: P2D against a K=100 GMM fitted to the mesh or its "
                 f"vertices; mesh GMMs fitted with {label}, points GMMs with textbook EM (the same algorithm).")
      for name, variant, label in (("fig6", "textbook", "textbook EM"),
                                   ("fig6_authors", "authors", "the authors' EM"))),
    FigureSpec("fig7", "Fig 7: visual odometry", ("fig7",), (),
               lambda data: Path(data.paths["fig7"]).read_bytes(),
               "Top-down trajectories of frame-to-frame odometry: GMM D2D with pixel primitives, with plain points, "
               "and point-to-point ICP, against the ground truth. The GMM runs' per-frame schedule is "
               "odometry.csv's `schedule` (config `odometry.schedule`; docs: the odometry user guide)."),
)


def figure_names(input_keys, configured):
    """Names of the figures drawn from these inputs.

    Parameters
    ----------
    input_keys : iterable of str
        Keys of ``INPUTS`` that will be given.
    configured : iterable of str
        Experiments the config runs: the bunny's fitting inputs (``res4-exact``, ...) and registered
        ``model/mesh`` pairs.
    """
    keys, configured = set(input_keys), set(configured)
    return [spec.name for spec in FIGURES
            if set(spec.needs) <= keys and (not spec.configured or set(spec.configured) & configured)]


def _pending_reason(spec, keys):
    missing = [INPUTS[key] for key in spec.needs if key not in keys]
    return ("waits for " + ", ".join(missing) if missing else "the config runs none of its experiments") + "."


def _table1_cells(row):
    """Table 1 row as strings: the model (and its mesh), each measure as ``ours (paper)``, then the coarse-to-fine
    P2D's errors (ours only)."""
    digits = {"ll": 2, "rot": 0, "trans": 0}
    return ([f"{row['model']} ({row['mesh']})"]
            + [f"{tables.format_number(row[c], digits[c.split('_')[0]])} "
               f"({tables.format_number(row[c + '_paper'], digits[c.split('_')[0]])})" for c in paper.TABLE1_COLUMNS]
            + [tables.format_number(row[c], 0) for c in tables.TABLE1_C2F_COLUMNS])


TABLE1_TEXT = ("As the authors' code ran it: the bunny is res4 (Fig 3's K=100 fits; the first 25 of Fig 6's trials, "
               "§VI-C's \"average of 25 runs\" as in the authors' stored Table 1, while table1.md adds the bunny over "
               "all of them), every other model a quadric decimation to 1000 faces; K=100, k-means; likelihoods of "
               "the points GMM (vertices) and the mesh GMM (triangles); registration errors in % of ICP's mean, with "
               "the paper's P2D and, last, the coarse-to-fine P2D (ours, not in the paper). –: not measured. "
               "table1.md has the literal protocol too.")
TABLE1_SETTINGS = {"scaled": "Trials with translations and the mixtures' covariance floor scaled by the diagonal",
                   "literal": "Trials with the authors' literal ±0.05 translations and reg_covar in model units "
                              "(bunny row: –)"}
TABLE1_VARIANTS = {"textbook": "textbook EM", "authors": "the authors' published EM"}
TABLE1_HEADER = ["model (mesh)", "likelihood points", "likelihood mesh", "translation % ICP points",
                 "translation % ICP mesh", "rotation % ICP points", "rotation % ICP mesh",
                 "translation % ICP mesh, coarse-to-fine", "rotation % ICP mesh, coarse-to-fine"]


def _figure_blocks(spec, drawn, keys):
    return [("h3", spec.title, spec.name), ("figure", spec.name, spec.caption) if spec.name in drawn else
            ("p", f"Pending: {_pending_reason(spec, keys)}")]


def _table1_blocks(loaded):
    """Table 1 under the claims' trial protocol (scaled), one table per EM of the mesh GMMs; every protocol's rows
    are in table1.md."""
    result = [("h3", "Table 1: five models, ours (paper)", "table1"), ("p", TABLE1_TEXT)]
    for (protocol, variant), rows in loaded.tables1.items():
        if protocol == "scaled":
            result.append(("p", f"**{TABLE1_SETTINGS[protocol]}; mesh GMMs fitted with {TABLE1_VARIANTS[variant]}**"))
            result.append(("table", TABLE1_HEADER, [_table1_cells(row) for row in rows]))
    return result


def _shown_with(figure):
    """Names of the report's figures and tables that a claim's ``figure`` ("Fig 6", "Table 1") stands for."""
    anchor = layout.figure_anchor(figure)
    return [] if anchor is None else ["table1"] if anchor == "table1" else [
        spec.name for spec in FIGURES if re.fullmatch(rf"{anchor}(_\w+)?", spec.name)]


def blocks(loaded, drawn, evaluated):
    """The report's blocks (see :mod:`dgmm.experiments.report.document`), figures limited to the names in ``drawn``:
    the findings, the summary table, the grading rules, then ``evaluated`` (the graded claims) section by section,
    each section followed by the figures and tables its claims are about, and last the timing block."""
    keys = set(loaded.paths)
    result = [("h1", TITLE), *(("p", text) for text in layout.findings(evaluated)),
              *(("p", text) for text in layout.stored_findings(evaluated, loaded.cells)),
              ("table", layout.SUMMARY_HEADER, layout.summary_rows(evaluated), "summary"),
              ("h2", "How the claims are graded", "grading"), ("list", layout.grading_rules())]
    by_section = {}  # the claims come in the paper's order (claims.evaluate)
    for index, claim in enumerate(evaluated):
        by_section.setdefault(first_section(claim), []).append((index, claim))
    specs = {spec.name: spec for spec in FIGURES}
    placed = []
    for section, listed in by_section.items():
        result.append(("h2", SECTION_TITLES.get(section, section), layout.section_anchor(section)))
        result.append(("list", [layout.claim_item(claim) for _, claim in listed],
                       [layout.claim_anchor(index) for index, _ in listed]))
        for name in dict.fromkeys(name for _, claim in listed for name in _shown_with(claim.figure)):
            if name not in placed:
                placed.append(name)
                result += _table1_blocks(loaded) if name == "table1" else _figure_blocks(specs[name], drawn, keys)
    rest = [spec for spec in FIGURES if spec.name not in placed]
    if rest:
        result.append(("h2", "Other figures", "figures"))
        for spec in rest:
            result += _figure_blocks(spec, drawn, keys)
    result.append(("h2", "Timings of this run", "timings"))
    return result + layout.timing_block(evaluated)


def _png_bytes(figure):
    """PNG bytes of a drawn figure (bytes are passed through)."""
    if isinstance(figure, bytes):
        return figure
    buffer = io.BytesIO()
    figures.save_png(figure, buffer)
    return buffer.getvalue()


def _write(path, data):
    with atomic_path(path) as partial:
        partial.write_bytes(data if isinstance(data, bytes) else data.encode())


def build_report(paths, drawn, out_dir, seed=0, table1_trials=None):
    """Write the report into ``out_dir``.

    Parameters
    ----------
    paths : dict
        ``key -> path`` for keys of ``INPUTS``; missing keys make their sections pending.
    drawn : sequence of str
        Names of the figures to draw (:func:`figure_names` of the same inputs).
    out_dir : path-like
    seed : int, default=0
        Root seed (Fig 5's fitted mixtures, Fig 6's jitter).
    table1_trials : int, optional
        Registration trials Table 1 averages per model (:class:`Loaded`).
    """
    out_dir = Path(out_dir)
    loaded = Loaded(paths, seed, table1_trials)
    images = {spec.name: _png_bytes(spec.draw(loaded)) for spec in FIGURES if spec.name in drawn}
    for name, data in images.items():
        _write(out_dir / "figures" / f"{name}.png", data)
    every = [row for rows in loaded.tables1.values() for row in rows]
    rows = [{key: "" if isinstance(value, float) and math.isnan(value) else value for key, value in row.items()}
            for row in every]
    write_csv(out_dir / "table1.csv", rows, tables.table1_columns())
    shown = every + list(loaded.bunny_all_trials.values())
    _write(out_dir / "table1.md", markdown_table(["trials, EM", *TABLE1_HEADER],
                                                 [[f"{row['protocol']}, {row['variant']}", *_table1_cells(row)]
                                                  for row in shown]) + "\n")
    if loaded.authors is not None:
        write_csv(out_dir / "authors.csv", loaded.authors.rows, AUTHORS_COLUMNS)
    evaluated = claims.evaluate(loaded.measured, loaded.stored())
    document, evidence = blocks(loaded, drawn, evaluated), layout.ledger(evaluated, loaded.cells)
    _write(out_dir / "report.md", to_markdown(document))
    _write(out_dir / "claims.md", to_markdown(evidence))
    _write(out_dir / "report.html", to_html(document + evidence, images, TITLE))
