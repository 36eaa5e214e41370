"""What the claims read: the sweep's and the checks' tables, each None while its stage is not configured.

likelihood.csv holds fits of two protocols apart by their ``max_iter`` column: the paper's text's 25 iterations
(every experiment) and the authors' stored 100 (Fig 4 again, config experiment fig4_100). A :class:`Measurements`
shows one: the text's by default, another from :meth:`Measurements.at_iterations`.
"""
from dataclasses import dataclass, field, replace
from functools import cached_property

from collections import defaultdict

from dgmm.experiments.report import tables
from dgmm.experiments.report.claims.grading import estimate

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
    "identities": "identities.csv",
}


OURS = "ours"
"""odometry.csv's protocol of our own per-frame schedule (config ``odometry.protocols``); a table without the column
holds only ours. Rows with an empty protocol (ICP: no mixture) belong to every protocol."""


@dataclass(frozen=True)
class Measurements:
    """Rows of every table of ``TABLES`` (None: not configured), with the summaries several claims share.

    ``likelihood`` holds the rows of likelihood.csv's fits capped at ``max_iter`` iterations (the text's 25 unless
    :meth:`at_iterations` says otherwise); ``all_fits`` every row, whatever its cap (set from ``likelihood`` when not
    given). Likewise ``odometry`` holds odometry.csv's runs of ``odometry_protocol`` (ours unless said otherwise) and
    ``all_odometry`` every run.
    """

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
    identities: list = None
    max_iter: int = tables.TEXT_MAX_ITER
    all_fits: list = field(default=None, repr=False)
    table1_trials: int = None
    odometry_protocol: str = OURS
    all_odometry: list = field(default=None, repr=False)

    def __post_init__(self):
        if self.all_fits is None:
            object.__setattr__(self, "all_fits", self.likelihood)
        if self.all_fits is not None:
            object.__setattr__(self, "likelihood", tables.likelihood_rows(self.all_fits, self.max_iter))
        if self.all_odometry is None:
            object.__setattr__(self, "all_odometry", self.odometry)
        if self.all_odometry is not None:
            object.__setattr__(self, "odometry", [row for row in self.all_odometry
                                                  if row.get("protocol", OURS) in ("", self.odometry_protocol)])

    def at_iterations(self, max_iter):
        """The same tables with ``likelihood`` (and ``means``, ``estimates``) the fits capped at ``max_iter``
        iterations: ``at_iterations(100)`` shows Fig 4 as the authors' stored data ran it (config experiment
        fig4_100; the other experiments have no such fits)."""
        return replace(self, max_iter=max_iter, likelihood=None)

    def with_odometry_protocol(self, protocol):
        """The same tables with ``odometry`` the runs of ``protocol`` (config ``odometry.protocols``)."""
        return replace(self, odometry_protocol=protocol, odometry=None)

    @cached_property
    def means(self):
        """:func:`dgmm.experiments.report.tables.likelihood_means` of ``likelihood`` ({} when it is missing)."""
        return tables.likelihood_means(self.likelihood, self.max_iter) if self.likelihood else {}

    @cached_property
    def estimates(self):
        """``(model, input, variant, init, K) -> Estimate``: the mean evaluation log-likelihood over seeds with its
        standard error ({} when likelihood.csv is missing)."""
        groups = defaultdict(list)
        for row in self.likelihood or []:
            groups[(row["model"], row["input"], row["variant"], row["init"], int(row["K"]))].append(row["eval_ll"])
        return {key: estimate([float(value) for value in values]) for key, values in sorted(groups.items())}

    def errors(self, variant):
        """Registration errors of the scaled trials with mesh mixtures of ``variant`` (None: not configured)."""
        return None if self.registration is None else tables.registration_errors(self.registration, "scaled",
                                                                                 variant)

    def table1_errors(self, variant):
        """:meth:`errors` with Table 1's meshes cut to their first ``table1_trials`` trials
        (:func:`~dgmm.experiments.report.tables.table1_errors`; None: every trial)."""
        return tables.table1_errors(self.errors(variant), self.table1_trials)

    def table1(self, variant):
        """Table 1 (scaled trials) with mesh mixtures of ``variant``."""
        return tables.table1(self.means, self.table1_errors(variant), variant)

    def seconds(self, check):
        """``setting -> {repeat: CPU seconds}`` of one timing check of timing_seconds.csv ({} when missing)."""
        result = defaultdict(dict)
        for row in self.timing_seconds or []:
            if row["check"] == check:
                result[row["setting"]][int(row["repeat"])] = float(row["seconds"])
        return dict(result)

    def time_ratios(self, check, numerator, denominator):
        """Per-repeat ratios ``numerator / denominator`` of one timing check, paired by repeat (() when missing)."""
        seconds = self.seconds(check)
        top, bottom = seconds.get(numerator, {}), seconds.get(denominator, {})
        return tuple(top[repeat] / bottom[repeat] for repeat in sorted(top.keys() & bottom.keys()))
