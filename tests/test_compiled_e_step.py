"""The screened E-step (GaussianMixture(screen=...), dgmm.compiled.e_step): the kernel against its numpy formula, and
screened fits against unscreened ones where most pairs are screened out."""
import numpy as np
import pytest

from dgmm import GaussianMixture, Primitives
from dgmm.compiled.e_step import BLOCK, exp_shifted_screened, screened_e_step_block_sums, screened_e_step_sums
from dgmm.mixture import EStep


def test_kernel_is_the_shifted_exponential_of_the_pairs_within_the_screen():
    rng = np.random.default_rng(0)
    log_rho = -rng.exponential(40.0, size=(30, 200))
    shifted = log_rho - log_rho.max(axis=0)
    expected = np.where(shifted > -50.0, np.exp(shifted), 0.0)
    assert 0.1 < np.mean(expected == 0) < 0.9
    out = log_rho.copy()
    peak, total = exp_shifted_screened(out, 50.0)
    np.testing.assert_array_equal(peak, log_rho.max(axis=0))
    np.testing.assert_allclose(out, expected, rtol=1e-15, atol=0)
    np.testing.assert_allclose(total, expected.sum(axis=0), rtol=1e-15)


@pytest.mark.parametrize("mesh", [True, False], ids=["triangles", "points"])
def test_screened_fit_is_the_unscreened_fit_to_rounding(bunny_res4, mesh):
    """K=50 on the bunny from the same k-means start: most pairs lie beyond e^-50, and the screened fit's parameters
    and bound equal the unscreened ones to 1e-12; a screen of e^-3 changes them by more than 1e-6 (the screen is
    applied, so the test can fail)."""
    data = bunny_res4 if mesh else np.asarray(bunny_res4.vertices)
    prims = Primitives.from_mesh(bunny_res4.vertices, bunny_res4.faces) if mesh else Primitives.from_points(data)
    reference = GaussianMixture(50, init="kmeans", max_iter=25, random_state=0).fit(data)
    log_rho = np.stack([np.log(w) - 0.5 * np.einsum("na,ab,nb->n", prims.means - m, np.linalg.inv(c), prims.means - m)
                        - 0.5 * np.linalg.slogdet(c)[1] for w, m, c in
                        zip(reference.weights_, reference.means_, reference.covariances_)])
    assert np.mean(log_rho - log_rho.max(axis=0) < -50) > 0.5
    screened = GaussianMixture(50, init="kmeans", max_iter=25, random_state=0, screen=50).fit(data)
    coarse = GaussianMixture(50, init="kmeans", max_iter=25, random_state=0, screen=3).fit(data)
    for name in ("weights_", "means_", "covariances_"):
        ours, theirs = getattr(screened, name), getattr(reference, name)
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12 * np.abs(theirs).max(), err_msg=name)
        assert np.abs(getattr(coarse, name) - theirs).max() > 1e-6 * np.abs(theirs).max(), name
    assert screened.lower_bound_ == pytest.approx(reference.lower_bound_, rel=1e-13)


def test_screened_responsibilities_are_the_unscreened_ones_to_rounding(bunny_res4):
    """``EStep(screen=...)``, as odometry's cuts take a screened fit's last E-step: equal to the unscreened
    responsibilities to 1e-15 at e^-50 (more than half of them are screened to 0), different at e^-3."""
    model = GaussianMixture(50, random_state=0).fit(bunny_res4)
    prims = Primitives.from_mesh(bunny_res4.vertices, bunny_res4.faces)
    params = (model.weights_, model.means_, model.covariances_, model.precisions_cholesky_)
    reference = EStep(*params).responsibilities(prims.means, prims.covariances)
    screened = EStep(*params, screen=50).responsibilities(prims.means, prims.covariances)
    assert np.mean(screened == 0) > 0.5
    np.testing.assert_allclose(screened, reference, rtol=0, atol=1e-15)
    assert np.abs(EStep(*params, screen=3).responsibilities(prims.means, prims.covariances) - reference).max() > 1e-3


@pytest.mark.parametrize("n_components", [40, 130])
def test_a_primitives_sums_do_not_depend_on_its_block(n_components):
    """The fused kernel computes ``log rho`` a block of primitives at a time: each primitive alone (a block of one)
    gives its log-normaliser to the bit, and the block's M-step sums equal the sum of its primitives' alone to
    rounding (and those of its kept pairs are numpy's); with more than 64 components the kept pairs span several
    words of bits."""
    rng = np.random.default_rng(2)
    n_rows = BLOCK + 5
    features = np.column_stack([rng.normal(size=(n_rows, 10)), np.ones(n_rows)])
    coefficients = np.ascontiguousarray(rng.normal(scale=30.0, size=(11, n_components)))
    moments, row_weights = rng.normal(size=(n_rows, 10)), rng.random(n_rows)
    log_norm = np.empty(n_rows)
    sums = screened_e_step_sums(features, coefficients, moments, row_weights, 50.0, log_norm)
    alone = np.empty((n_rows, n_components, 10))
    for j in range(n_rows):
        one = np.empty(1)
        alone[j] = screened_e_step_sums(features[j:j + 1], coefficients, moments[j:j + 1], row_weights[j:j + 1],
                                        50.0, one)
        assert one[0] == log_norm[j]
    np.testing.assert_allclose(sums, alone.sum(axis=0), rtol=0, atol=1e-13 * np.abs(sums).max())
    log_rho = features @ coefficients
    rho = np.exp(log_rho - log_rho.max(axis=1, keepdims=True))
    rho[log_rho - log_rho.max(axis=1, keepdims=True) <= -50.0] = 0.0
    expected = (rho * (row_weights / rho.sum(axis=1))[:, None]).T @ moments
    np.testing.assert_allclose(sums, expected, rtol=0, atol=1e-12 * np.abs(expected).max())
    np.testing.assert_allclose(log_norm, np.log(rho.sum(axis=1)) + log_rho.max(axis=1), rtol=1e-14)


def test_block_sums_in_one_call_are_the_blocks_added_in_order():
    """The one-call kernel over row blocks gives, to the bit, the log-normalisers and the sums of a call per block
    added in block order (BlockPass.run's order)."""
    rng = np.random.default_rng(5)
    n_rows, n_components = 3 * BLOCK + 11, 70
    features = np.column_stack([rng.normal(size=(n_rows, 10)), np.ones(n_rows)])
    coefficients = np.ascontiguousarray(rng.normal(scale=30.0, size=(11, n_components)))
    table = np.column_stack([rng.normal(size=(n_rows, 10)), np.ones(n_rows)])
    row_weights = rng.random(n_rows)
    starts = np.array([0, 40, 41, 90, n_rows])
    log_norm, expected_log_norm = np.empty(n_rows), np.empty(n_rows)
    expected = None
    for start, stop in zip(starts[:-1], starts[1:]):
        part = screened_e_step_sums(features[start:stop], coefficients, table[start:stop, :-1],
                                    row_weights[start:stop], 50.0, expected_log_norm[start:stop])
        expected = part if expected is None else expected + part
    sums = screened_e_step_block_sums(features, coefficients, table[:, :-1], row_weights, 50.0, log_norm, starts)
    np.testing.assert_array_equal(sums, expected)
    np.testing.assert_array_equal(log_norm, expected_log_norm)


def test_moment_table_is_numpys_to_the_bit():
    """The compiled moment table of 3-D primitives (a screened fit's) against the numpy one, every value."""
    from dgmm.mixture import _moment_table

    rng = np.random.default_rng(6)
    factors = rng.normal(size=(500, 3, 3))
    prims = Primitives(rng.normal(size=(500, 3)) * 3.0, factors @ factors.transpose(0, 2, 1), rng.random(500))
    centre, unit = rng.normal(size=3), 0.5
    np.testing.assert_array_equal(_moment_table(prims, centre, unit, compiled=True), _moment_table(prims, centre, unit))
