"""The paper's claims, one function each, grouped by the paper's sections; each grades its claim with both EMs.

Modules: :mod:`~.theory` (§II-III, Fig 2), :mod:`~.fitting` (§IV-A, Fig 3, Fig 7), :mod:`~.decimation` (§IV-B,
Fig 4, Discussion), :mod:`~.convergence` (Discussion, Introduction, Conclusion), :mod:`~.registration` (§V-A/B,
Fig 5), :mod:`~.table1` (§V-C, Table 1), :mod:`~.odometry` (§V-D, Fig 6). The verdicts, rules and EM policy are in
:mod:`~.rules`; what the claims read in :mod:`~.measurements`.
"""
from dgmm.experiments.report.claims import convergence, decimation, fitting, odometry, registration, table1, theory
from dgmm.experiments.report.claims.measurements import TABLES, Measurements
from dgmm.experiments.report.claims.rules import (CLOSE_NATS, FIG3_INPUTS, FIG4_INPUTS, HEADLINE, NOT, PARTLY, PENDING,
                                                  REPRODUCED, SAME_NATS, VARIANT_NAMES, VARIANTS, Claim, Grade,
                                                  gap_verdict, share_verdict)

SECTIONS = (theory, fitting, decimation, convergence, registration, table1, odometry)
CLAIMS = tuple(claim for module in SECTIONS for claim in module.CLAIMS)


def evaluate(data):
    """Every claim of ``CLAIMS`` graded on ``data`` (a :class:`Measurements`), in the paper's order."""
    return [claim(data) for claim in CLAIMS]


__all__ = ["CLAIMS", "CLOSE_NATS", "Claim", "FIG3_INPUTS", "FIG4_INPUTS", "Grade", "HEADLINE", "Measurements", "NOT",
           "PARTLY", "PENDING", "REPRODUCED", "SAME_NATS", "SECTIONS", "TABLES", "VARIANTS", "VARIANT_NAMES",
           "evaluate", "gap_verdict", "share_verdict"]
