"""dgmm vs scikit-learn EM, in one run, on one BLAS thread (as the workflow's jobs run).

1. 50,000 points on bunny res4, K=100, full covariances, 25 iterations, tol 0, the same starting parameters:
   time ratio, final mean log-likelihoods, peak traced memory.
2. 50,000 triangles vs 50,000 points through dgmm: the cost of exact triangles.
3. ``score_samples`` on 50,000 points with K=400.

Usage: ``python benchmarks/em_speed.py`` (or ``make bench``).
"""
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np
import trimesh
from sklearn.mixture import GaussianMixture as SklearnGaussianMixture
from threadpoolctl import threadpool_info, threadpool_limits

from dgmm import GaussianMixture, Primitives

BUNNY_RES4 = Path(__file__).resolve().parents[2] / "shared" / "data" / "stanford" / "bunny_res4.ply"
N, K, ITERATIONS = 50_000, 100, 25


def timed(function, repeats=1):
    """Best wall time over ``repeats`` calls, the last result, and the peak traced memory (MiB)."""
    best = np.inf
    for _ in range(repeats):
        tracemalloc.start()
        start = time.perf_counter()
        result = function()
        best = min(best, time.perf_counter() - start)
        peak = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
    return best, result, peak


def starting_parameters(points, n_components):
    """One shared start for both libraries: scikit-learn's k-means initialisation, no EM step taken."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        start = SklearnGaussianMixture(n_components, max_iter=1, random_state=0).fit(points)
    return dict(weights_init=start.weights_, means_init=start.means_, precisions_init=start.precisions_)


def bunny_points():
    """The benchmark's bunny res4 mesh and its N surface points (seed 0)."""
    mesh = trimesh.load(BUNNY_RES4, process=False)
    return mesh, trimesh.sample.sample_surface(mesh, N, seed=0)[0]


def sklearn_fit(points, init):
    """scikit-learn's EM on ``points``: K components, ITERATIONS iterations, tol 0, from ``init``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return SklearnGaussianMixture(K, max_iter=ITERATIONS, tol=0, **init).fit(points)


def sklearn_fit_seconds():
    """The project's speed yardstick: scikit-learn's wall time for the fit of :func:`main` (call it on one BLAS
    thread), also the unit of benchmarks/sweep_profile.py."""
    points = bunny_points()[1]
    init = starting_parameters(points, K)
    return timed(lambda: sklearn_fit(points, init))[0]


def main():
    mesh, points = bunny_points()
    init = starting_parameters(points, K)
    blas = {(i["internal_api"], i.get("architecture")) for i in threadpool_info()}
    print(f"bunny res4, {N} points, K={K}, {ITERATIONS} iterations, tol 0, 1 thread; libraries: {sorted(blas)}")

    ours_fit = lambda: GaussianMixture(K, max_iter=ITERATIONS, tol=0, **init).fit(points)  # noqa: E731
    t_sk, sk, mem_sk = timed(lambda: sklearn_fit(points, init))
    t_ours, ours, mem_ours = timed(ours_fit, repeats=3)
    ll_sk, ll_ours = sk.score(points), ours.score(points)
    print(f"fit      scikit-learn {t_sk:7.3f} s  {mem_sk:7.1f} MiB  log-likelihood {ll_sk:.12f}")
    print(f"fit      dgmm         {t_ours:7.3f} s  {mem_ours:7.1f} MiB  log-likelihood {ll_ours:.12f}")
    print(f"fit      time ratio dgmm/scikit-learn {t_ours / t_sk:.3f} (target <= 0.125); "
          f"log-likelihood relative difference {abs(ll_ours - ll_sk) / abs(ll_sk):.1e} (target <= 1e-9)")

    fine = mesh.subdivide().subdivide().subdivide()
    triangles = Primitives.from_mesh(fine.vertices, fine.faces[:N])
    centroids = triangles.means
    t_tri, _, _ = timed(lambda: GaussianMixture(K, max_iter=ITERATIONS, tol=0, **init).fit(triangles), repeats=3)
    t_pts, _, _ = timed(lambda: GaussianMixture(K, max_iter=ITERATIONS, tol=0, **init).fit(centroids), repeats=3)
    print(f"mesh     {N} triangles {t_tri:.3f} s vs {N} points {t_pts:.3f} s: ratio {t_tri / t_pts:.2f} "
          "(target <= 1.2)")

    big_init = starting_parameters(points, 400)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sk400 = SklearnGaussianMixture(400, max_iter=1, tol=0, **big_init).fit(points)
    ours400 = GaussianMixture(400, max_iter=1, tol=0, **big_init).fit(points)
    t_sk_score, s_sk, _ = timed(lambda: sk400.score_samples(points), repeats=3)
    t_our_score, s_ours, _ = timed(lambda: ours400.score_samples(points), repeats=3)
    print(f"score    K=400 scikit-learn {t_sk_score:.3f} s, dgmm {t_our_score:.3f} s: ratio "
          f"{t_our_score / t_sk_score:.3f} (target <= 0.2); max |difference| {np.abs(s_sk - s_ours).max():.1e}")


if __name__ == "__main__":
    with threadpool_limits(1):
        main()
