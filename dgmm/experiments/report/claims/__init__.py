"""The paper's claims, one function each, grouped by the paper's sections; each grades its claim with both EMs.

Modules: :mod:`~.theory` (§II, §III, §V-A, §VII: Fig 2 and the identities), :mod:`~.fitting` (§IV-A, Fig 3,
Fig 5), :mod:`~.decimation` (§IV-B, §IV-C, Fig 4), :mod:`~.convergence` (§I, §IV-C, §VII), :mod:`~.registration`
(§VI-A, §VI-B, Fig 6), :mod:`~.table1` (§VI-C, Table 1), :mod:`~.odometry` (§VI-D, Fig 7). The rule kinds and
verdicts are in :mod:`~.grading`; what a claim holds and the EM policy in :mod:`~.rules`; what the claims read in
:mod:`~.measurements`.
"""
from dgmm.experiments.report.claims import convergence, decimation, fitting, odometry, registration, table1, theory
from dgmm.experiments.report.claims.grading import (NOT, PARTLY, PENDING, REPRODUCED, RULE_KINDS, TIMING_NOISE,
                                                    VERDICTS, Grade)
from dgmm.experiments.report.claims.measurements import TABLES, Measurements
from dgmm.experiments.report.claims.rules import (FIG3_INPUTS, FIG4_INPUTS, HEADLINE, VARIANT_NAMES, VARIANTS, Claim,
                                                  in_paper_order)

SECTIONS = (theory, fitting, decimation, convergence, registration, table1, odometry)
CLAIMS = tuple(claim for module in SECTIONS for claim in module.CLAIMS)


def evaluate(data):
    """Every claim of ``CLAIMS`` graded on ``data`` (a :class:`Measurements`), in the order of the paper's
    sections."""
    return in_paper_order([claim(data) for claim in CLAIMS])


__all__ = ["CLAIMS", "Claim", "FIG3_INPUTS", "FIG4_INPUTS", "Grade", "HEADLINE", "Measurements", "NOT", "PARTLY",
           "PENDING", "REPRODUCED", "RULE_KINDS", "SECTIONS", "TABLES", "TIMING_NOISE", "VARIANTS", "VARIANT_NAMES",
           "VERDICTS", "evaluate"]
