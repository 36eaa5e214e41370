"""EM streamed over blocks of primitives: bounded memory, threads, scikit-learn agreement, k-means at scale."""
import functools
import time
import tracemalloc
import warnings

import numpy as np
import pytest
import trimesh
from sklearn.mixture import GaussianMixture as SklearnGaussianMixture

import dgmm.mixture
from dgmm import GaussianMixture, InputError
from dgmm.em_blocks import BlockPass, block_rows

FITTED = ("weights_", "means_", "covariances_", "precisions_cholesky_")


def test_blocks_cover_the_rows_within_the_limit():
    with BlockPass(1000, 50, memory_limit=8 * 74 * 300, n_jobs=2) as blocks:
        assert block_rows(1000, 50, 8 * 74 * 300) == 300
        assert block_rows(1000, 50, 8 * 74 * 1000) == 1000  # fits: one block
        assert block_rows(10**7, 50, 2**30) == 2**23 // (8 * 74)  # streamed: 8 MiB blocks
        starts = [rows.start for rows in blocks.blocks]
        assert starts == [0, 300, 600, 900] and blocks.blocks[-1].stop == 1000


@pytest.mark.parametrize("n_jobs", [None, 2, 3])
def test_block_sums_are_added_in_block_order_with_fresh_buffers_per_block(n_jobs):
    """Float sums depend on their order: parts spanning 16 orders of magnitude, added in block order, must give
    exactly the left-to-right sum, whatever the threads (the reverse order differs, so the test can tell). Each
    call gets an (n_components, rows) buffer of its thread, reused across calls; a result written in it and
    returned must survive until it is added, so a buffer shared between threads (or handed out twice before its
    part is summed) fails."""
    n_rows, n_components = 1000, 4
    rng = np.random.default_rng(5)
    values = rng.choice([-1.0, 1.0], size=(n_rows, n_components)) * 10.0 ** rng.uniform(-8, 8, (n_rows, n_components))
    buffers = []

    def part(rows, out):
        assert out.shape == (n_components, rows.stop - rows.start) and out.flags.c_contiguous
        out[:] = values[rows].T
        buffers.append(out.base if out.base is not None else out)
        time.sleep(0.002)  # lets another thread run: it would overwrite a shared buffer here
        return out.sum(axis=1)

    with BlockPass(n_rows, n_components, memory_limit=8 * (n_components + 24) * 70, n_jobs=n_jobs) as blocks:
        assert len(blocks.blocks) == 15
        parts = [np.ascontiguousarray(values[rows].T).sum(axis=1) for rows in blocks.blocks]
        in_order = functools.reduce(np.add, parts)
        assert not np.array_equal(in_order, functools.reduce(np.add, parts[::-1]))
        for _ in range(2):  # a second run reuses the buffers
            assert np.array_equal(blocks.run(part), in_order)
    assert len({id(buffer) for buffer in buffers}) <= (n_jobs or 1)


@pytest.mark.slow
@pytest.mark.parametrize("variant", ["textbook", "authors"])
@pytest.mark.parametrize("init", ["kmeans", "random"])
def test_blocked_fit_equals_one_block_and_is_the_same_on_any_thread_count(bunny_res4, variant, init):
    """Blocks change only the order of the M-step sums: an iteration differs from the unblocked one by rounding
    (parameters to 1e-12 of their scale), and 25 iterations reach the same bounds (EM may carry a parameter's
    rounding further from one iteration to the next, the bound it maximises stays put)."""
    mesh = bunny_res4.subdivide()  # 3792 triangles
    limit = 8 * (20 + 24) * 500  # blocks of 500 rows, the last one shorter

    def fit(max_iter, **params):
        return GaussianMixture(20, init=init, variant=variant, max_iter=max_iter, tol=0, random_state=2,
                               **params).fit(mesh)
    blocked = [fit(25, memory_limit=limit, n_jobs=n_jobs) for n_jobs in (None, 2, 3, -1)]
    for model in blocked[1:]:
        for name in FITTED:
            assert np.array_equal(getattr(model, name), getattr(blocked[0], name)), name
        assert model.history_ == blocked[0].history_
    np.testing.assert_allclose(blocked[0].history_, fit(25).history_, rtol=1e-12)

    whole, one = fit(1), fit(1, memory_limit=limit)
    for name in FITTED:
        expected = getattr(whole, name)
        np.testing.assert_allclose(getattr(one, name), expected, rtol=0, atol=1e-12 * np.abs(expected).max())


@pytest.mark.slow
def test_blocked_threaded_fit_agrees_with_scikit_learn(bunny_res4):
    points = trimesh.sample.sample_surface(bunny_res4, 5000, seed=6)[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # scikit-learn warns that 1 iteration does not converge
        start = SklearnGaussianMixture(15, init_params="random", max_iter=1, random_state=0).fit(points)
        init = dict(weights_init=start.weights_, means_init=start.means_, precisions_init=start.precisions_)
        reference = SklearnGaussianMixture(15, max_iter=20, tol=0, **init).fit(points)
    ours = GaussianMixture(15, max_iter=20, tol=0, memory_limit=2**20, n_jobs=2, **init).fit(points)
    assert len(BlockPass(len(points), 15, 2**20, 2).blocks) > 1
    for name in FITTED:
        expected = getattr(reference, name)
        np.testing.assert_allclose(getattr(ours, name), expected, rtol=1e-8, atol=1e-8 * np.abs(expected).max())
    assert ours.lower_bound_ == pytest.approx(reference.score(points), abs=1e-10)


def traced_peak_mib(function):
    tracemalloc.start()
    try:
        function()
        return tracemalloc.get_traced_memory()[1] / 2**20
    finally:
        tracemalloc.stop()


def test_memory_is_bounded_by_the_limit_not_by_n_prims_times_n_components():
    """100,000 points at K=100: all responsibilities are 76 MiB; the fit's own arrays are about 12 floats per
    point (9 MiB) beside its input's moments (10 MiB), so with 4 MiB blocks it must stay far below 76 MiB."""
    rng = np.random.default_rng(0)
    points = rng.normal(size=(100_000, 3))
    k = 100
    start = dict(weights_init=np.full(k, 1 / k), means_init=points[:k], precisions_init=np.tile(np.eye(3), (k, 1, 1)))
    fit = lambda limit: GaussianMixture(k, max_iter=2, memory_limit=limit, **start).fit(points)  # noqa: E731
    assert traced_peak_mib(lambda: fit(4 * 2**20)) < 40
    assert traced_peak_mib(lambda: fit(2**30)) > 76  # the same fit in one block holds every responsibility


def test_kmeans_on_a_subsample_is_seeded_and_finds_the_clusters(monkeypatch):
    """Five well separated blobs: k-means on 500 of 20,000 points finds the same clusters as on all of them."""
    rng = np.random.default_rng(1)
    centres = rng.uniform(-100, 100, size=(5, 3))
    points = (centres[:, None, :] + rng.normal(size=(5, 4000, 3))).reshape(-1, 3)
    full = GaussianMixture(5, random_state=4).fit(points)
    monkeypatch.setattr(dgmm.mixture, "_KMEANS_SAMPLE", 500)
    subsampled = [GaussianMixture(5, random_state=4).fit(points) for _ in range(2)]
    assert np.array_equal(subsampled[0].means_, subsampled[1].means_)
    order = lambda model: np.argsort(model.means_[:, 0])  # noqa: E731
    np.testing.assert_allclose(subsampled[0].means_[order(subsampled[0])], full.means_[order(full)], rtol=1e-9)
    assert subsampled[0].lower_bound_ == pytest.approx(full.lower_bound_, rel=1e-12)


@pytest.mark.parametrize("params, message", [
    ({"memory_limit": 0.5}, "memory_limit=0.5: must be a number of bytes >= 1"),
    ({"n_jobs": 0}, "n_jobs=0: must be None or a nonzero integer"),
    ({"n_jobs": 1.5}, "n_jobs=1.5: must be None or a nonzero integer"),
])
def test_bad_block_parameters_are_one_line_errors(bunny_res4, params, message):
    with pytest.raises(InputError, match=message.replace("(", r"\(")):
        GaussianMixture(3, **params).fit(bunny_res4)
