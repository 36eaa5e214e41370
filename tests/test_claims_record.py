"""The claim record and its grader (dgmm.experiments.report.claims.record) on hand-made comparisons: one rule for an
inconclusive grade's sentence and its cause, one evidence for a claim waiting for data, an EM with data but nothing
to compare, a premise that fails, and a twin on another view of the tables."""
from functools import partial

from dgmm.experiments.report.claims.grading import EVERY, NOT, PLAIN, Grade, compare
from dgmm.experiments.report.claims.measurements import Measurements
from dgmm.experiments.report.claims.record import LIKELIHOOD, PerEmClaim, twin
from dgmm.experiments.report.claims.rules import Cause

MARGINS = {"authors": (1.0, 0.0), "textbook": (1.0, -1.0)}
"""Per EM, the margins of its comparisons (band 0.5): authors' 1 won, 1 tied; textbook's 1 won, 1 lost."""
TIED = {"authors": (0.0, 0.0), "textbook": (1.0, -1.0)}
"""As :data:`MARGINS`, the authors' every comparison tied."""


def _comparisons(margins, data, variant):
    compared = [compare(f"cell {index}", margin, band=0.5) for index, margin in enumerate(margins[variant])]
    return compared, f"{variant} numbers"


def _none(data, variant):
    return None


def _nothing_compared(data, variant):
    return [], f"{variant} numbers"


def _cause(finding):
    return lambda data, variant, grades, compared: Cause(f"Cause of {variant}.", finding)


def record(comparisons=partial(_comparisons, MARGINS), cause=_cause("measured"), quantifier=EVERY, **fields):
    return PerEmClaim("made_up", "The paper's words.", "§IV-A", "", "A made-up claim", "share, every", quantifier,
                      comparisons=comparisons, cause=cause, table=LIKELIHOOD, needs="made-up fits", paper="always",
                      **fields)


def test_an_inconclusive_grade_says_the_data_cannot_tell_and_its_cause_goes_to_the_evidence():
    claim = record(quantifier=PLAIN)(Measurements())
    # authors': 1 won, 1 tied: as many untied as tied: reproduced; textbook: 1 won, 1 lost: not reproduced
    assert claim.grades["textbook"] == Grade(NOT, "1/2 won", "Cause of textbook.")
    claim = record()(Measurements())
    assert claim.grades["textbook"].why == "Cause of textbook."
    claim = record(comparisons=partial(_comparisons, TIED))(Measurements())
    assert claim.grades["authors"].verdict == "inconclusive"
    assert claim.grades["authors"].why == "The data cannot tell: all 2 comparisons lie inside their noise."
    assert "authors' EM: authors numbers; cause: measured" in claim.evidence
    # a cause with no finding: its sentence goes to the evidence, as a clause
    claim = record(comparisons=partial(_comparisons, TIED), cause=_cause(""))(Measurements())
    assert "authors' EM: authors numbers; cause: of authors" in claim.evidence
    assert claim.evidence.endswith("textbook numbers.")  # its sentence is in the summary: not repeated


def test_a_record_without_data_waits_for_the_data_it_needs_as_a_function_claim_does():
    claim = record(comparisons=_none)(Measurements())
    assert claim.verdict == "pending" and claim.why == "Needs made-up fits."
    assert claim.evidence == "waiting for data: made-up fits."


def test_data_with_nothing_to_compare_is_inconclusive_not_pending():
    claim = record(comparisons=_nothing_compared)(Measurements())
    assert claim.grades["authors"].verdict == "inconclusive" and claim.grades["authors"].ours == "0/0 won"
    assert claim.evidence == "authors' EM: authors numbers; cause: measured; textbook EM: textbook numbers; cause: " \
                             "measured."


def test_a_premise_that_fails_is_not_reproduced_with_its_own_sentence_and_no_cause():
    unmet = Grade(NOT, "no premise", "The premise fails.")
    claim = record(premise=lambda data, variant: unmet if variant == "textbook" else None)(Measurements())
    assert claim.grades["textbook"] == unmet and claim.grades["authors"].verdict == "reproduced"
    assert claim.evidence == "authors' EM: authors numbers; textbook EM: textbook numbers."


def test_a_twin_grades_the_same_rule_on_its_view_and_waits_for_what_the_view_lacks():
    base = record()
    twin_claim = twin(base, "at_100", "another view", view=lambda data: data.at_iterations(100),
                      waits=lambda view: None if view.max_iter == 100 else "fits at 100 iterations")
    assert twin_claim.__name__ == "made_up_at_100" and twin_claim.__wrapped__ is base
    graded = twin_claim(Measurements())
    assert graded.title == "A made-up claim (another view)" and graded.grades == base(Measurements()).grades
    waiting = twin(base, "x", "y", view=lambda data: data, waits=lambda view: "fits at 100 iterations")
    assert waiting(Measurements()).evidence == "waiting for data: fits at 100 iterations."
