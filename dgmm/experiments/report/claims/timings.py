"""Claims graded by the time-ratio rule on a timing check (timing_seconds.csv): the paper's words against the
interval of a median ratio of interleaved CPU times. Each is a :class:`TimingClaim` record, graded by
:func:`grade_timing`."""
from dataclasses import dataclass

import numpy as np

from dgmm.experiments.report.claims.grading import TimeRatio, grade_time
from dgmm.experiments.report.claims.rules import WORDS, Cause, Claim, pending, same, sentence


MIN_REPEATS = 6
"""Fewest repeats a timing claim needs: below it no 95% interval of a median exists."""


@dataclass(frozen=True)
class TimingClaim:
    """One claim graded by the time-ratio rule on one check of timing_seconds.csv; calling it on the Measurements
    grades it (:func:`grade_timing`). No mixture enters a timing ratio as a mesh EM's: one grade serves both EMs.

    Attributes
    ----------
    name : str
        Its name in the code, also its ``__name__``.
    words : str
        The paper's words it grades, quoted; also its ``__doc__``.
    section, figure, title, paper, source : str
        As :class:`~.rules.Claim`.
    check : str
        The timing check (timing_seconds.csv's ``check`` column).
    ratio : tuple of str
        ``(numerator, denominator)`` settings of the check.
    target : tuple of float
        ``(low, high)``: the range the claim puts the ratio in.
    cause : Cause or callable
        Why, when the verdict is not reproduced, or ``cause(data) -> Cause`` when it reads the tables: a sentence that
        holds whatever the run's seconds (no timing numbers; deterministic counts are fine); its finding is the
        claim's evidence.
    beside : tuple
        ``((numerator, denominator), name)`` of other ratios of the check, set beside in the timings ungraded (ours
        beside the paper's setup).
    """

    name: str
    words: str
    section: str
    figure: str
    title: str
    check: str
    ratio: tuple
    target: tuple
    paper: str
    source: str = WORDS
    cause: object = Cause("")
    beside: tuple = ()

    def __post_init__(self):
        """Answer to ``__name__`` and ``__doc__`` as the claims written as functions do."""
        object.__setattr__(self, "__name__", self.name)
        object.__setattr__(self, "__doc__", self.words)

    def __call__(self, data):
        return grade_timing(self, data)

    @property
    def rule(self):
        """The rule, one line: the ratio, its check and the range the claim puts it in."""
        low, high = self.target
        bound = f"< {high:g}" if low == 0 else f"> {low:g}" if high == float("inf") else f"in [{low:g}, {high:g}]"
        return f"time ratio: {self.ratio[0]} / {self.ratio[1]} CPU seconds per repeat ({self.check} check) {bound}"


def grade_timing(claim, data):
    """The :class:`~.rules.Claim` of a :class:`TimingClaim` on ``data``: pending below :data:`MIN_REPEATS` repeats;
    else the ratio's verdict with the cause's sentence, the cause's finding as the evidence, and the numbers (the
    ratio's, the median CPU times, the ratios set beside) in the timings."""
    args = (claim.section, claim.figure, claim.title, claim.rule)
    ratios = data.time_ratios(claim.check, *claim.ratio)
    if len(ratios) < MIN_REPEATS:
        return pending(*args, f"timing_seconds.csv with at least {MIN_REPEATS} repeats of the {claim.check} check "
                       "(config section `checks.timing`)", claim.paper, claim.source)
    measured = TimeRatio(ratios, *claim.target)
    cause = claim.cause if isinstance(claim.cause, Cause) else claim.cause(data)
    return Claim(*args, sentence(cause.finding), same(grade_time(measured, cause.why)), claim.paper, claim.source,
                 _timings(claim, data, measured))


def _timings(claim, data, measured):
    """The timing block's line: the graded ratio, the median CPU time of every setting of the check, then each ratio
    set beside that has enough repeats."""
    seconds = {setting: float(np.median(list(by_repeat.values()))) for setting, by_repeat in
               data.seconds(claim.check).items()}
    line = f"{claim.ratio[0]} / {claim.ratio[1]}: {measured}; median CPU time " + ", ".join(
        f"{setting} {value * 1000:.3g} ms" for setting, value in seconds.items())
    for ratio, name in claim.beside:
        ratios = data.time_ratios(claim.check, *ratio)
        if len(ratios) >= MIN_REPEATS:
            line += f"; {name}, {ratio[0]} / {ratio[1]}: {TimeRatio(ratios)}"
    return line
