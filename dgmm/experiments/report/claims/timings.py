"""Claims graded by the time-ratio rule on a timing check (timing_seconds.csv): the paper's words against the
interval of a median ratio of interleaved CPU times."""
from dataclasses import replace

import numpy as np

from dgmm.experiments.report.claims.grading import TimeRatio, grade_time
from dgmm.experiments.report.claims.rules import WORDS, Cause, Claim, pending, same, sentence


MIN_REPEATS = 6
"""Fewest repeats a timing claim needs: below it no 95% interval of a median exists."""


def timing_claim(data, section, figure, title, check, ratio, target, paper, source=WORDS, cause=Cause("")):
    """A claim graded by the time-ratio rule on one check of timing_seconds.csv.

    Parameters
    ----------
    check : str
        The timing check (``check`` column).
    ratio : tuple of str
        ``(numerator, denominator)`` settings of the check.
    target : tuple of float
        ``(low, high)``: the range the claim puts the ratio in.
    cause : Cause
        Why, when the verdict is not reproduced: a sentence that holds whatever the run's seconds (no timing
        numbers; deterministic counts are fine); its finding is the claim's evidence.
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
    return Claim(section, figure, title, rule, sentence(cause.finding), same(grade_time(measured, cause.why)), paper,
                 source, timings)


def beside(claim, data, check, ratio, name):
    """``claim`` (a :func:`timing_claim`) with another ratio of its timing check in its timings, ungraded (ours
    beside the paper's setup); unchanged while the check has too few repeats."""
    ratios = data.time_ratios(check, *ratio)
    if len(ratios) < MIN_REPEATS or not claim.timings:
        return claim
    return replace(claim, timings=f"{claim.timings}; {name}, {ratio[0]} / {ratio[1]}: {TimeRatio(ratios)}")
