"""The authors' stored results beside ours: does our sweep reproduce their cells, and do the paper's statements hold
on their data?

Two judgements, each defined once here:

- **Reproduction of a cell** (:class:`Cell`): our mean against the authors' stored value of the same cell (same
  input, start, K; their EM for meshes, textbook EM for points, which is the same algorithm). The notebooks store no
  spread, so the authors' mean is taken to have our seeds' standard error (the same protocol); the cell reproduces
  when the difference is inside the tie band of two such means (:func:`~.claims.grading.versus_paper`'s: Student's
  t times √2 standard errors), plus half the last printed digit of the stored value.
- **The paper's statement on the authors' data** (:func:`authors_measurements`): the claims whose rules read only
  means are graded again on the authors' stored means with our noise: each likelihood cell's mean replaced by
  theirs with our standard error, each registration method's trials scaled to their stored mean (Fig 6: the mean
  error; Table 1: the % of ICP's mean). Claims that read anything the notebooks do not store (per-seed iterations,
  medians and quartiles of trials, timings, odometry) have no verdict on the authors' data.
"""
import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from dgmm.experiments.report.claims.grading import Estimate, bootstrap
from dgmm.experiments.report.claims.measurements import Measurements
from dgmm.experiments.report.claims.rules import FIG3_MODEL, fitted_variant
from dgmm.experiments.report.tables import (STORED_MAX_ITER, TABLE1_FIT, TABLE1_INPUTS, TABLE1_METHODS, TEXT_MAX_ITER,
                                            table1_mesh)
from dgmm.registration.protocol import BUNNY_DIAGONAL

HEADLINE = "authors"
"""The EM whose fits stand beside the authors' data: theirs."""
ITEMS = {"fig3": "Fig 3", "fig4": "Fig 4", "table1": "Table 1", "fig6": "Fig 6"}
"""The items of the authors' table compared cell by cell, with the report's names."""
ITERATIONS = {"fig3": TEXT_MAX_ITER, "fig4": STORED_MAX_ITER, "table1": TEXT_MAX_ITER}
"""The iteration cap each stored likelihood ran at (their stored mean iterations: Fig 4's point fits ran 100), so
the cap of our fits it stands beside (likelihood.csv's ``max_iter``)."""


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
        return (self.ours - Estimate(0.0, self.ours.error, self.ours.dof)).band + 0.5 * 10.0 ** -decimals

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
        """``(estimates key, row)`` of every stored likelihood: Fig 3 and Fig 4 cells, Table 1's columns (mesh cells
        are the authors' EM's, point cells textbook EM's). The bunny's Table 1 row and Fig 3's K=100 k-means cells
        share a key: the authors stored each from its own run."""
        result = []
        for row in self.rows:
            if row["quantity"] != "eval_ll":
                continue
            if row["item"] == "table1":
                mesh = table1_mesh(row["model"])
                name = f"{mesh}-{TABLE1_INPUTS[row['input']]}"
                key = (row["model"], name, fitted_variant(name, HEADLINE), TABLE1_FIT["init"], TABLE1_FIT["K"])
            else:
                key = (row["model"], row["input"], fitted_variant(row["input"], HEADLINE), row["init"], int(row["K"]))
            result.append((key, row))
        return result

    def likelihood_cells(self, data):
        """:class:`Cell` of every stored likelihood against our fits at its iteration cap (``data``: our
        Measurements)."""
        estimates = {cap: data.at_iterations(cap).estimates for cap in set(ITERATIONS.values())}
        return [Cell(row["item"], _likelihood_label(row), float(row["value"]), row["value"],
                     estimates[ITERATIONS[row["item"]]].get(key), "nat", row["n_iter"])
                for key, row in self.likelihood_keys()]

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

    def cells(self, data):
        """Every stored value beside ours (``data``: our Measurements): likelihoods, then Table 1's and Fig 6's
        registration errors (the authors' EM's mixtures, scaled trials)."""
        return (self.likelihood_cells(data) + self.table1_cells(data.table1_errors(HEADLINE))
                + self.fig6_cells(data.errors(HEADLINE)))

    def fig6_trials(self, errors):
        """``errors`` (ours) with each of Fig 6's methods scaled to its stored mean rotation and translation (None
        without errors)."""
        if not errors:
            return None
        result = {}
        for row in self.rows:
            key = (row["model"], "res4", row["input"])
            if row["item"] == "fig6" and key in errors:
                name = "rot" if row["quantity"] == "rotation" else "trans"
                mean = float(row["value"]) * (100.0 / BUNNY_DIAGONAL if row["unit"] == "m" else 1.0)
                result.setdefault(key, dict(errors[key]))[name] = scaled(errors[key][name], mean)
        return result

    def table1_trials(self, errors):
        """``errors`` (ours) with Table 1's points and mesh GMM trials scaled so that their mean is the stored % of
        our ICP's on the same trials (None without errors)."""
        if not errors:
            return None
        result = {}
        for row in self.rows:
            if row["item"] != "table1" or row["quantity"] == "eval_ll":
                continue
            mesh = table1_mesh(row["model"])
            key, reference = ((row["model"], mesh, TABLE1_METHODS[kind]) for kind in (row["input"], "reference"))
            if key in errors and reference in errors:
                name = "rot" if row["quantity"] == "rotation" else "trans"
                result.setdefault(reference, errors[reference])
                mean = float(row["value"]) / 100.0 * np.mean(errors[reference][name])
                result.setdefault(key, dict(errors[key]))[name] = scaled(errors[key][name], mean)
        return result

    def stored_estimates(self, estimates, view, max_iter):
        """``estimates`` (ours, at ``max_iter`` iterations) with every cell the authors stored at that cap at their
        value, our standard error kept; cells they did not store are dropped, and so is every textbook-EM mesh cell
        (their data has only their EM). Where two stored values share a cell, ``view``'s item wins (``"table1"``:
        Table 1's run, else the figures')."""
        pairs = [(key, row) for key, row in self.likelihood_keys() if ITERATIONS[row["item"]] == max_iter]
        preferred = [(row["item"] == "table1") == (view == "table1") for _, row in pairs]
        stored = dict([pair for pair, first in zip(pairs, preferred) if not first]
                      + [pair for pair, first in zip(pairs, preferred) if first])
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
    """Measurements whose likelihood cells are the authors' stored means at the view's iteration cap
    (:meth:`AuthorsData.stored_estimates` of ours) and whose registration trials (the authors' EM's) are ours scaled
    to their stored means (:meth:`AuthorsData.fig6_trials`, :meth:`AuthorsData.table1_trials`); every other table is
    absent, so a claim that needs one is pending on the authors' data."""

    authors: AuthorsData = None
    view: str = "figures"
    trials: dict = None

    @cached_property
    def estimates(self):
        return self.authors.stored_estimates(Measurements.estimates.func(self), self.view, self.max_iter)

    @cached_property
    def means(self):
        return {key: (value.value, math.nan) for key, value in self.estimates.items()}

    def errors(self, variant):
        """The scaled trials for the authors' EM (theirs is the only EM their data has), else None."""
        return self.trials if variant == HEADLINE and self.trials else None


def scaled(trials, mean):
    """``trials`` times the factor that makes their mean ``mean``: the authors' mean with our trials' relative
    spread (errors are positive, so the scaled ones stay so)."""
    return np.asarray(trials) * (mean / np.mean(trials))


def authors_measurements(authors, data):
    """The authors' data as the claims read it, with ``data``'s (ours) noise: ``view -> StoredMeasurements`` for
    the views of :data:`VIEWS`."""
    trials = {"figures": authors.fig6_trials(data.errors(HEADLINE)),
              "table1": authors.table1_trials(data.table1_errors(HEADLINE))}
    return {view: StoredMeasurements(likelihood=data.likelihood, all_fits=data.all_fits, max_iter=data.max_iter,
                                     authors=authors, view=view, trials=trials[view]) for view in VIEWS}


VIEWS = {"figures": "Figs 3 and 4's cells; Fig 6's methods on bunny res4, each scaled to the stored mean of its 250 "
                    "trials",
         "table1": "Table 1's likelihoods; its models' points and mesh GMM trials scaled to the stored % of our ICP's "
                   "mean"}
"""The two views of the authors' data: their figures and their Table 1 came from separate runs (the bunny's K=100
k-means cells and its registration trials, 250 against 25), so one set of cells cannot hold both."""
