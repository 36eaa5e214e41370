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
    on_stored = authors_measurements(AuthorsData(stored), data)
    assert decimation.poisson_beats_random(data).grades["authors"].verdict == NOT
    graded = decimation.poisson_beats_random(on_stored).grades["authors"]
    assert graded.verdict == REPRODUCED and graded.ours == "4/4 won"
    estimate = on_stored.estimates[("bunny", "poisson1000-points", "textbook", "kmeans", 25)]
    assert estimate.value == pytest.approx(7.8)  # their mean, our standard error
    assert estimate.error == pytest.approx(data.estimates[("bunny", "poisson1000-points", "textbook", "kmeans",
                                                           25)].error)
    (claim,) = [c for c in claims.evaluate(data, on_stored) if c.title == "Poisson-disk samples fit better than "
                                                                            "random samples"]
    assert claim.on_stored.verdict == REPRODUCED and claim.verdict == NOT


def test_claims_the_stored_means_cannot_grade_have_no_verdict_on_them():
    data = claims.Measurements(likelihood=_rows("bunny", "res4-exact", "kmeans", 25, [7.0, 7.1], "authors"))
    evaluated = claims.evaluate(data, authors_measurements(AuthorsData([]), data))
    graded = {claim.title for claim in evaluated if claim.on_stored is not None}
    assert len(graded) == len(claims.ON_STORED)
    assert "With ε = 10⁻¹² every fit runs all 25 iterations (no early exit)" not in graded  # reads per-seed n_iter
