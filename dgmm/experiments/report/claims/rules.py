"""What a graded claim holds, the EM policy, and the helpers the claims share to read the sweep's tables.

Verdicts and rule kinds are defined once in :mod:`~.grading`. EM policy: every claim is graded twice, once on the
mixtures of textbook EM (the paper's equations 11-13) and once on those of the authors' published EM
(leonidk/direct_gmm: its E-step scales each primitive's Mahalanobis-plus-trace term by its area over the smallest
area and its M-step does not weight by area; it produced the paper's numbers). Point inputs are fitted by both alike
(textbook EM). The headline verdict is the authors' EM's (``HEADLINE``): a reproduction first asks whether what the
authors ran gives what they report; the textbook column says whether the method as the paper writes it does too.
Claims that involve no mixture fitted to a mesh get one verdict in both.

A grade partly or not reproduced names its cause in one sentence (``Grade.why``, for the summary table); an
inconclusive one says that the data cannot tell; the numbers behind the cause, the cells and what was tried, go to the
claim's evidence (:class:`Cause`, :func:`explained`).
"""
import math
from dataclasses import dataclass, field

import numpy as np

from dgmm.experiments.report.claims.grading import INCONCLUSIVE, LOSS, PENDING, REPRODUCED, TIE, WIN, Grade, Tally
from dgmm.experiments.sweep import SIZED, parse_input

VARIANTS = ("authors", "textbook")
HEADLINE = "authors"
VARIANT_NAMES = {"authors": "authors' EM", "textbook": "textbook EM"}

FIG3_MODEL = "bunny"
FIG3_INPUTS = ("res4-exact", "res4-approx", "res4-centroids", "res4-vertices")
FIG4_INPUTS = ("quadric1000-exact", "clustering1000-exact", "poisson1000-points", "random1000-points")
HIGH_K = 200
"""K from which point inputs of 1000 points or fewer collapse from k-means starts (5 points a component or fewer)."""
SCALING = "the authors' E-step area scaling"
"""What differs between the two EMs: the authors' E-step multiplies each triangle's Mahalanobis-plus-trace term by its
area over the smallest area, which sharpens the responsibilities, and their M-step does not weight by area. The sweep
switches both at once; run apart (:data:`HALVES`), the E-step's scaling is the half that moves the likelihoods."""


@dataclass(frozen=True)
class Study:
    """A study the sweep does not run, whose numbers a cause quotes: typed by hand, they go stale unless the study is
    rerun (``command``) on the sweep's tables and ``doc`` and the quote updated with it."""

    doc: str
    command: str


EM_HALVES = Study("docs/studies/em_halves.md", "python benchmarks/studies/em_halves.py --likelihood "
                  "results/tables/likelihood.csv --data results/data --inputs <two mesh inputs>")
"""The authors' EM's two halves (E-step scaling, M-step without area weights), each run alone."""
HALVES = ("its E-step half alone lands nearer the authors' EM in 51 of Fig 3's and Fig 4's 56 mesh cells, all the "
          "difference from random starts and about two thirds from k-means (docs/studies/em_halves.md)")
"""What :data:`EM_HALVES` measured, quoted by hand (a cause that quotes it names ``EM_HALVES`` as its study)."""

ERROR_NAMES = {"rot": "rotation", "trans": "translation"}
"""The registration errors (registration.csv's rotation and translation columns)."""
WRONG_MINIMUM_DEG = 45.0
"""A trial whose rotation error exceeds this ended farther from the truth than it started, in a wrong local minimum:
no trial rotates more (three Euler angles of at most 15°, config `registration.max_angle_deg`, compose to a rotation
of at most their sum)."""
SIMILAR_TIME = (0.78, 1.28)
"""Time ratios the paper's "similar", "approximately match" and "roughly match" allow: closer than the 22% that
§VI-D reports as a difference ("22% faster", a time ratio of 0.78), either way (1 / 0.78 ≈ 1.28). A ratio beyond
the upper end is "much faster"."""
SIGNIFICANT = SIMILAR_TIME[0]
"""What "significantly" needs beyond the noise (§VI-C's "often significantly"): a practical size, the same 22% the
report reads as a difference: a mean error below 0.78 of the other's, or a per-sample likelihood above 1 / 0.78 of the
other's (a mean log-likelihood margin above log(1 / 0.78) ≈ 0.25 nat). The paper's own Table 1 margins pass both."""
SIGNIFICANT_NAT = math.log(1 / SIGNIFICANT)
"""A practically significant likelihood margin, in nat: a per-sample likelihood 1 / 0.78 times the other's. Within
it, likelihoods are "very similar"."""


SECTION_TITLES = {
    "§I": "I. Introduction",
    "§II": "II. Method",
    "§III": "III. Modifying EM to account for triangles",
    "§III-A": "III-A. Evaluating the derived loss function",
    "§IV": "IV. Results",
    "§IV-A": "IV-A. Mesh input data",
    "§IV-B": "IV-B. Mesh decimation",
    "§IV-C": "IV-C. Discussion",
    "§V-A": "V-A. Generalization to other primitives",
    "§VI-A": "VI-A. Mesh registration",
    "§VI-B": "VI-B. Analysis of mesh registration",
    "§VI-C": "VI-C. Other 3D models",
    "§VI-D": "VI-D. Visual odometry",
    "§VII": "VII. Conclusion",
}
"""The paper's sections that make claims, in the paper's order."""


def first_section(claim):
    """The section a claim is listed under: the first it names ("§I, §VII" → "§I")."""
    return claim.section.split(",")[0].strip()


def in_paper_order(evaluated):
    """Claims sorted by the paper's section that makes them (stable within a section)."""
    order = list(SECTION_TITLES)
    return sorted(evaluated, key=lambda claim: order.index(first_section(claim)) if first_section(claim) in order
                  else len(order))


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
    on_stored : Grade or None
        The headline EM's grade on the authors' stored data (:mod:`dgmm.experiments.report.authors`); None where
        their data cannot grade it.
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
    on_stored: Grade = None

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
        """The cause of every grade not reproduced, one sentence each, named by its EM when the two EMs' causes
        differ."""
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


def waiting(what):
    """The evidence of a claim waiting for data: ``what`` names the missing table or run."""
    return f"waiting for data: {what}."


def pending(section, figure, title, rule, what, paper="", source=WORDS):
    """A claim waiting for data: ``what`` names the missing table or run."""
    return Claim(section, figure, title, rule, waiting(what), same(missing(what)), paper, source)


def capital(text):
    """``text`` with its first letter upper case."""
    return text[:1].upper() + text[1:]


def sentence(text):
    """``text`` as a sentence: first letter upper case, a final full stop ("" stays "")."""
    return f"{capital(text)}." if text else ""


def em(variant):
    """The EM's name inside a sentence: "the authors' EM", "textbook EM"."""
    return f"the {VARIANT_NAMES[variant]}" if variant == "authors" else VARIANT_NAMES[variant]


def other_em(variant):
    """The other EM variant of ``VARIANTS``."""
    return next(other for other in VARIANTS if other != variant)


def is_mesh(input_name):
    """Whether an input is fitted as sized primitives (exact or approximate triangles)."""
    return parse_input(input_name)[1] in SIZED


def fitted_variant(input_name, variant):
    """The EM variant whose fits of ``input_name`` stand for ``variant``: points are textbook EM in both."""
    return variant if is_mesh(input_name) else "textbook"


def wrong_minima(rotation_errors):
    """Trials (a boolean mask) that ended in a wrong local minimum: rotation error beyond :data:`WRONG_MINIMUM_DEG`."""
    return np.asarray(rotation_errors) > WRONG_MINIMUM_DEG


# -- causes -----------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Cause:
    """Why a grade is not reproduced.

    Attributes
    ----------
    why : str
        The measured cause in one short sentence, for the summary table (``Grade.why``).
    finding : str
        What was measured behind it (the cells, the numbers, what was tried), a clause for the claim's evidence;
        "" when the sentence says it all.
    switch : str
        The switch experiments it reads, each a job of the sweep that changes one thing, named with its table
        (:data:`EM_VARIANTS`, :data:`LONGER_FITS`, :data:`OWN_CELLS`); "" when it reads none.
    study : Study or None
        The study outside the sweep whose hand-typed numbers the sentence quotes; None when every number in it comes
        from the sweep's tables.
    """

    why: str
    finding: str = ""
    switch: str = ""
    study: Study = None


EM_VARIANTS = ("the EM (config fit.variants): the authors' against textbook on the same inputs and start methods, in "
               "the claim's own table")
"""The sweep's EM switch: every mesh input fitted by both EMs (seeds differ by EM)."""
LONGER_FITS = ("the iterations (the convergence check, config checks.convergence): Fig 3's first seeds run on from "
               "the paper's 25 to 100, in convergence.csv")
"""The iteration switch."""
COARSE_TO_FINE = ("the registration optimiser: the coarse-to-fine P2D (method mesh-kmeans-c2f) on the same mixture "
                  "and trials as the paper's P2D, in registration.csv")
"""The optimiser switch of the registration claims."""
OWN_CELLS = "the claim's own cells singled out (a start method, a K, an input), in its table"
"""No switch run for it: the cause is read off the claim's own comparisons."""


def explained(evidence, cause, verdict):
    """``evidence`` of a grade of ``verdict`` with its ``cause`` appended: the cause's finding; for an inconclusive
    grade, whose sentence says only that the data cannot tell, the cause's own sentence when it has no finding
    (unchanged when nothing is left to say: a sentence of a grade partly or not reproduced is in the summary)."""
    said = cause and (cause.finding or (verdict == INCONCLUSIVE and clause(cause.why)))
    return f"{evidence}; cause: {said}" if said else evidence


def clause(text):
    """A cause's sentence as a clause after "cause:": no final stop, no leading "Cause", first letter lower case
    ("Cause not found: x." → "not found: x")."""
    text = text.rstrip(".").removeprefix("Cause ")
    return text[:1].lower() + text[1:]


def misses(comparisons):
    """What keeps a share from being reproduced: its lost comparisons, or its tied ones when none is lost."""
    lost = [c for c in comparisons if c.outcome == LOSS]
    return lost or [c for c in comparisons if c.outcome == TIE]


def switched(compared, variant, other):
    """Labels of the comparisons ``variant`` does not win and ``other`` wins: the same comparison, only the EM
    changed."""
    won = {c.label for c in compared.get(other) or [] if c.outcome == WIN}
    return [c.label for c in compared[variant] if c.outcome != WIN and c.label in won]


def _how_many(part, whole):
    """``"the one"``, ``"all 3"`` or ``"2 of the 3"`` comparisons."""
    return ("the one comparison" if whole == 1 else f"all {whole} comparisons" if part == whole
            else f"{part} of the {whole} comparisons")


def _not_won(comparisons):
    """What an EM does with the comparisons it does not win: "ties", "loses" or "does not win"."""
    outcomes = {c.outcome for c in comparisons}
    return "ties" if outcomes == {TIE} else "loses" if outcomes == {LOSS} else "does not win"


def em_switch(finding, variant, grades, compared):
    """A :class:`Cause` that is the EM: the other EM wins, on the same data from the same start method (seeds differ
    by EM), comparisons that ``variant`` does not; ``finding`` (what ``variant``'s fits do, with their numbers) and
    the other EM's grade go to the evidence. None when the other EM wins none of them."""
    other = other_em(variant)
    flipped = switched(compared, variant, other)
    if not flipped:
        return None
    missed = [c for c in compared[variant] if c.outcome != WIN]
    return Cause(f"{capital(SCALING)}: {em(other)} wins {_how_many(len(flipped), len(missed))} this EM "
                 f"{_not_won(missed)}.",
                 f"{finding}; {em(other)} on the same data and start method wins {len(flipped)} of the {len(missed)} "
                 f"({grades[other].ours}, {grades[other].verdict}): the authors' EM is the switch, and of its two "
                 f"halves {HALVES}", EM_VARIANTS, study=EM_HALVES)


def by_cause(missed, causes):
    """One sentence for the comparisons ``missed`` (all lost or all tied, :func:`misses`) that several causes share:
    ``causes`` lists ``(label, count, sentence)``; one cause gives its own sentence, several their labels and counts
    (their numbers are in the evidence)."""
    if len(causes) == 1:
        return causes[0][2]
    return (f"{len(missed)} comparisons {missed[0].outcome}, by cause: "
            + "; ".join(f"{label} ({count})" for label, count, _ in causes) + ".")


def conjoined(names):
    """``"a"``, ``"a and b"``, ``"a, b and c"``."""
    names = list(names)
    return " and ".join(filter(None, (", ".join(names[:-1]), names[-1]))) if names else ""


def switch_or_not_found(finding, variant, grades, compared):
    """:func:`em_switch` when the other EM wins what ``variant`` does not, else "cause not found" (the other EM was
    tried), with ``finding`` for the evidence."""
    missed = [c for c in compared[variant] if c.outcome != WIN]
    return em_switch(finding, variant, grades, compared) or Cause(
        f"Cause not found: {em(other_em(variant))} on the same data and starts does not win "
        f"{'it' if len(missed) == 1 else 'them'} either.", finding, EM_VARIANTS)


# -- the likelihood claims' evidence and grades ---------------------------------------------------------------------

SPELLED = 14
"""A share's evidence spells out every comparison up to this many (beyond it, the tied and lost ones)."""


def listed(comparisons):
    """``(comparisons, their listing)`` of a record's comparisons (:mod:`~.record`); None when there are none: the
    fits they need are missing."""
    return (comparisons, listing(comparisons)) if comparisons else None


def listing(comparisons, spelled=SPELLED):
    """Evidence of a share: every comparison with its numbers and outcome when there are at most ``spelled``,
    else the number won and every tied and lost one."""
    if len(comparisons) <= spelled:
        return "; ".join(f"{comparison} ({comparison.outcome})" for comparison in comparisons)
    tally = Tally(tuple(comparisons))
    parts = [f"{len(tally.of(WIN))} won"]
    for outcome in (TIE, LOSS):
        if tally.of(outcome):
            parts.append(f"{len(tally.of(outcome))} {outcome} ({'; '.join(map(str, tally.of(outcome)))})")
    return ", ".join(parts)


def unwon(comparisons):
    """The comparisons not won, for evidence that lists the numbers elsewhere ("" when every one is won)."""
    lost = [str(c) for c in comparisons if c.outcome == LOSS]
    tied = [c.label for c in comparisons if c.outcome == TIE]
    return "".join(f"; {kind}: {', '.join(items)}" for kind, items in (("lost", lost), ("tied", tied)) if items)
