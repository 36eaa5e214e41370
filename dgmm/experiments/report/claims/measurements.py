"""What the claims read: the sweep's and the checks' tables, each None while its stage is not configured."""
from dataclasses import dataclass
from functools import cached_property

from dgmm.experiments.report import tables

TABLES = {
    # field: the table (under results/tables/) it holds as rows of strings
    "likelihood": "likelihood.csv",
    "fig2": "fig2.csv",
    "registration": "registration.csv",
    "registration_seconds": "registration_seconds.csv",
    "odometry": "odometry.csv",
    "odometry_seconds": "odometry_seconds.csv",
    "convergence": "convergence.csv",
    "resampling": "resampling.csv",
    "optimisers": "optimisers.csv",
    "optimisers_seconds": "optimisers_seconds.csv",
    "timing_seconds": "timing_seconds.csv",
}


@dataclass(frozen=True)
class Measurements:
    """Rows of every table of ``TABLES`` (None: not configured), with the summaries several claims share."""

    likelihood: list = None
    fig2: list = None
    registration: list = None
    registration_seconds: list = None
    odometry: list = None
    odometry_seconds: list = None
    convergence: list = None
    resampling: list = None
    optimisers: list = None
    optimisers_seconds: list = None
    timing_seconds: list = None

    @cached_property
    def means(self):
        """:func:`dgmm.experiments.report.tables.likelihood_means` of ``likelihood`` ({} when it is missing)."""
        return tables.likelihood_means(self.likelihood) if self.likelihood else {}

    def errors(self, variant):
        """Registration errors of the scaled trials with mesh mixtures of ``variant`` (None: not configured)."""
        return None if self.registration is None else tables.registration_errors(self.registration, "scaled",
                                                                                 variant)

    def table1(self, variant):
        """Table 1 (scaled trials) with mesh mixtures of ``variant``."""
        return tables.table1(self.means, self.errors(variant), variant)
