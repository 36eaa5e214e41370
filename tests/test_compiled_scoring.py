"""Scoring's compiled log-normalisers (dgmm.compiled.scoring) against scipy's logsumexp of every term, and a bunny
score against scikit-learn's on the same mixture, where most terms lie beyond the screen."""
import numpy as np
import trimesh
from scipy.special import logsumexp
from sklearn.mixture import GaussianMixture as SklearnMixture

from dgmm import GaussianMixture
from dgmm.compiled.e_step import moment_table, table_log_normalisers
from dgmm.compiled.scoring import screened_log_normalisers


def test_kernel_is_logsumexp_of_every_term_to_rounding():
    """Rows whose terms spread over hundreds of nats (half beyond e^-50 of their best): the screened sums equal
    scipy's over every term to 1e-13 (a sum of 300 terms of at least 1, rounded in another order, moves by up to
    300 eps); a screen of e^-1 leaves out terms that count (the screen is applied)."""
    rng = np.random.default_rng(0)
    log_rho = -rng.exponential(60.0, size=(500, 300)) + rng.normal(0.0, 5.0, size=(500, 1))
    assert 0.3 < np.mean(log_rho - log_rho.max(axis=1, keepdims=True) < -50) < 0.9
    np.testing.assert_allclose(screened_log_normalisers(log_rho, 50.0), logsumexp(log_rho, axis=1), rtol=0,
                               atol=1e-13)
    assert np.max(logsumexp(log_rho, axis=1) - screened_log_normalisers(log_rho, 1.0)) > 1e-3


def test_a_bunny_score_is_scikit_learn_s(bunny_res4):
    """A K=100 mixture of the bunny's surface, scored on 20k surface points: each point's log-likelihood is
    scikit-learn's score_samples for the same parameters to 1e-9."""
    points = trimesh.sample.sample_surface(bunny_res4, 20_000, seed=1)[0]
    ours = GaussianMixture(100, max_iter=10, random_state=0).fit(bunny_res4)
    reference = SklearnMixture(100, covariance_type="full")
    reference.weights_, reference.means_, reference.covariances_ = ours.weights_, ours.means_, ours.covariances_
    reference.precisions_cholesky_ = np.linalg.cholesky(np.linalg.inv(ours.covariances_))
    np.testing.assert_allclose(ours.score_samples(points), reference.score_samples(points), rtol=0, atol=1e-9)


def test_table_kernel_is_logsumexp_of_the_product_to_rounding():
    """3-D points' moment table under 150 components (three words of bits) whose terms spread over hundreds of
    nats: the fused log-normalisers equal scipy's logsumexp of numpy's product over every term to rounding, 1,001
    rows (a last, partial block); a row's value is the same bits in any block (the table from row 13 on); a screen
    of e^-1 leaves out terms that count."""
    rng = np.random.default_rng(1)
    points = rng.normal(0.0, 1.0, size=(1001, 3))
    table = moment_table(points, np.zeros((1001, 3, 3)), np.zeros(3), 1.0)
    coefficients = np.zeros((11, 150))
    coefficients[:3] = -rng.uniform(1.0, 40.0, size=(3, 150))  # -1/2 of diagonal precisions on x^2, y^2, z^2
    coefficients[6:9] = rng.normal(0.0, 20.0, size=(3, 150))
    coefficients[10] = rng.normal(0.0, 3.0, size=150)
    log_rho = table @ coefficients
    assert 0.3 < np.mean(log_rho - log_rho.max(axis=1, keepdims=True) < -50) < 0.95
    ours = table_log_normalisers(table, coefficients, 50.0)
    np.testing.assert_allclose(ours, logsumexp(log_rho, axis=1), rtol=1e-14, atol=1e-13)
    assert np.array_equal(table_log_normalisers(table[13:], coefficients, 50.0), ours[13:])
    assert np.max(ours - table_log_normalisers(table, coefficients, 1.0)) > 1e-3
