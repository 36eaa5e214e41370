"""A claim as data: a :class:`PerEmClaim` record holds a share rule's whole entry (the paper's words, the rule kind
and margin, the quantifier, and the plain functions that make its comparisons and its cause), and one grader,
:func:`grade`, turns a record and the :class:`~.measurements.Measurements` into a :class:`~.rules.Claim`.

The record's functions are module-level functions of the claim's module:

- ``comparisons(data, variant) -> (comparisons, evidence)``: the claim's comparisons on one EM's fits and its
  evidence line; None when that EM's fits are missing (a pending grade). An empty list is data with nothing to
  compare: inconclusive.
- ``cause(data, variant, grades, compared) -> Cause`` of a grade not reproduced. It sees both EMs' grades and
  comparisons (``variant -> list``), so that a cause can be the other EM's result on the same data and starts.
- ``premise(data, variant) -> Grade or None``: the not-reproduced grade of an EM whose data fails the claim's
  premise ("given some method in wrong minima"), which no comparison can count; None when the premise holds.

A twin of a record (:func:`twin`) grades the same rule on another view of the tables (Fig 4 at the authors' 100
iterations, the odometry at the authors' protocol): ``view(data) -> Measurements`` and ``waits(view) -> str or
None``, what the whole claim waits for on that view before either EM's fits (None: nothing).

One rule for the sentences: a grade partly or not reproduced gives its cause's sentence, an inconclusive one says the
data cannot tell (:func:`~.grading.grade_share`), and the cause goes to the evidence either way
(:func:`~.rules.explained`). A claim no EM has data for waits for the data it ``needs``.
"""
from dataclasses import dataclass, replace

from dgmm.experiments.report.claims.grading import INCONCLUSIVE, REPRODUCED, Quantifier, grade_share
from dgmm.experiments.report.claims.rules import (VARIANT_NAMES, VARIANTS, WORDS, Claim, explained, missing, pending,
                                                  same, waiting)

LIKELIHOOD = "likelihood.csv"
CONVERGENCE = "convergence.csv"
REGISTRATION = "registration.csv"
OPTIMISER_CHECK = "optimisers.csv"
IDENTITY_CHECK = "identities.csv"
RESAMPLING_CHECK = "resampling.csv"
ODOMETRY = "odometry.csv"
"""The sweep's and the checks' tables the records read (:attr:`PerEmClaim.table`)."""


@dataclass(frozen=True)
class PerEmClaim:
    """One claim graded by a share rule on each EM's fits; calling it on the Measurements grades it (:func:`grade`).

    Attributes
    ----------
    name : str
        Its name in the code, also its ``__name__`` (a twin graded on another view adds a suffix).
    words : str
        The paper's words it grades, quoted; also its ``__doc__``.
    section, figure, title, rule : str
        As :class:`~.rules.Claim`: ``rule`` states the rule kind, its margin and what one comparison is.
    quantifier : Quantifier
        How the comparisons are counted (:data:`~.grading.QUANTIFIERS`).
    comparisons, cause : callable
        The module-level functions that make its comparisons and its cause (see the module's docstring).
    table : str
        The table it reads (:data:`LIKELIHOOD`, :data:`CONVERGENCE`, :data:`REGISTRATION`, ...); its causes name the
        switch experiments they read (:attr:`~.rules.Cause.switch`).
    needs : str
        The fits or trials it needs, for a pending grade; ``{em}`` stands for the EM's name (each EM's where the
        claim waits as a whole).
    paper : str
        The paper's number or words the deciding number stands beside.
    source : str
        Where ``paper`` comes from (:data:`~.rules.TEXT`, :data:`~.rules.NOTEBOOK`, :data:`~.rules.WORDS`).
    evidence : str
        Template of the evidence: ``{lines}`` the EMs' evidence lines joined by ``separator``, ``{paper}`` the
        paper's value, and the fields of ``context``.
    separator : str
        What joins the EMs' evidence lines.
    ours : callable or None
        ``ours(data, variant, comparisons) -> str``, the grade's short number in place of the share's count (a claim
        of one comparison, or one decided by its worst case).
    mesh : bool
        Whether mesh fits enter its comparisons; when not (points are fitted by textbook EM in both), it gets one
        grade in both, textbook EM's.
    premise : callable or None
        ``premise(data, variant)``, the grade of an EM whose data fails the claim's premise (see the module's
        docstring); None: the claim has none.
    context : callable or None
        ``context(data) -> dict``: fields of the evidence that the tables give, beside the EMs' lines (what the tie
        bands rest on, what is missing); None: none.
    view, waits : callable or None
        A twin's view of the tables and what it waits for on it (see the module's docstring); None: the tables as
        given, waiting for nothing beyond each EM's fits.
    twin_of : PerEmClaim or None
        The record a twin grades on another view (its ``__wrapped__``, as :func:`~.claims.evaluate` reads it).
    """

    name: str
    words: str
    section: str
    figure: str
    title: str
    rule: str
    quantifier: Quantifier
    comparisons: object
    cause: object
    table: str
    needs: str
    paper: str
    source: str = WORDS
    evidence: str = "{lines}."
    separator: str = "; "
    ours: object = None
    mesh: bool = True
    premise: object = None
    context: object = None
    view: object = None
    waits: object = None
    twin_of: object = None

    def __post_init__(self):
        """Answer to ``__name__`` and ``__doc__`` as the claims written as functions do (twins and the tests read
        them)."""
        object.__setattr__(self, "__name__", self.name)
        object.__setattr__(self, "__doc__", self.words)
        if self.twin_of is not None:
            object.__setattr__(self, "__wrapped__", self.twin_of)

    def __call__(self, data):
        return grade(self, data)


def grade(claim, data):
    """The :class:`~.rules.Claim` of a :class:`PerEmClaim` on ``data``: each EM's comparisons counted under its
    quantifier, each grade not reproduced with its cause's sentence, and its evidence lines with the causes'
    findings; a twin grades its view, pending while the view lacks what it waits for."""
    data = claim.view(data) if claim.view else data
    waited = claim.waits(data) if claim.waits else None
    if waited:
        return pending(claim.section, claim.figure, claim.title, claim.rule, waited, claim.paper, claim.source)
    grades, lines = _graded_per_em(claim, data)
    if not claim.mesh:
        grades, lines = same(grades["textbook"]), [line.split(": ", 1)[1] for line in lines[-1:]]
    fields = claim.context(data) if claim.context else {}
    evidence = (claim.evidence.format(lines=claim.separator.join(lines), paper=claim.paper, **fields) if lines
                else waiting(claim.needs.format(em="each EM")))
    return Claim(claim.section, claim.figure, claim.title, claim.rule, evidence, grades, claim.paper, claim.source)


def twin(claim, suffix, title, view, waits):
    """``claim`` graded on another view of the tables: named with ``suffix``, its title followed by ``title`` in
    brackets."""
    return replace(claim, name=f"{claim.name}_{suffix}", title=f"{claim.title} ({title})", view=view, waits=waits,
                   twin_of=claim)


def _graded_per_em(claim, data):
    """``variant -> Grade``, each partly or not reproduced with its cause's sentence, and the ``"<EM>: <evidence>"``
    lines of every EM that had fits, each with its cause (:func:`~.rules.explained`)."""
    grades, compared, evidence, unmet = {}, {}, {}, {}
    for variant in VARIANTS:
        made = claim.comparisons(data, variant)
        if made is None:
            grades[variant] = missing(claim.needs.format(em=VARIANT_NAMES[variant]))
            continue
        compared[variant], evidence[variant] = made
        unmet[variant] = claim.premise(data, variant) if claim.premise else None
        grades[variant] = unmet[variant] or _counted(claim, data, variant, compared[variant])
    causes = {variant: claim.cause(data, variant, grades, compared) for variant in compared
              if grades[variant].verdict != REPRODUCED and not unmet[variant]}
    lines = [f"{VARIANT_NAMES[variant]}: {explained(evidence[variant], causes.get(variant), grades[variant].verdict)}"
             for variant in compared]
    return {variant: replace(grade, why=causes[variant].why) if variant in causes and grade.verdict != INCONCLUSIVE
            else grade for variant, grade in grades.items()}, lines


def _counted(claim, data, variant, comparisons):
    """The grade of ``comparisons`` under the claim's quantifier, with its own short number when it has one."""
    grade = grade_share(comparisons, claim.quantifier)
    return grade if claim.ours is None else replace(grade, ours=claim.ours(data, variant, comparisons))
