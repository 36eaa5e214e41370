"""The authors' stored results beside ours: does our sweep reproduce their cells, and do the paper's statements hold
on their data?

Two judgements, each defined once here:

- **Reproduction of a cell** (:class:`Cell`): our mean against the authors' stored value of the same cell (same
  input, start, K; their EM for meshes, textbook EM for points, which is the same algorithm). The notebooks store no
  spread, so the authors' mean is taken to have our seeds' standard error (the same protocol); the cell reproduces
  when the difference is inside the tie band of two such means, :data:`~.claims.grading.BAND_ERRORS` × √2 standard
  errors, plus half the last printed digit of the stored value.
- **The paper's statement on the authors' data** (:func:`authors_measurements`): the claims whose rules read only
  the likelihood cells' means are graded again with each cell's mean replaced by the authors' value, keeping our
  standard error as its noise. Claims that read anything the notebooks do not store (per-seed iterations,
  registration trials, timings, odometry) have no verdict on the authors' data.
"""
import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from dgmm.experiments.report.claims.grading import BAND_ERRORS, Estimate, bootstrap
from dgmm.experiments.report.claims.measurements import Measurements
from dgmm.experiments.report.claims.rules import FIG3_MODEL, fitted_variant
from dgmm.experiments.report.tables import TABLE1_FIT, TABLE1_INPUTS, TABLE1_METHODS, table1_mesh
from dgmm.registration.protocol import BUNNY_DIAGONAL

HEADLINE = "authors"
"""The EM whose fits stand beside the authors' data: theirs."""
ITEMS = {"fig3": "Fig 3", "fig4": "Fig 4", "table1": "Table 1", "fig6": "Fig 6"}
"""The items of the authors' table compared cell by cell, with the report's names."""


@dataclass(frozen=True)
class Cell:
    """One stored value of the authors' beside ours.

    Attributes
    ----------
    item : str
        A key of :data:`ITEMS`.
    label : str
        The cell's keys ("res4-exact kmeans K=100", "armadillo mesh", "icp rotation").
    theirs : float
        The authors' stored value.
    printed : str
        It as printed (its last digit sets the rounding allowed).
    ours : Estimate or None
        Our mean and its standard error (None: not in our sweep).
    unit : str
    n_iter : str
        The authors' mean EM iterations where stored.
    """

    item: str
    label: str
    theirs: float
    printed: str
    ours: Estimate = None
    unit: str = ""
    n_iter: str = ""

    @property
    def difference(self):
        """Ours − theirs (nan without ours)."""
        return math.nan if self.ours is None else self.ours.value - self.theirs

    @property
    def band(self):
        """How far ours may be from theirs and still reproduce it (nan without ours)."""
        if self.ours is None:
            return math.nan
        decimals = len(self.printed.partition(".")[2]) if "e" not in self.printed.lower() else 15
        return BAND_ERRORS * math.sqrt(2.0) * self.ours.error + 0.5 * 10.0 ** -decimals

    @property
    def reproduced(self):
        """True inside the band, False outside, None without ours."""
        return None if self.ours is None else bool(abs(self.difference) <= self.band)


class AuthorsData:
    """The authors' table (rows of :data:`dgmm.experiments.authors_data.COLUMNS`), read for the report."""

    def __init__(self, rows):
        self.rows = list(rows)

    def curves(self, item):
        """``(input, init) -> (ks, means)`` of a likelihood figure's stored means (``item``: fig3 or fig4)."""
        points = {}
        for row in self.rows:
            if row["item"] == item:
                points.setdefault((row["input"], row["init"]), []).append((int(row["K"]), float(row["value"])))
        return {key: tuple(np.array(column) for column in zip(*sorted(values))) for key, values in points.items()}

    def likelihood_keys(self):
        """``estimates key -> row`` of every stored likelihood: Fig 3 and Fig 4 cells, Table 1's columns (mesh cells
        are the authors' EM's, point cells textbook EM's)."""
        result = {}
        for row in self.rows:
            if row["quantity"] != "eval_ll":
                continue
            if row["item"] == "table1":
                mesh = table1_mesh(row["model"])
                name = f"{mesh}-{TABLE1_INPUTS[row['input']]}"
                key = (row["model"], name, fitted_variant(name, HEADLINE), TABLE1_FIT["init"], TABLE1_FIT["K"])
            else:
                key = (row["model"], row["input"], fitted_variant(row["input"], HEADLINE), row["init"], int(row["K"]))
            result[key] = row
        return result

    def likelihood_cells(self, estimates):
        """:class:`Cell` of every stored likelihood against ``estimates`` (``Measurements.estimates``)."""
        return [Cell(row["item"], _likelihood_label(row), float(row["value"]), row["value"], estimates.get(key),
                     "nat", row["n_iter"])
                for key, row in self.likelihood_keys().items()]

    def fig6_cells(self, errors):
        """:class:`Cell` of Fig 6's stored means against ours (``errors``: ``(model, mesh, method) -> {"rot", "trans"}``
        of the authors' EM's mixtures; their translations, in metres, as % of the bunny's diagonal as ours)."""
        result = []
        for row in self.rows:
            if row["item"] != "fig6":
                continue
            name = "rot" if row["quantity"] == "rotation" else "trans"
            theirs = float(row["value"]) * (100.0 / BUNNY_DIAGONAL if row["unit"] == "m" else 1.0)
            trials = (errors or {}).get((row["model"], "res4", row["input"]))
            ours = None if trials is None else bootstrap(np.mean, trials[name])
            printed = f"{theirs:.{max(len(row['value'].partition('.')[2]) - 2, 0)}f}" if row["unit"] == "m" else (
                row["value"])
            result.append(Cell("fig6", f"{row['input']} {row['quantity']}", theirs, printed, ours,
                               "%" if name == "trans" else "°"))
        return result

    def table1_cells(self, errors):
        """:class:`Cell` of Table 1's stored registration errors (% of ICP's mean) against ours on the same model's
        trials (``errors`` as :meth:`registration_cells`'), the standard error from a paired bootstrap of the
        trials."""
        result = []
        for row in self.rows:
            if row["item"] != "table1" or row["quantity"] == "eval_ll":
                continue
            name = "rot" if row["quantity"] == "rotation" else "trans"
            mesh = table1_mesh(row["model"])
            method, reference = ((errors or {}).get((row["model"], mesh, TABLE1_METHODS[kind]))
                                 for kind in (row["input"], "reference"))
            ours = None if method is None or reference is None else bootstrap(_percent, method[name], reference[name])
            result.append(Cell("table1", f"{row['model']} {row['input']} {row['quantity']}", float(row["value"]),
                               row["value"], ours, row["unit"]))
        return result

    def cells(self, estimates, errors):
        """Every stored value beside ours: likelihoods (``estimates``), then Table 1's and Fig 6's registration
        errors (``errors`` of the authors' EM's mixtures, scaled trials)."""
        return self.likelihood_cells(estimates) + self.table1_cells(errors) + self.fig6_cells(errors)

    def stored_estimates(self, estimates):
        """``estimates`` with every cell the authors stored at their value, our standard error kept; cells they did
        not store are dropped, and so is every textbook-EM mesh cell (their data has only their EM)."""
        stored = self.likelihood_keys()
        return {key: Estimate(float(stored[key]["value"]), value.error) for key, value in estimates.items()
                if key in stored}


def _percent(errors, reference, axis=None):
    """Mean error as % of the reference method's mean error (Table 1's registration columns)."""
    return 100.0 * np.mean(errors, axis=axis) / np.mean(reference, axis=axis)


def _likelihood_label(row):
    if row["item"] == "table1":
        return f"{row['model']} {row['input']}"
    return f"{row['input']} {row['init']} K={row['K']}"


@dataclass(frozen=True)
class StoredMeasurements(Measurements):
    """Measurements whose likelihood cells are the authors' stored means (:meth:`AuthorsData.stored_estimates`);
    every other table is absent, so a claim that needs one is pending on the authors' data."""

    stored: dict = None

    @cached_property
    def estimates(self):
        return self.stored

    @cached_property
    def means(self):
        return {key: (value.value, math.nan) for key, value in self.stored.items()}


def authors_measurements(authors, data):
    """:class:`StoredMeasurements` of the authors' data with ``data``'s (ours) standard errors."""
    return StoredMeasurements(likelihood=data.likelihood, stored=authors.stored_estimates(data.estimates))
