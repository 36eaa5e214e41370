"""The grading framework: each claim's verdict follows from one of four rule kinds, each defined here once.

- **comparison**: one number of ours against another, in the direction the claim states, with a *tie band* from
  the measured noise of the two: Student's t (97.5%, the difference's Welch-Satterthwaite degrees of freedom) times
  the standard error of their difference. Beyond the band it is won or lost; inside it, tied, and a tie counts
  neither way.
- **share**: a claim's comparisons counted under the paper's quantifier (:data:`QUANTIFIERS`). The data can tell a
  claim when its untied comparisons are no fewer than the ties. Universal words ("every", "always") need no untied
  comparison lost; a plain comparative ("A fits better than B") allows one loss in ten among the untied comparisons;
  "often" needs half of all the comparisons won. Where what is untied bears the claim out but the data cannot tell
  it (every comparison tied, or more ties than untied ones), the verdict is *inconclusive*. "Partly" needs wins
  beyond chance (a one-sided sign test at 5% over the untied comparisons, never a coin flip).
- **equivalence**: a number within a stated margin of a target (the paper's value, zero, a ratio's 1): each is a
  comparison whose margin is the distance left to the edge, and its claim a share of them.
- **time ratio**: CPU-time ratios of interleaved repeats; their median's 95% interval (order statistics, no
  assumption on the distribution) must clear the claim's threshold for a verdict, else the claim is *within timing
  noise*: a rerun could flip it, so it gets no verdict.
"""
import math
from dataclasses import dataclass

import numpy as np
from scipy.stats import binom, binomtest, t

REPRODUCED, PARTLY, NOT, INCONCLUSIVE, TIMING_NOISE, PENDING = (
    "reproduced", "partly", "not reproduced", "inconclusive", "within timing noise", "pending")
VERDICTS = (REPRODUCED, PARTLY, NOT, INCONCLUSIVE, TIMING_NOISE, PENDING)
WIN, TIE, LOSS = "won", "tied", "lost"

BAND_ERRORS = 2.0
"""Standard deviations of one Monte Carlo draw that bound a sampled value (the §II identity's check)."""
BAND_LEVEL = 0.975
"""A tie band is Student's t at this quantile times the standard error of the difference compared (a two-sided 95%
band; 1.96 standard errors when the degrees of freedom are unbounded, 4.30 at 2)."""
ALPHA = 0.05
"""Level of the one-sided sign test that "partly" needs, and one minus the timing interval's coverage."""
PLAIN_SHARE = 0.9
"""Share of the untied comparisons a plain comparative must win."""
OFTEN, SOMETIMES = 0.5, 0.25
"""Shares of all comparisons that "often" needs for reproduced and for partly."""
BOOTSTRAP = 1000
"""Resamples of the paired bootstrap that gives a statistic's standard error over registration trials."""


@dataclass(frozen=True)
class Comparison:
    """One comparison a claim makes.

    Attributes
    ----------
    label : str
        Where it is made ("kmeans K=25", "armadillo rotation").
    margin : float
        How far it goes the claim's way (> 0 supports the claim), in the compared quantity's unit.
    band : float
        Its tie band: ``|margin| <= band`` is a tie.
    detail : str
        The numbers compared, for the evidence ("exact 7.62 vs centroids 7.70").
    """

    label: str
    margin: float
    band: float = 0.0
    detail: str = ""

    @property
    def outcome(self):
        """``WIN``, ``TIE`` or ``LOSS``."""
        return WIN if self.margin > self.band else LOSS if self.margin < -self.band else TIE

    def __str__(self):
        return f"{self.label}: {self.detail}" if self.detail else self.label


@dataclass(frozen=True)
class Estimate:
    """A measured number, its standard error and the degrees of freedom of that error (unbounded for a bootstrap
    over many trials); differences carry the error of both sides, with Welch-Satterthwaite's degrees of freedom."""

    value: float
    error: float = 0.0
    dof: float = math.inf

    def __sub__(self, other):
        error = math.hypot(self.error, other.error)
        parts = sum(e ** 4 / d for e, d in ((self.error, self.dof), (other.error, other.dof)) if e > 0)
        return Estimate(self.value - other.value, error, error ** 4 / parts if parts > 0 else math.inf)

    def __neg__(self):
        return Estimate(-self.value, self.error, self.dof)

    def __format__(self, spec):
        return format(self.value, spec)

    @property
    def band(self):
        """Half-width of the tie band: Student's t at :data:`BAND_LEVEL` with ``dof`` times ``error``."""
        return band_multiplier(self.dof) * self.error


def band_multiplier(dof):
    """Student's t at :data:`BAND_LEVEL` with ``dof`` degrees of freedom (the normal quantile when unbounded)."""
    return float(t.ppf(BAND_LEVEL, dof))


def estimate(values):
    """Mean of ``values`` with its standard error (sample standard deviation over √n; 0 for one value) on
    ``n - 1`` degrees of freedom."""
    values = np.asarray(values, dtype=float)
    error = float(np.std(values, ddof=1) / np.sqrt(len(values))) if len(values) > 1 else 0.0
    return Estimate(float(np.mean(values)), error, max(len(values) - 1, 1))


def compare(label, difference, *, higher=True, band=None, detail=""):
    """Comparison of a claim that ``difference`` (ours − other) is above zero (``higher``) or below it.

    ``difference`` is an :class:`Estimate`, whose tie band is :attr:`Estimate.band`, or a number with an explicit
    ``band``.
    """
    if isinstance(difference, Estimate):
        value, band = difference.value, difference.band if band is None else band
    else:
        value, band = float(difference), 0.0 if band is None else band
    return Comparison(label, value if higher else -value, band, detail)


def within(label, value, target, margin, *, detail=""):
    """Equivalence: ``value`` within ``margin`` of ``target`` (won inside, lost outside; no tie zone: the margin
    already holds the noise)."""
    return Comparison(label, margin - abs(value - target), 0.0, detail)


def inside(label, ours, low, high, *, detail=""):
    """Equivalence of ``ours`` (an :class:`Estimate`) with a range the paper's words give ("about three": 2.5 to
    3.5): won when its whole tie band lies inside, lost when the band lies wholly outside, tied otherwise."""
    return Comparison(label, min(ours.value - low, high - ours.value), ours.band,
                      detail or f"ours {ours.value:.1f} ± {ours.band:.1f}, paper {low:g} to {high:g}")


def versus_paper(label, ours, published, decimals, *, paper_error=None, detail=""):
    """Equivalence of ``ours`` (an :class:`Estimate`) with a published value printed to ``decimals`` places: within
    the tie band of the difference of the two plus half the paper's last printed digit. The paper's standard error is
    ``paper_error`` (an :class:`Estimate` of zero value carrying it and its degrees of freedom), by default ours: the
    same protocol and seeds."""
    paper = Estimate(0.0, ours.error, ours.dof) if paper_error is None else paper_error
    margin = (ours - paper).band + 0.5 * 10.0 ** -decimals
    return within(label, ours.value, published, margin,
                  detail=detail or f"ours {ours.value:.{decimals + 1}f}, paper {published:.{decimals}f}")


def same_protocol_error(ours, trials, paper_trials):
    """The standard error of a mean the paper took over ``paper_trials`` trials, from ours over ``trials`` (the same
    protocol: the spread of one trial is the same), as :func:`versus_paper`'s ``paper_error``."""
    return Estimate(0.0, ours.error * math.sqrt(trials / paper_trials), ours.dof)


def magnitude(difference):
    """``|difference|`` of an :class:`Estimate`, with its error: how far apart two means are, either way."""
    return Estimate(abs(difference.value), difference.error)


def bootstrap(statistic, *samples, seed=0):
    """``statistic(*samples)`` over paired samples (the same registration trials), with its standard error from a
    seeded paired bootstrap: :data:`BOOTSTRAP` resamples of the pairs, the same for every statistic of the same
    trials; ``statistic`` takes numpy's ``axis``."""
    samples = [np.asarray(sample, dtype=float) for sample in samples]
    picks = np.random.default_rng(seed).integers(0, len(samples[0]), size=(BOOTSTRAP, len(samples[0])))
    resampled = statistic(*(sample[picks] for sample in samples), axis=1)
    return Estimate(float(statistic(*samples)), float(np.std(resampled, ddof=1)))


def paired_difference(first, second, statistic=np.mean, seed=0):
    """``statistic(first) − statistic(second)`` over paired samples, its standard error from :func:`bootstrap`."""
    return bootstrap(lambda a, b, axis=None: statistic(a, axis=axis) - statistic(b, axis=axis), first, second,
                     seed=seed)


@dataclass(frozen=True)
class Tally:
    """A claim's comparisons counted: won, tied and lost, with the sign test over the untied ones."""

    comparisons: tuple

    def of(self, outcome):
        return [c for c in self.comparisons if c.outcome == outcome]

    @property
    def counts(self):
        return tuple(len(self.of(outcome)) for outcome in (WIN, TIE, LOSS))

    @property
    def sign_test(self):
        """One-sided p-value of the wins among the untied comparisons under a fair coin (1 when none)."""
        wins, _, losses = self.counts
        return float(binomtest(wins, wins + losses, 0.5, alternative="greater").pvalue) if wins + losses else 1.0

    def beyond_chance(self):
        return self.sign_test < ALPHA

    def __str__(self):
        wins, ties, losses = self.counts
        return f"{wins} won, {ties} tied, {losses} lost"


@dataclass(frozen=True)
class Quantifier:
    """How the paper's words count a claim's comparisons.

    Attributes
    ----------
    name : str
        ``"every"``, ``"plain"`` or ``"often"``.
    words : str
        The paper's words it stands for.
    rule : str
        The rule, as the report states it.
    """

    name: str
    words: str
    rule: str

    def holds(self, tally):
        """Whether the claim's share holds on the comparisons counted (ties count neither way, except for
        "often", whose share is of all)."""
        wins, ties, losses = tally.counts
        if self.name == "often":
            return wins >= OFTEN * (wins + ties + losses)
        if self.name == "every":
            return wins > 0 and not losses
        return wins > 0 and wins >= PLAIN_SHARE * (wins + losses) - 1e-9  # float-safe share

    def verdict(self, tally):
        """Verdict of a :class:`Tally` of at least one comparison."""
        wins, ties, losses = tally.counts
        if self.holds(tally):
            return REPRODUCED if wins + losses >= ties else INCONCLUSIVE
        if wins + losses == 0:
            return INCONCLUSIVE
        if self.name == "often":
            return PARTLY if wins >= SOMETIMES * (wins + ties + losses) else NOT
        return PARTLY if tally.beyond_chance() else NOT


PARTLY_RULE = "partly when the wins are beyond chance (sign test)"
TELLS_RULE = ("the data tell a claim when its untied comparisons are no fewer than the ties; where they cannot, "
              "a share that holds on the untied ones, or a claim whose every comparison is tied, is *inconclusive*")
EVERY = Quantifier("every", "every, all, always, never", "reproduced when no untied comparison is lost")
PLAIN = Quantifier("plain", "a plain comparative, usually, largely", f"reproduced when ≥ {PLAIN_SHARE:.0%} of the "
                   "untied comparisons are won")
OFTEN_WORDS = Quantifier("often", "often", f"reproduced when ≥ {OFTEN:.0%} of all comparisons are won, partly at "
                         f"≥ {SOMETIMES:.0%}")
QUANTIFIERS = (EVERY, PLAIN, OFTEN_WORDS)


def median_interval(values, alpha=ALPHA):
    """Median of ``values`` and its distribution-free ``1 − alpha`` interval: the ``k``-th order statistic from
    either end, ``k`` the largest with ``P(Binomial(n, ½) < k) ≤ alpha / 2`` (at least 1: below 6 values the
    interval is the whole range, which covers less than ``1 − alpha``)."""
    ordered = np.sort(np.asarray(values, dtype=float))
    n = len(ordered)
    k = 1
    while k < n // 2 and binom.cdf(k, n, 0.5) <= alpha / 2:
        k += 1
    return float(np.median(ordered)), (float(ordered[k - 1]), float(ordered[n - k]))


def time_verdict(interval, low=0.0, high=math.inf):
    """Verdict of a time ratio whose interval is ``interval`` for a claim that it lies in ``[low, high]``:
    reproduced inside, not reproduced outside, within timing noise across an edge."""
    lower, upper = interval
    if low <= lower and upper <= high:
        return REPRODUCED
    if upper < low or lower > high:
        return NOT
    return TIMING_NOISE


@dataclass(frozen=True)
class Grade:
    """One EM's verdict on a claim.

    Attributes
    ----------
    verdict : str
        One of :data:`VERDICTS`.
    ours : str
        What decides it, short, for the summary table (no timing numbers: those change from run to run).
    why : str
        When not reproduced: the measured cause, one short sentence for the summary table (the numbers behind it go
        to the claim's evidence); when pending: what is missing.
    """

    verdict: str
    ours: str = ""
    why: str = ""


def grade_share(comparisons, quantifier, cause=""):
    """Grade of a share rule: ``comparisons`` counted under ``quantifier``; ``cause`` is kept when the verdict is
    partly or not reproduced; an inconclusive one says how many comparisons the noise leaves undecided."""
    tally = Tally(tuple(comparisons))
    wins, ties, losses = tally.counts
    verdict = quantifier.verdict(tally)
    ours = f"{wins}/{wins + ties + losses} won" + (f", {ties} tied" if ties else "")
    if verdict == INCONCLUSIVE:
        cause = "The data cannot tell: " + _undecided(wins, ties, losses)
    return Grade(verdict, ours, "" if verdict == REPRODUCED else cause)


def _undecided(wins, ties, losses):
    """Which of an inconclusive grade's comparisons the noise leaves undecided, as a sentence."""
    if wins + losses:
        return (f"{ties} of {wins + ties + losses} comparisons lie inside their noise; the untied ones bear the claim "
                "out.")
    if ties == 1:
        return "its one comparison lies inside its noise."
    return f"all {ties} comparisons lie inside their noise."


@dataclass(frozen=True)
class TimeRatio:
    """A time ratio from interleaved repeats: its median, its interval and the claim's range for it."""

    ratios: tuple
    low: float = 0.0
    high: float = math.inf

    @property
    def median(self):
        return median_interval(self.ratios)[0]

    @property
    def interval(self):
        return median_interval(self.ratios)[1]

    @property
    def verdict(self):
        return time_verdict(self.interval, self.low, self.high)

    def __str__(self):
        lower, upper = self.interval
        return f"median {self.median:.3g}, 95% interval [{lower:.3g}, {upper:.3g}] over {len(self.ratios)} repeats"


def grade_time(ratio, cause=""):
    """Grade of a time-ratio rule from a :class:`TimeRatio`; its numbers stay out of the grade (they go to the
    timing block)."""
    verdict = ratio.verdict
    target = (f"< {ratio.high:g}" if ratio.low == 0 else f"> {ratio.low:g}" if ratio.high == math.inf
              else f"in [{ratio.low:g}, {ratio.high:g}]")
    ours = {REPRODUCED: "interval ", NOT: "interval not ", TIMING_NOISE: "interval across "}[verdict] + target
    return Grade(verdict, ours, "" if verdict == REPRODUCED else cause)


RULE_KINDS = {
    "comparison": "ours against another number in the claim's direction, tied within Student's t (97.5%, the "
                  "difference's degrees of freedom) standard errors of the difference (the seeds' spread of the "
                  "sweep's fits; a paired bootstrap over registration trials: 1.96); a tie counts neither way",
    "share": "the comparisons counted by the paper's quantifier: " + "; ".join(
        f"*{q.name}* ({q.words}) {q.rule}" for q in QUANTIFIERS)
    + f"; {TELLS_RULE}; for *every* and *plain*, {PARTLY_RULE} (one-sided, {ALPHA:.0%}, over the untied "
    "comparisons)",
    "equivalence": "a number within a stated margin of a target (the paper's value, zero, rounding, a Monte Carlo "
                   "integral's noise), counted as a share; against a range a word gives (\"about three\"), won with "
                   "the whole tie band inside, lost wholly outside, tied across",
    "time ratio": f"CPU-time ratios of interleaved repeats; the median's {1 - ALPHA:.0%} interval (order statistics) "
                  f"inside the claim's range: reproduced, outside: not, across its edge: *{TIMING_NOISE}*, no verdict "
                  "(a rerun could flip it); the numbers are only in the timing block",
}
"""The four rule kinds, as the report defines them once."""
