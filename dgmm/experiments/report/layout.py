"""The report's text around the graded claims: the findings in prose, the summary table, the claims by the paper's
sections beside their figures, the grading rules defined once, and the timing block.

Everything here is a function of the verdicts and of the numbers that do not change between runs of one commit;
a timing claim's numbers go only to the timing block, which :func:`without_timings` strips to compare two runs.
"""
import re

from dgmm.experiments.report import claims
from dgmm.experiments.report.claims import grading
from dgmm.experiments.report.authors import ITEMS as AUTHORS_ITEMS
from dgmm.experiments.report.claims.rules import NOTEBOOK, TEXT, WORDS, first_section
from dgmm.experiments.report.document import BADGE_MARKS


VERDICT_ORDER = (grading.REPRODUCED, grading.PARTLY, grading.NOT, grading.INCONCLUSIVE, grading.TIMING_NOISE,
                 grading.PENDING)
SOURCE_MARKS = {NOTEBOOK: "ᴺ", TEXT: "", WORDS: ""}
"""Mark of a paper value by where it comes from (:data:`~.claims.rules.NOTEBOOK`: not in the paper's text)."""
TIMING_START, TIMING_END = "<!-- timings: the only part that changes from run to run -->", "<!-- /timings -->"


def claim_anchor(index):
    """Anchor of the ``index``-th claim's details."""
    return f"claim-{index + 1}"


def section_anchor(section):
    return "section-" + section.lstrip("§").lower()


def figure_anchor(figure):
    """Anchor of a claim's figure or table ("Fig 6" → "fig6", "Table 1" → "table1"; "" → None)."""
    match = re.fullmatch(r"(Fig|Table) (\d+)", figure)
    return f"{match[1].lower()}{match[2]}" if match else None


def _grade_text(grade):
    return f"{{{{{grade.verdict}}}}} {grade.ours}".rstrip()


SUMMARY_HEADER = ["section", "claim — why, when not reproduced",
                  *("ours, " + claims.VARIANT_NAMES[v] + (" (headline)" if v == claims.HEADLINE else "")
                    for v in claims.VARIANTS), "the authors' data", "paper's text"]
CONTRADICTED = "The authors' own stored data"
"""How the summary opens what the authors' data says of a claim it does not fully bear out: the paper's text against
the paper's data, not our failure to reproduce."""


def _stored_text(claim):
    return "–" if claim.on_stored is None else _grade_text(claim.on_stored)


def _why(claim):
    """The cause of a claim not reproduced, led by what the authors' data says when it does not bear it out."""
    stored = claim.on_stored
    if stored is not None and stored.verdict == grading.NOT:
        said = f"{CONTRADICTED} does not bear it out either ({stored.ours})."
    elif stored is not None and stored.verdict == grading.PARTLY:
        said = f"{CONTRADICTED} bears it out only partly ({stored.ours})."
    else:
        return claim.why
    return "\n".join(filter(None, [said, claim.why]))


def summary_rows(evaluated):
    """One row per claim: its section, its title linked to its place in its section's list with
    the cause when not reproduced, each EM's verdict and deciding number on our data, the headline EM's on the
    authors' stored data (– where it stores nothing the rule reads), the paper's value (marked by source; none where
    the paper's value is its words, which the title gives)."""
    return [[claim.section,
             f"[{claim.title}](#{claim_anchor(index)})" + (f"\n{_why(claim)}" if _why(claim) else ""),
             *(_grade_text(claim.grades[v]) for v in claims.VARIANTS), _stored_text(claim),
             claim.paper + SOURCE_MARKS[claim.source] if claim.source != WORDS and claim.paper else ""]
            for index, claim in enumerate(evaluated)]


def stored_findings(evaluated, cells):
    """The opening's counts of the authors' data: how many of the paper's statements hold on it, and how many of
    our cells reproduce their stored values (``cells``: :class:`~dgmm.experiments.report.authors.Cell`)."""
    graded = [claim for claim in evaluated if claim.on_stored is not None]
    verdicts = [claim.on_stored.verdict for claim in graded]
    both = sum(claim.on_stored.verdict == grading.REPRODUCED and claim.verdict == grading.REPRODUCED
               for claim in graded)
    counts = reproduced_by_figure(cells)
    items = "; ".join(f"{figure} {done}/{compared}" for figure, (done, compared) in counts.items())
    contradicted = [claim for claim in graded if claim.on_stored.verdict in (grading.NOT, grading.PARTLY)]
    return [
        f"The authors' own data (their notebooks' stored outputs, authors.csv) can grade {len(graded)} of the "
        f"paper's statements: on it, {', '.join(f'{{{{{v}}}}} {verdicts.count(v)}' for v in VERDICT_ORDER if v in verdicts)}"
        f". {len(contradicted)} statements are not fully borne out by the paper's own data; the summary says so "
        f"where it says why ours are not. {both} hold on both their data and ours (headline EM).",
        f"Our sweep reproduces {sum(done for done, _ in counts.values())} of the "
        f"{sum(compared for _, compared in counts.values())} stored values it has cells for ({items}; a cell reproduces when our mean is inside the tie band of two means with our "
        "seeds' standard error, plus the stored value's rounding). Every cell is listed in claims.md.",
    ] if cells or graded else []


def _counts(evaluated, variant):
    verdicts = [claim.grades[variant].verdict for claim in evaluated]
    return ", ".join(f"{{{{{v}}}}} {verdicts.count(v)}" for v in VERDICT_ORDER if v in verdicts)


def findings(evaluated):
    """The prose at the top: the counts of each EM, what the headline EM reproduces by the paper's sections, and
    how often the two EMs disagree."""
    headline, other = claims.HEADLINE, next(v for v in claims.VARIANTS if v != claims.HEADLINE)
    by_section = {}
    for claim in evaluated:
        by_section.setdefault(first_section(claim), []).append(claim)
    sections = "; ".join(f"{section} {sum(c.verdict == grading.REPRODUCED for c in listed)}/{len(listed)}"
                         for section, listed in by_section.items())
    split = sum(claim.grades[headline].verdict != claim.grades[other].verdict for claim in evaluated)
    return [
        f"We graded {len(evaluated)} claims of the paper on our sweep, each on the mixtures of both EMs. With the "
        f"{claims.VARIANT_NAMES[headline]} (the code that produced the paper's numbers, the headline): "
        f"{_counts(evaluated, headline)}. With {claims.VARIANT_NAMES[other]} (the paper's equations 11–13): "
        f"{_counts(evaluated, other)}. Claims that fit no mixture to a mesh get one verdict in both; the two EMs "
        f"disagree on {split}, and where the headline reproduces and textbook EM does not, the switch between them "
        "(the authors' E-step scales each triangle's terms by its area) is the measured cause.",
        f"Reproduced with the headline EM, by the paper's sections: {sections}. Each section below lists its claims "
        "(marks: the authors' EM's verdict, then textbook EM's) beside its figures; every claim's numbers and rule "
        "are in the evidence ledger, claims.md.",
    ]


def grading_rules():
    """The rule kinds, verdicts and value sources, defined once for every claim."""
    kinds = [f"**{kind}**: {text}." for kind, text in grading.RULE_KINDS.items()]
    return kinds + [
        f"**verdicts**: {', '.join(VERDICT_ORDER)} (a table the claim needs is missing); inconclusive and within "
        "timing noise are no verdict: the data cannot tell, a rerun could tell it either way. Not reproduced names its "
        "measured cause (an experiment that switches it and moves the verdict) or \"cause not found\" and what was "
        "tried; an inconclusive claim's cause, when one was looked for, is in its evidence.",
        f"**paper values**: the paper's text, or {SOURCE_MARKS[NOTEBOOK]} the authors' notebooks (not in the text; "
        "the figure is an image).",
    ]


def claim_item(claim):
    """A claim as its section lists it: both EMs' verdict marks (authors' first) and the claim; a timing claim
    points to the timing block, every claim to its line in the evidence ledger."""
    marks = "".join(BADGE_MARKS[claim.grades[v].verdict] for v in claims.VARIANTS)
    timing = " ([timings](#timings))" if claim.timings else ""
    return f"{marks} {claim.title}{timing}"


def ledger_item(claim, reproduced=None):
    """A claim in the evidence ledger: its verdicts, the paper's value and source, our numbers and the rule; where
    the authors' data grades it, that verdict and how many of our cells of its figure reproduce their stored values
    (``reproduced``: ``figure -> (reproduced, compared)``)."""
    grades = "; ".join(f"{claims.VARIANT_NAMES[v]} {_grade_text(claim.grades[v])}" for v in claims.VARIANTS)
    evidence = claim.evidence or "its numbers are in the report's timing block."
    source = "" if claim.source != NOTEBOOK else " (authors' notebooks)"
    stored = ""
    if claim.on_stored is not None:
        count = (reproduced or {}).get(claim.figure)
        cells = f"; our {claim.figure} cells reproduce {count[0]} of their {count[1]} stored values" if count else ""
        stored = f" On the authors' stored data (their means, our noise): {_grade_text(claim.on_stored)}{cells}."
    return re.sub(r"\.\.(?= |$)", ".", f"**{claim.title}** ({claim.section}) — {grades}. "
                  f"Paper: {claim.paper or '–'}{source}. Ours: {evidence}{stored} Rule: {claim.rule}.")


def reproduced_by_figure(cells):
    """``figure name -> (cells reproduced, cells compared)`` of :class:`~dgmm.experiments.report.authors.Cell`."""
    result = {}
    for cell in cells:
        if cell.reproduced is not None:
            done, compared = result.get(AUTHORS_ITEMS[cell.item], (0, 0))
            result[AUTHORS_ITEMS[cell.item]] = (done + cell.reproduced, compared + 1)
    return result


def ledger(evaluated, cells=()):
    """The evidence ledger (``claims.md``): every claim's numbers, in the report's order, then every stored value of
    the authors' beside ours (``cells``)."""
    return [("h1", "The claims' evidence"),
            ("p", "Our numbers behind each verdict of [the report](report.md), claim by claim, in the report's "
                  "order (rule kinds: the report's \"How the claims are graded\")."),
            ("list", [ledger_item(claim, reproduced_by_figure(cells)) for claim in evaluated],
             [f"evidence-{index + 1}" for index in range(len(evaluated))]),
            *cell_tables(cells)]


CELL_HEADER = ["cell", "theirs", "their iterations", "ours ± standard error", "ours − theirs", "band", "reproduced"]


def _cell_row(cell):
    if cell.ours is None:
        return [cell.label, cell.printed, cell.n_iter or "–", "–", "–", "–", "not in our sweep"]
    return [cell.label, cell.printed, cell.n_iter or "–", f"{cell.ours.value:.4f} ± {cell.ours.error:.4f}",
            f"{cell.difference:+.4f}", f"±{cell.band:.4f}", "yes" if cell.reproduced else "no"]


def cell_tables(cells):
    """One table per item of the authors' stored values: theirs, ours, the difference against its band."""
    if not cells:
        return []
    result = [("h2", "The authors' stored values beside ours", "stored-values"),
              ("p", "Each stored value of the authors' notebooks (authors.csv: notebook and cell) against our cell of "
                    "the same input, start and K: mesh inputs fitted by the authors' EM, point inputs by textbook EM "
                    "(the same algorithm). The band is the tie band of two means with our seeds' standard error "
                    "(the notebooks store no spread) plus half the stored value's last printed digit.")]
    for item, title in AUTHORS_ITEMS.items():
        listed = [cell for cell in cells if cell.item == item]
        if listed:
            units = ", ".join(dict.fromkeys(cell.unit for cell in listed))
            result += [("h3", f"{title} ({units})", f"stored-{item}"),
                       ("table", CELL_HEADER, [_cell_row(cell) for cell in listed])]
    return result


def timing_block(evaluated):
    """The run's timing numbers, one line per timing claim, between markers that :func:`without_timings`
    finds."""
    lines = [f"[claim {index + 1}](#{claim_anchor(index)}), {claim.section}: {claim.timings}."
             for index, claim in enumerate(evaluated) if claim.timings]
    return [("p", TIMING_START), ("list", lines or ["no timing claim has its data yet"]), ("p", TIMING_END)]


def without_timings(markdown):
    """``markdown`` with its timing block cut out: what two runs of one commit must agree on byte for byte."""
    start, end = markdown.find(TIMING_START), markdown.find(TIMING_END)
    return markdown if start < 0 or end < 0 else markdown[:start] + markdown[end + len(TIMING_END):]
