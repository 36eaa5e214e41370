"""The claims' shared vocabulary: verdicts, the two kinds of rule, the EM policy, and what a graded claim holds.

Verdicts are ``reproduced``, ``partly``, ``not reproduced`` or ``pending`` (a table the claim needs is missing).
Most rules are one of two kinds, stated with every claim in the report:

- a *gap* rule: a difference in nats is within ``SAME_NATS`` (reproduced) or ``CLOSE_NATS`` (partly);
- a *share* rule: the claim holds in at least ``MOST`` of the comparisons it makes (reproduced), at least half
  (partly), or fewer (not reproduced). Claims the paper words with "often" use ``OFTEN``.

EM policy: every claim is graded twice, once on the mixtures of textbook EM (the paper's equations 11-13) and once
on those of the authors' published EM (leonidk/direct_gmm: its E-step scales each primitive's Mahalanobis-plus-trace
term by its area over the smallest area and its M-step does not weight by area; it produced the paper's numbers).
Point inputs are fitted by both alike (textbook EM). The headline verdict is the authors' EM's (``HEADLINE``): a
reproduction first asks whether what the authors ran gives what they report; the textbook column says whether the
method as the paper writes it does too. Claims that involve no mixture fitted to a mesh get one verdict in both.
"""
import math
from dataclasses import dataclass, field

import numpy as np

from dgmm.experiments.sweep import SIZED, parse_input

SAME_NATS = 0.1
"""Two mean log-likelihoods this close (nats per evaluation point) count as equal."""
CLOSE_NATS = 0.5
"""... and this close as about equal (half a nat: less than the gap between mesh and point fits in Fig 3)."""
ROBUST_NATS = 0.25
"""A fit is robust to initialisation at a K when k-means and random starts end this close (nats)."""
MOST = 0.9
"""Share of comparisons a claim must win to count as reproduced (at least half: partly)."""
OFTEN = 0.5
"""Share a claim worded "often" must win to count as reproduced (at least a quarter: partly)."""

REPRODUCED, PARTLY, NOT, PENDING = "reproduced", "partly", "not reproduced", "pending"
VARIANTS = ("authors", "textbook")
HEADLINE = "authors"
VARIANT_NAMES = {"authors": "authors' EM", "textbook": "textbook EM"}

FIG3_MODEL = "bunny"
FIG3_INPUTS = ("res4-exact", "res4-approx", "res4-centroids", "res4-vertices")
FIG4_INPUTS = ("quadric1000-exact", "clustering1000-exact", "poisson1000-points", "random1000-points")

GAP_RULE = (f"gap rule: |difference| ≤ {SAME_NATS} nat reproduced, ≤ {CLOSE_NATS} nat partly, "
            "larger not reproduced")
SHARE_RULE = f"share rule: holds in ≥ {MOST:.0%} of comparisons reproduced, ≥ 50% partly, fewer not reproduced"
OFTEN_RULE = (f"share rule for \"often\": holds in ≥ {OFTEN:.0%} of comparisons reproduced, ≥ 25% partly, fewer "
              "not reproduced")
MACHINE = "a time ratio measured within one run: it changes with the machine and its load"


@dataclass(frozen=True)
class Grade:
    """One EM's verdict on a claim.

    Attributes
    ----------
    verdict : str
        ``REPRODUCED``, ``PARTLY``, ``NOT`` or ``PENDING``.
    ours : str
        The number that decides it (short, for the summary table).
    why : str
        When not reproduced: the measured cause, one sentence; when pending: what is missing.
    """

    verdict: str
    ours: str = ""
    why: str = ""


@dataclass(frozen=True)
class Claim:
    """One claim of the paper, graded with both EMs.

    Attributes
    ----------
    section : str
        Where the paper makes it ("Fig 3", "§V-A", "Table 1", ...); a "Fig n" or "Table n" links to it.
    title : str
        The claim, in the paper's words where possible.
    rule : str
        How a verdict follows from the evidence.
    evidence : str
        Our numbers (Markdown).
    grades : dict
        ``variant -> Grade`` for every variant of ``VARIANTS``.
    paper : str
        The paper's number or words the deciding number stands beside.
    machine_dependent : bool
        A timing claim: its numbers are CPU-time ratios of one run.
    """

    section: str
    title: str
    rule: str
    evidence: str
    grades: dict = field(default_factory=dict)
    paper: str = ""
    machine_dependent: bool = False

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


def gap_verdict(gap):
    """Verdict of a gap rule on ``|gap|`` in nats."""
    return REPRODUCED if abs(gap) <= SAME_NATS else PARTLY if abs(gap) <= CLOSE_NATS else NOT


def share_verdict(wins, total, most=MOST, half=0.5):
    """Verdict of a share rule: ``wins`` of ``total`` comparisons (``total`` > 0) hold."""
    share = wins / total
    return REPRODUCED if share >= most else PARTLY if share >= half else NOT


def often_verdict(wins, total):
    """Verdict of a share rule for a claim worded "often"."""
    return share_verdict(wins, total, OFTEN, OFTEN / 2)


def ratio_verdict(ratio, reproduced, partly):
    """Verdict of a ratio that must lie in the interval ``reproduced`` (else ``partly``, else not reproduced)."""
    inside = lambda interval: interval[0] <= ratio <= interval[1]  # noqa: E731
    return REPRODUCED if inside(reproduced) else PARTLY if inside(partly) else NOT


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


def pending(section, title, rule, what, paper="", machine_dependent=False):
    """A claim waiting for data: ``what`` names the missing table or run."""
    return Claim(section, title, rule, f"waiting for data: {what}.", same(missing(what)), paper, machine_dependent)


def sentence(text):
    """``text`` as a sentence: first letter upper case, a final full stop ("" stays "")."""
    return f"{text[0].upper()}{text[1:]}." if text else ""


def lost(comparisons, limit=3):
    """``why`` of a share rule: the first ``limit`` comparisons that did not hold, as one sentence."""
    if not comparisons:
        return ""
    more = f" and {len(comparisons) - limit} more" if len(comparisons) > limit else ""
    return "Fails where " + "; ".join(comparisons[:limit]) + more + "."


def fitted_variant(input_name, variant):
    """The EM variant whose fits of ``input_name`` stand for ``variant``: points are textbook EM in both."""
    return variant if parse_input(input_name)[1] in SIZED else "textbook"


def is_mesh(input_name):
    """Whether an input is fitted as sized primitives (exact or approximate triangles)."""
    return parse_input(input_name)[1] in SIZED


def cells(means, model, inputs, variant):
    """``(init, K) -> {input: mean}`` for ``model``'s ``inputs`` with mesh inputs fitted by ``variant``."""
    result = {}
    for (row_model, input_name, row_variant, init, k), (mean, _) in means.items():
        if row_model == model and input_name in inputs and row_variant == fitted_variant(input_name, variant):
            result.setdefault((init, k), {})[input_name] = mean
    return dict(sorted(result.items()))


def init_gaps(means, model, inputs, variant):
    """``(input, K) -> kmeans − random`` for the ``inputs`` fitted from both starts."""
    table = cells(means, model, inputs, variant)
    return {(name, k): cell[name] - table[("random", k)][name]
            for (init, k), cell in table.items() if init == "kmeans"
            for name in inputs if name in cell and name in table.get(("random", k), {})}


def best(cell, names):
    """Highest mean among ``names`` in a cell (−inf when none was fitted)."""
    return max((cell[name] for name in names if name in cell), default=-math.inf)


def median(values):
    return float(np.median(values))


def mean(values):
    return float(np.mean(values))
