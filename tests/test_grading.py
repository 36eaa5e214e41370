"""The grading framework's rule kinds on hand-made numbers, each verdict worked out by hand."""
import math

import numpy as np
import pytest
from scipy.stats import binom

from dgmm.experiments.report.claims.grading import (EVERY, INCONCLUSIVE, LOSS, NOT, OFTEN_WORDS, PARTLY, PLAIN,
                                                    REPRODUCED, TIE, TIMING_NOISE, WIN, Estimate, Tally, TimeRatio,
                                                    bootstrap, compare, estimate, grade_share, grade_time, inside,
                                                    magnitude, median_interval, paired_difference,
                                                    same_protocol_error, versus_paper, within)


def outcomes(wins, ties, losses):
    """Comparisons with these counts (margins of ±1 against a band of 0.5, ties at 0)."""
    return ([compare(f"w{i}", 1.0, band=0.5) for i in range(wins)]
            + [compare(f"t{i}", 0.2, band=0.5) for i in range(ties)]
            + [compare(f"l{i}", -1.0, band=0.5) for i in range(losses)])


def test_a_comparison_inside_its_band_is_a_tie_whichever_way_it_leans():
    difference = Estimate(7.28, 0.02) - Estimate(7.29, 0.02)  # 0.01 below, band 1.96·√(0.02²+0.02²) = 0.055
    assert math.isclose(difference.error, math.hypot(0.02, 0.02))
    assert compare("a", difference).outcome == TIE
    assert compare("a", Estimate(0.06, 0.02)).outcome == WIN  # 0.06 > 1.96 × 0.02 (a bootstrap: unbounded dof)
    assert compare("a", Estimate(0.06, 0.02), higher=False).outcome == LOSS
    assert compare("a", Estimate(0.0391, 0.02)).outcome == TIE  # 0.0391 ≤ 1.95996 × 0.02 = 0.03920: a tie


def test_the_band_is_students_t_on_the_differences_degrees_of_freedom():
    # Three seeds each (2 degrees of freedom): t(0.975, 2) = 4.303; the difference of two such means with equal
    # errors has Welch-Satterthwaite's (2e²)² / (2e⁴/2) = 4 degrees of freedom: t = 2.776.
    three = Estimate(1.0, 0.1, 2)
    assert math.isclose(three.band, 0.4303, abs_tol=1e-4)
    difference = three - Estimate(0.5, 0.1, 2)
    assert math.isclose(difference.dof, 4.0)
    assert math.isclose(difference.band, 2.776 * math.hypot(0.1, 0.1), rel_tol=1e-3)
    # 0.35 apart is a win at 1.96 (band 0.277) and a tie at t(4) (band 0.393).
    assert compare("a", Estimate(1.0, 0.1) - Estimate(0.65, 0.1)).outcome == WIN
    assert compare("a", three - Estimate(0.65, 0.1, 2)).outcome == TIE
    # Unequal errors: Welch-Satterthwaite weighs the larger error's dof: (0.1² + 0.01²)² / (0.1⁴/2 + 0.01⁴/9) ≈ 2.04.
    welch = (0.1 ** 2 + 0.01 ** 2) ** 2 / (0.1 ** 4 / 2 + 0.01 ** 4 / 9)
    assert math.isclose((three - Estimate(0.0, 0.01, 9)).dof, welch)
    # estimate(): n − 1 degrees of freedom
    assert estimate([1.0, 2.0, 4.0]).dof == 2


def test_estimate_is_the_mean_with_the_standard_error():
    values = [1.0, 2.0, 4.0]
    assert estimate(values) == Estimate(7 / 3, float(np.std(values, ddof=1)) / math.sqrt(3), 2)
    assert estimate([5.0]).error == 0.0


def test_ties_count_neither_way():
    assert Tally(tuple(outcomes(3, 5, 0))).counts == (3, 5, 0)
    assert grade_share(outcomes(5, 3, 0), PLAIN).verdict == REPRODUCED  # the ties are no loss
    assert grade_share(outcomes(5, 3, 1), PLAIN).verdict == NOT  # 5 of 6 untied: 83% < 90%; P(X ≥ 5 | 6) = 0.11
    assert grade_share(outcomes(3, 5, 0), PLAIN).verdict == INCONCLUSIVE  # mostly undecided: fewer untied than ties
    assert grade_share(outcomes(8, 0, 0), EVERY).verdict == REPRODUCED
    assert grade_share(outcomes(0, 4, 0), EVERY).verdict == INCONCLUSIVE  # nothing shown beyond noise either way
    assert grade_share(outcomes(0, 4, 0), PLAIN).verdict == INCONCLUSIVE
    assert grade_share(outcomes(0, 4, 0), OFTEN_WORDS).verdict == INCONCLUSIVE


def test_a_never_claim_with_ties_is_reproduced_when_the_data_can_tell_it():
    # "Exact never prefers random": 6 won, 4 tied, 0 lost. Ties count neither way; the untied (6) are no fewer than
    # the ties (4), and none is lost: reproduced (it used to be "partly": a tie demoted a universal claim).
    grade = grade_share(outcomes(6, 4, 0), EVERY)
    assert (grade.verdict, grade.ours) == (REPRODUCED, "6/10 won, 4 tied")
    # 3 won, 5 tied: what is untied bears it out, but most comparisons cannot tell: inconclusive, saying so.
    grade = grade_share(outcomes(3, 5, 0), EVERY, "a cause")
    assert grade.verdict == INCONCLUSIVE
    assert grade.why == ("The data cannot tell: 5 of 8 comparisons lie inside their noise; the untied ones bear the "
                         "claim out.")
    assert grade_share(outcomes(0, 3, 0), EVERY).why == ("The data cannot tell: all 3 comparisons lie inside their "
                                                          "noise.")
    assert grade_share(outcomes(0, 1, 0), EVERY).why == ("The data cannot tell: its one comparison lies inside its "
                                                          "noise.")
    # one loss among ties: the claim's share fails on what is untied; not beyond chance -> not reproduced
    assert grade_share(outcomes(0, 5, 1), EVERY).verdict == NOT


def test_a_universal_claim_fails_on_one_loss_unless_the_rest_is_beyond_chance():
    # 4 won, 1 lost: P(X ≥ 4 | n=5) = 6/32 = 0.19, not beyond chance
    assert grade_share(outcomes(4, 0, 1), EVERY).verdict == NOT
    # 9 won, 1 lost: P(X ≥ 9 | n=10) = 11/1024 = 0.011 < 0.05
    assert grade_share(outcomes(9, 0, 1), EVERY).verdict == PARTLY


@pytest.mark.parametrize("wins, losses, verdict", [
    (12, 12, NOT),        # a coin flip is never partly
    (17, 7, PARTLY),      # P(X ≥ 17 | 24) = 0.032
    (16, 8, NOT),         # P(X ≥ 16 | 24) = 0.076
    (18, 2, REPRODUCED),  # losses 2 ≤ 10% of 20
    (17, 3, PARTLY),      # 3 > 10% of 20, P(X ≥ 17 | 20) = 0.0013
])
def test_a_plain_comparative_allows_one_loss_in_ten_and_partly_needs_the_sign_test(wins, losses, verdict):
    assert grade_share(outcomes(wins, 0, losses), PLAIN).verdict == verdict


def test_the_sign_test_edge():
    """The smallest win count that is beyond chance over 24 untied comparisons, from the binomial tail."""
    edge = next(k for k in range(25) if binom.sf(k - 1, 24, 0.5) < 0.05)
    assert edge == 17
    assert Tally(tuple(outcomes(edge, 0, 24 - edge))).beyond_chance()
    assert not Tally(tuple(outcomes(edge - 1, 0, 25 - edge))).beyond_chance()


def test_often_counts_the_wins_among_all_comparisons():
    assert grade_share(outcomes(5, 5, 0), OFTEN_WORDS).verdict == REPRODUCED  # 5/10 = 50%
    assert grade_share(outcomes(3, 7, 0), OFTEN_WORDS).verdict == PARTLY  # 30% ≥ 25%
    assert grade_share(outcomes(2, 6, 2), OFTEN_WORDS).verdict == NOT  # 20%


def test_a_cause_is_kept_only_when_not_reproduced():
    assert grade_share(outcomes(2, 0, 0), EVERY, "because").why == ""
    assert grade_share(outcomes(0, 0, 2), EVERY, "because").why == "because"


def test_equivalence_within_a_margin():
    assert within("x", 8.64, 8.62, 0.03).outcome == WIN
    assert within("x", 8.66, 8.62, 0.03).outcome == LOSS
    # against a paper value printed to 2 decimals, the paper's error taken as ours (unbounded dof):
    # 1.96·√2 × 0.005 + 0.005 = 0.0189
    assert versus_paper("K=400", Estimate(8.635, 0.005), 8.62, 2).outcome == WIN
    assert versus_paper("K=400", Estimate(8.645, 0.005), 8.62, 2).outcome == LOSS
    # ten seeds (9 dof each, 18 for the difference): t = 2.101, margin 2.101·√2 × 0.005 + 0.005 = 0.01986
    assert versus_paper("K=400", Estimate(8.6395, 0.005, 9), 8.62, 2).outcome == WIN
    assert versus_paper("K=400", Estimate(8.6405, 0.005, 9), 8.62, 2).outcome == LOSS


def test_unequal_standard_errors_against_the_paper():
    # The paper averaged 25 trials where we average 250: its mean's error is √10 times ours. Ours 10.0 ± 0.1 against
    # a printed 10.6: with the paper's error taken as ours the margin is 1.96·√2·0.1 + 0.05 = 0.327 < 0.6: lost; with
    # its own, 1.96·√(0.1² + 0.316²) + 0.05 = 0.700 > 0.6: won.
    ours = Estimate(10.0, 0.1)
    paper_error = same_protocol_error(ours, 250, 25)
    assert math.isclose(paper_error.error, 0.1 * math.sqrt(10))
    assert versus_paper("x", ours, 10.6, 1).outcome == LOSS
    assert versus_paper("x", ours, 10.6, 1, paper_error=paper_error).outcome == WIN


def test_a_verbal_range_needs_the_whole_band_inside_to_win_and_outside_to_lose():
    # "about three": 2.5 to 3.5. Band 1.96·0.1 = 0.196: 3.3 ± 0.196 inside (won), 3.4 ± 0.196 across 3.5 (tied),
    # 3.7 ± 0.196 wholly above (lost); a wide band (4.4 ± 2.0) across the range cannot tell.
    outcomes = [inside("x", Estimate(value, error), 2.5, 3.5).outcome
                for value, error in ((3.3, 0.1), (3.4, 0.1), (3.7, 0.1), (4.4, 1.0), (2.0, 0.1))]
    assert outcomes == [WIN, TIE, LOSS, TIE, LOSS]


def test_paired_difference_over_trials():
    rng = np.random.default_rng(3)
    base = rng.exponential(1.0, 200)
    first, second = base + 0.5, base  # the same trials, shifted: the paired difference has no spread
    paired = paired_difference(first, second)
    assert math.isclose(paired.value, 0.5) and paired.error < 1e-12
    unrelated = paired_difference(rng.exponential(1.0, 200), base)
    assert 0.5 * math.sqrt(2 / 200) < unrelated.error < 2 * math.sqrt(2 / 200)  # σ = 1 per sample
    assert paired_difference(first, second) == paired  # seeded: the same band on every run


def test_every_statistic_of_the_same_trials_takes_the_same_resamples():
    rng = np.random.default_rng(4)
    first, second = rng.exponential(1.0, 50), rng.exponential(1.0, 50)
    difference = bootstrap(lambda a, b, axis=None: np.median(a, axis=axis) - np.median(b, axis=axis), first, second)
    assert difference == paired_difference(first, second, np.median)  # one bootstrap: the same band either way
    ratio = bootstrap(lambda a, axis=None: np.mean(a, axis=axis) / np.median(a, axis=axis), first)
    assert math.isclose(ratio.value, np.mean(first) / np.median(first)) and ratio.error > 0
    assert magnitude(Estimate(-0.3, 0.1)) == Estimate(0.3, 0.1)


@pytest.mark.parametrize("n, rank", [(6, 1), (10, 2), (20, 6), (30, 10)])
def test_median_interval_is_the_order_statistic_of_the_binomial(n, rank):
    """Ranks from the binomial tables: P(B(n, ½) < rank) ≤ 2.5% < P(B(n, ½) < rank + 1)."""
    assert binom.cdf(rank - 1, n, 0.5) <= 0.025 < binom.cdf(rank, n, 0.5)
    values = np.arange(n, dtype=float)[::-1]
    assert median_interval(values)[1] == (rank - 1, n - rank)


def test_a_timing_interval_that_straddles_its_threshold_gives_no_verdict():
    straddles = TimeRatio((0.90, 0.95, 0.97, 0.99, 1.01, 1.02, 1.03, 1.04, 1.06, 1.10, 0.98), 0.0, 1.0)
    assert straddles.interval[0] < 1.0 < straddles.interval[1] and straddles.verdict == TIMING_NOISE
    grade = grade_time(straddles, "why")
    assert (grade.verdict, grade.why) == (TIMING_NOISE, "why") and not any(c.isdigit() for c in grade.ours[:-1])
    clears = TimeRatio((0.80, 0.82, 0.85, 0.90, 0.95, 0.97, 0.84, 0.83, 0.88, 0.86, 0.91), 0.0, 1.0)
    assert clears.verdict == REPRODUCED
    above = TimeRatio(tuple(np.linspace(1.1, 1.4, 11)), 0.0, 1.0)
    assert above.verdict == NOT
    similar = TimeRatio(tuple(np.linspace(0.6, 1.9, 11)), 0.5, 2.0)
    assert similar.verdict == REPRODUCED


def test_against_rivals_each_rival_keeps_its_own_band():
    from dgmm.experiments.report.claims.inits import versus_rivals

    # Ours 8.00 ± 0.01; rival A 8.05 ± 0.2 (the highest mean, but noisy: a tie), rival B 8.03 ± 0.005 (lower, but
    # 0.03 above ours beyond its band 1.96·√(0.01² + 0.005²) = 0.022: a loss). Against the highest mean alone the
    # comparison would be a tie; against each, B decides it: lost.
    ours, rivals = Estimate(8.0, 0.01), {"A": Estimate(8.05, 0.2), "B": Estimate(8.03, 0.005)}
    rival, comparison = versus_rivals("K=6", ours, rivals, lambda name, value: f"vs {name} {value:.2f}")
    assert (rival, comparison.outcome, comparison.detail) == ("B", LOSS, "vs B 8.03")
    # Above both beyond their bands: won, decided by the one beaten by least.
    rival, comparison = versus_rivals("K=6", Estimate(9.0, 0.01), rivals, lambda name, value: name)
    assert (rival, comparison.outcome) == ("A", WIN)
    # No loss, one tie: tied.
    rival, comparison = versus_rivals("K=6", Estimate(8.1, 0.01), rivals, lambda name, value: name)
    assert (rival, comparison.outcome) == ("A", TIE)
    assert versus_rivals("K=6", ours, {}, str) == (None, None)
