"""What a graded claim holds, the EM policy, and the helpers the claims share to read the sweep's tables.

Verdicts and rule kinds are defined once in :mod:`~.grading`. EM policy: every claim is graded twice, once on the
mixtures of textbook EM (the paper's equations 11-13) and once on those of the authors' published EM
(leonidk/direct_gmm: its E-step scales each primitive's Mahalanobis-plus-trace term by its area over the smallest
area and its M-step does not weight by area; it produced the paper's numbers). Point inputs are fitted by both alike
(textbook EM). The headline verdict is the authors' EM's (``HEADLINE``): a reproduction first asks whether what the
authors ran gives what they report; the textbook column says whether the method as the paper writes it does too.
Claims that involve no mixture fitted to a mesh get one verdict in both.
"""
from dataclasses import dataclass, field

import numpy as np

from dgmm.experiments.report.claims.grading import PENDING, REPRODUCED, Grade, TimeRatio, grade_time
from dgmm.experiments.sweep import SIZED, parse_input

VARIANTS = ("authors", "textbook")
HEADLINE = "authors"
VARIANT_NAMES = {"authors": "authors' EM", "textbook": "textbook EM"}

FIG3_MODEL = "bunny"
FIG3_INPUTS = ("res4-exact", "res4-approx", "res4-centroids", "res4-vertices")
FIG4_INPUTS = ("quadric1000-exact", "clustering1000-exact", "poisson1000-points", "random1000-points")


TEXT = "the paper's text"
NOTEBOOK = "the authors' notebooks (not in the paper's text; its figure is an image)"
WORDS = "the paper's words"
"""Where a paper value comes from (``Claim.source``)."""


@dataclass(frozen=True)
class Claim:
    """One claim of the paper, graded with both EMs.

    Attributes
    ----------
    section : str
        The paper's section that makes it ("§IV-A", "§VI-C", "§VII").
    figure : str
        The figure or table it is about ("Fig 3", "Table 1"), or "" for none; the report places it there.
    title : str
        The claim, in the paper's words where possible.
    rule : str
        The rule kind it is graded by and its margin, one line (kinds: :data:`~.grading.RULE_KINDS`).
    evidence : str
        Our numbers (Markdown); none for a timing claim, whose numbers are in ``timings``.
    grades : dict
        ``variant -> Grade`` for every variant of ``VARIANTS``.
    paper : str
        The paper's number or words the deciding number stands beside.
    source : str
        Where the paper value comes from: ``TEXT``, ``NOTEBOOK`` or ``WORDS``.
    timings : str
        A timing claim's numbers of this run (they go to the report's timing block); "" for other claims.
    """

    section: str
    figure: str
    title: str
    rule: str
    evidence: str
    grades: dict = field(default_factory=dict)
    paper: str = ""
    source: str = WORDS
    timings: str = ""

    @property
    def machine_dependent(self):
        """Whether it is a timing claim (its numbers change with the machine and the run)."""
        return bool(self.timings)

    @property
    def verdict(self):
        """The headline verdict (``HEADLINE``'s)."""
        return self.grades[HEADLINE].verdict

    @property
    def why(self):
        """The cause of every grade not reproduced, each named by its EM when the two EMs' causes differ."""
        causes = {v: self.grades[v].why for v in VARIANTS if self.grades[v].verdict != REPRODUCED
                  and self.grades[v].why}
        if len(set(causes.values())) == 1 and len(causes) == len(VARIANTS):
            return next(iter(causes.values()))
        return "\n".join(f"{VARIANT_NAMES[v]}: {why}" for v, why in causes.items())


def same(grade):
    """The same grade for every EM (a claim no mesh mixture enters)."""
    return {variant: grade for variant in VARIANTS}


def missing(what):
    """The grade of an EM whose data is missing: ``what`` names the table or run it needs."""
    return Grade(PENDING, "–", f"Needs {what}.")


def per_variant(grade):
    """Grades and evidence lines of a claim graded on each EM's mixtures.

    ``grade(variant)`` returns ``(Grade, evidence)``, or the :func:`missing` Grade alone when that EM's data are
    missing; each evidence line is named by its EM.

    Returns
    -------
    grades : dict
        ``variant -> Grade`` for every variant of ``VARIANTS``.
    lines : list of str
        ``"<EM>: <evidence>"`` of every EM that had data, in ``VARIANTS`` order.
    """
    grades, lines = {}, []
    for variant in VARIANTS:
        result = grade(variant)
        if isinstance(result, Grade):
            grades[variant] = result
        else:
            grades[variant], evidence = result
            lines.append(f"{VARIANT_NAMES[variant]}: {evidence}")
    return grades, lines


def pending(section, figure, title, rule, what, paper="", source=WORDS):
    """A claim waiting for data: ``what`` names the missing table or run."""
    return Claim(section, figure, title, rule, f"waiting for data: {what}.", same(missing(what)), paper, source)


def sentence(text):
    """``text`` as a sentence: first letter upper case, a final full stop ("" stays "")."""
    return f"{text[0].upper()}{text[1:]}." if text else ""


def fitted_variant(input_name, variant):
    """The EM variant whose fits of ``input_name`` stand for ``variant``: points are textbook EM in both."""
    return variant if parse_input(input_name)[1] in SIZED else "textbook"


def is_mesh(input_name):
    """Whether an input is fitted as sized primitives (exact or approximate triangles)."""
    return parse_input(input_name)[1] in SIZED


def cells(estimates, model, inputs, variant):
    """``(init, K) -> {input: Estimate}`` for ``model``'s ``inputs`` with mesh inputs fitted by ``variant``
    (``estimates``: :attr:`~.measurements.Measurements.estimates`)."""
    result = {}
    for (row_model, input_name, row_variant, init, k), value in estimates.items():
        if row_model == model and input_name in inputs and row_variant == fitted_variant(input_name, variant):
            result.setdefault((init, k), {})[input_name] = value
    return dict(sorted(result.items()))


def init_gaps(estimates, model, inputs, variant):
    """``(input, K) -> kmeans − random`` (an Estimate) for the ``inputs`` fitted from both starts."""
    table = cells(estimates, model, inputs, variant)
    return {(name, k): cell[name] - table[("random", k)][name]
            for (init, k), cell in table.items() if init == "kmeans"
            for name in inputs if name in cell and name in table.get(("random", k), {})}


def best(cell, names):
    """``(name, Estimate)`` of the highest mean among ``names`` in a cell (None when none was fitted)."""
    fitted = [(name, cell[name]) for name in names if name in cell]
    return max(fitted, key=lambda item: item[1].value, default=None)


def median(values):
    return float(np.median(values))


def mean(values):
    return float(np.mean(values))


MIN_REPEATS = 6
"""Fewest repeats a timing claim needs: below it no 95% interval of a median exists."""


def timing_claim(data, section, figure, title, check, ratio, target, paper, source=WORDS, cause=""):
    """A claim graded by the time-ratio rule on one check of timing_seconds.csv.

    Parameters
    ----------
    check : str
        The timing check (``check`` column).
    ratio : tuple of str
        ``(numerator, denominator)`` settings of the check.
    target : tuple of float
        ``(low, high)``: the range the claim puts the ratio in.
    cause : str
        Why, when the verdict is not reproduced: a cause that holds whatever the run's numbers (no numbers).
    """
    low, high = target
    bound = f"< {high:g}" if low == 0 else f"> {low:g}" if high == float("inf") else f"in [{low:g}, {high:g}]"
    rule = f"time ratio: {ratio[0]} / {ratio[1]} CPU seconds per repeat ({check} check) {bound}"
    ratios = data.time_ratios(check, *ratio)
    if len(ratios) < MIN_REPEATS:
        return pending(section, figure, title, rule, f"timing_seconds.csv with at least {MIN_REPEATS} repeats of "
                       f"the {check} check (config section `checks.timing`)", paper, source)
    measured = TimeRatio(ratios, low, high)
    seconds = {setting: float(np.median(list(by_repeat.values()))) for setting, by_repeat in
               data.seconds(check).items()}
    timings = f"{ratio[0]} / {ratio[1]}: {measured}; median CPU time " + ", ".join(
        f"{setting} {value * 1000:.3g} ms" for setting, value in seconds.items())
    return Claim(section, figure, title, rule, "", same(grade_time(measured, cause)), paper, source, timings)
