"""The paper's claims, one entry each, grouped by the paper's sections; each grades its claim with both EMs when
called on the :class:`Measurements`: a :class:`~.record.PerEmClaim` record (a share rule on each EM's fits, graded
by :func:`~.record.grade`), a :class:`~.timings.TimingClaim` record (a time ratio of the timing check, graded by
:func:`~.timings.grade_timing`), or, for the two whose rule the records do not hold, a function
(:func:`~.theory.triangle_equals_points`, whose rule states the draws and noise of its table, and
:func:`~.registration.bfgs_faster_than_cg`, a time ratio of the optimisers check's trials).

Modules: :mod:`~.theory` (§II, §III, §V-A, §VII: Fig 2 and the identities), :mod:`~.fitting` (§IV-A, Fig 3,
Fig 5), :mod:`~.decimation` (§IV-B, §IV-C, Fig 4), :mod:`~.convergence` (§I, §IV-C, §VII), :mod:`~.registration`
(§VI-A, §VI-B, Fig 6), :mod:`~.table1` (§VI-C, Table 1), :mod:`~.odometry` (§VI-D, Fig 7). The rule kinds and
verdicts are in :mod:`~.grading`; what a graded claim holds, its causes and the EM policy in :mod:`~.rules`; the
claim record and its grader in :mod:`~.record` (the timing record in :mod:`~.timings`); what the claims read in
:mod:`~.measurements`.
"""
from dataclasses import replace

from dgmm.experiments.report.claims import convergence, decimation, fitting, odometry, registration, table1, theory
from dgmm.experiments.report.claims.grading import (INCONCLUSIVE, NOT, PARTLY, PENDING, REPRODUCED, RULE_KINDS,
                                                    TIMING_NOISE, VERDICTS, Grade)
from dgmm.experiments.report.claims.measurements import TABLES, Measurements
from dgmm.experiments.report.claims.rules import (FIG3_INPUTS, FIG4_INPUTS, HEADLINE, VARIANT_NAMES, VARIANTS, Claim,
                                                  in_paper_order)

SECTIONS = (theory, fitting, decimation, convergence, registration, table1, odometry)
CLAIMS = tuple(claim for module in SECTIONS for claim in module.CLAIMS)
ON_STORED = {
    **dict.fromkeys((fitting.fig3_values, fitting.exact_best_approx_second, fitting.mesh_handles_both_inits,
                     fitting.points_prefer_an_init, decimation.quadric_beats_clustering, decimation.poisson_beats_random,
                     decimation.mesh_invariant_to_init, decimation.points_prefer_kmeans,
                     decimation.poisson_kmeans_often_best, decimation.random_samples_lowest, decimation.mesh_reliable,
                     decimation.random_points_prefer_random, decimation.exact_never_prefers_random,
                     registration.fig6_means_match, registration.all_within_model_size,
                     registration.mesh_registers_best), "figures"),
    **dict.fromkeys((table1.mesh_likelihood_higher, table1.likelihood_margins, table1.likelihood_values,
                     table1.mesh_registers_better, table1.registration_margins, table1.registration_values), "table1"),
}
"""The claims whose rules read only means and their noise, which the authors' stored means can grade, with the view
of their data each reads (:data:`dgmm.experiments.report.authors.VIEWS`; the likelihood cells are the same in
both)."""


def evaluate(data, stored=None):
    """Every claim of ``CLAIMS`` graded on ``data`` (a :class:`Measurements`), in the order of the paper's
    sections; with ``stored`` (the authors' data: ``view -> Measurements``), each claim of ``ON_STORED`` (or graded
    at another iteration cap from one) is graded on its view too (``Claim.on_stored``, the headline EM's grade; None
    where the authors stored nothing at that protocol, such as Fig 4 at 25 iterations)."""
    graded = []
    for claim in CLAIMS:
        result, base = claim(data), getattr(claim, "__wrapped__", claim)
        if stored is not None and base in ON_STORED:
            grade = claim(stored[ON_STORED[base]]).grades[HEADLINE]
            result = replace(result, on_stored=None if grade.verdict == PENDING else grade)
        graded.append(result)
    return in_paper_order(graded)


__all__ = ["CLAIMS", "Claim", "FIG3_INPUTS", "FIG4_INPUTS", "Grade", "HEADLINE", "INCONCLUSIVE", "Measurements", "NOT",
           "PARTLY",
           "PENDING", "REPRODUCED", "RULE_KINDS", "SECTIONS", "TABLES", "TIMING_NOISE", "VARIANTS", "VARIANT_NAMES",
           "VERDICTS", "evaluate"]
