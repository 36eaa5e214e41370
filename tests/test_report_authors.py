"""The authors' stored data in the report: a cell's reproduction band, and a claim graded on their means."""
import math

import numpy as np
import pytest

from dgmm.experiments.report import claims
from dgmm.experiments.report.authors import AuthorsData, Cell, authors_measurements
from dgmm.experiments.report.claims import decimation
from dgmm.experiments.report.claims.grading import NOT, REPRODUCED, Estimate


def test_a_cell_reproduces_inside_two_standard_errors_of_two_means_plus_the_rounding():
    band = 2.0 * math.sqrt(2.0) * 0.01 + 0.5e-6  # our error 0.01, the stored value printed to 6 decimals
    inside = Cell("fig3", "c", 8.02, "8.020000", Estimate(8.0, 0.01))
    assert inside.band == pytest.approx(band) and inside.reproduced
    assert not Cell("fig3", "c", 8.0 + band + 1e-4, "8.030000", Estimate(8.0, 0.01)).reproduced
    assert Cell("table1", "c", 41.3, "41", Estimate(41.0, 0.0)).reproduced  # printed as an integer: ±0.5
    assert Cell("fig3", "c", 8.0, "8.0").reproduced is None  # not in our sweep


def _rows(model, name, init, k, values, variant="textbook"):
    return [{"model": model, "input": name, "variant": variant, "init": init, "K": str(k), "seed": str(seed),
             "eval_ll": repr(float(value)), "n_iter": "25"} for seed, value in enumerate(values)]


def _stored(name, init, k, value):
    return {"item": "fig4", "model": "bunny", "input": name, "init": init, "K": str(k), "quantity": "eval_ll",
            "unit": "nat", "value": value, "n_iter": "100.0", "trials": "", "notebook": "n", "cell": "4"}


def test_a_claim_our_data_misses_is_graded_on_the_authors_means_with_our_noise():
    """Ours: random samples fit better than Poisson-disk ones; the authors' stored means: the other way round, by
    more than the band of our seeds' noise at K=25 and inside it at K=50."""
    rng = np.random.default_rng(0)
    ours, stored = [], []
    for k, poisson, random_ in ((25, 7.0, 7.5), (50, 7.2, 7.7)):
        for init in ("kmeans", "random"):
            ours += _rows("bunny", "poisson1000-points", init, k, poisson + 0.01 * rng.standard_normal(5))
            ours += _rows("bunny", "random1000-points", init, k, random_ + 0.01 * rng.standard_normal(5))
            stored += [_stored("poisson1000-points", init, k, f"{random_ + 0.3:.6f}"),
                       _stored("random1000-points", init, k, f"{random_:.6f}")]
    data = claims.Measurements(likelihood=ours)
    on_stored = authors_measurements(AuthorsData(stored), data)["figures"]
    assert decimation.poisson_beats_random(data).grades["authors"].verdict == NOT
    graded = decimation.poisson_beats_random(on_stored).grades["authors"]
    assert graded.verdict == REPRODUCED and graded.ours == "4/4 won"
    estimate = on_stored.estimates[("bunny", "poisson1000-points", "textbook", "kmeans", 25)]
    assert estimate.value == pytest.approx(7.8)  # their mean, our standard error
    assert estimate.error == pytest.approx(data.estimates[("bunny", "poisson1000-points", "textbook", "kmeans",
                                                           25)].error)
    (claim,) = [c for c in claims.evaluate(data, authors_measurements(AuthorsData(stored), data)) if c.title == "Poisson-disk samples fit better than "
                                                                            "random samples"]
    assert claim.on_stored.verdict == REPRODUCED and claim.verdict == NOT


def test_claims_the_stored_means_cannot_grade_have_no_verdict_on_them():
    data = claims.Measurements(likelihood=_rows("bunny", "res4-exact", "kmeans", 25, [7.0, 7.1], "authors"))
    evaluated = claims.evaluate(data, authors_measurements(AuthorsData([]), data))
    graded = {claim.title for claim in evaluated if claim.on_stored is not None}
    assert len(graded) == len(claims.ON_STORED)
    assert "With ε = 10⁻¹² every fit runs all 25 iterations (no early exit)" not in graded  # reads per-seed n_iter


def _stored_registration(item, model, method, quantity, unit, value):
    return {"item": item, "model": model, "input": method, "init": "", "K": "", "quantity": quantity, "unit": unit,
            "value": value, "n_iter": "", "trials": "", "notebook": "n", "cell": "1"}


def test_registration_trials_are_ours_scaled_to_the_stored_means():
    rng = np.random.default_rng(1)
    trial = lambda scale: {"rot": rng.lognormal(0, 0.3, 40) * scale, "trans": rng.lognormal(0, 0.3, 40) * scale}  # noqa
    errors = {("bunny", "res4", "mesh-kmeans"): trial(2.0), ("bunny", "res4", "icp"): trial(1.0),
              ("lucy", "quadric1000", "mesh-kmeans"): trial(3.0), ("lucy", "quadric1000", "icp"): trial(1.0)}
    authors = AuthorsData([_stored_registration("fig6", "bunny", "mesh-kmeans", "rotation", "deg", "0.5"),
                           _stored_registration("fig6", "bunny", "mesh-kmeans", "translation", "m", "0.0002"),
                           _stored_registration("table1", "lucy", "mesh", "rotation", "% of ICP", "35.0")])
    fig6 = authors.fig6_trials(errors)[("bunny", "res4", "mesh-kmeans")]
    assert np.mean(fig6["rot"]) == pytest.approx(0.5)
    assert np.mean(fig6["trans"]) == pytest.approx(0.0002 / 0.24077 * 100)
    assert np.corrcoef(fig6["rot"], errors[("bunny", "res4", "mesh-kmeans")]["rot"])[0, 1] == pytest.approx(1.0)
    table1 = authors.table1_trials(errors)
    lucy = table1[("lucy", "quadric1000", "mesh-kmeans")]
    assert 100 * np.mean(lucy["rot"]) / np.mean(errors[("lucy", "quadric1000", "icp")]["rot"]) == pytest.approx(35.0)
    assert lucy["trans"] is errors[("lucy", "quadric1000", "mesh-kmeans")]["trans"]  # not stored: ours as it is
    data = claims.Measurements(registration=[])
    view = authors_measurements(authors, data)["figures"]
    assert view.errors("authors") is None and view.errors("textbook") is None  # no trials of ours to scale


def test_every_stored_value_gets_a_cell_beside_ours():
    authors = AuthorsData([_stored("random1000-points", "kmeans", 25, "7.500000"),
                           _stored_registration("fig6", "bunny", "icp", "rotation", "deg", "2.0"),
                           _stored_registration("table1", "lucy", "mesh", "rotation", "% of ICP", "35.0")])
    errors = {("bunny", "res4", "icp"): {"rot": np.array([1.0, 3.0]), "trans": np.array([0.1, 0.2])}}
    estimates = {("bunny", "random1000-points", "textbook", "kmeans", 25): Estimate(7.45, 0.01)}
    cells = authors.cells(estimates, errors)
    assert [(cell.item, cell.label, cell.reproduced) for cell in cells] == [
        ("fig4", "random1000-points kmeans K=25", False), ("table1", "lucy mesh rotation", None),
        ("fig6", "icp rotation", True)]
