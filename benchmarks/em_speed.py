"""dgmm vs scikit-learn EM, in one run, on one BLAS thread (as the workflow's jobs run).

1. 50,000 points on bunny res4, K=100, full covariances, 25 iterations, tol 0, the same starting parameters:
   time ratio, final mean log-likelihoods, peak traced memory.
2. 50,000 triangles vs 50,000 points through dgmm: the cost of exact triangles.
3. ``score_samples`` on 50,000 points with K=400.
4. ``--grid``: seconds per EM iteration against scikit-learn across shapes, d in {2, 3, 8, 32} x K in {5, 100,
   1000} x n in {10^4, 10^6} x every covariance type, from the same start (tol 0), alternating the two libraries
   repeat by repeat; a markdown table on stdout. Cells whose estimated memory or time do not fit are skipped
   and listed with why (:func:`grid`).

Usage: ``python benchmarks/em_speed.py`` (sections 1-3, as ``make bench``), ``python benchmarks/em_speed.py
--grid --budget-minutes 20`` (section 4 alone), ``--all`` (both).
"""
import os

if __name__ == "__main__":  # one thread, set before numpy loads its BLAS (not when imported: sweep_profile.py)
    for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ.setdefault(_variable, "1")

import argparse
import itertools
import sys
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np
import trimesh
from sklearn.mixture import GaussianMixture as SklearnGaussianMixture
from threadpoolctl import threadpool_info, threadpool_limits

from dgmm import GaussianMixture, Primitives
from dgmm.mixture import layout

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


# -- section 4: the grid of shapes ------------------------------------------------------------------------

GRID_DIMENSIONS, GRID_COMPONENTS, GRID_SIZES = (2, 3, 8, 32), (5, 100, 1000), (10_000, 1_000_000)
COVARIANCE_TYPES = ("full", "tied", "diag", "spherical")
SCORE_ROWS = 20_000  # final log-likelihoods compared on the first rows (both fits' own parameters)


def grid_points(d, n, seed=0):
    """``n`` points in dimension ``d``: the bunny res4's surface for d = 3, else a sample of a random
    20-component mixture (means uniform in [-10, 10]^d, covariances ``A Aᵀ / d + 0.1 I``), seeded."""
    if d == 3:
        mesh = trimesh.load(BUNNY_RES4, process=False)
        return np.ascontiguousarray(trimesh.sample.sample_surface(mesh, n, seed=seed)[0])
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-10, 10, size=(20, d))
    factors = rng.normal(size=(20, d, d)) / np.sqrt(d)
    labels = rng.integers(20, size=n)
    points = rng.normal(size=(n, d))
    for component in range(20):  # no (n, d, d) temporary
        rows = labels == component
        points[rows] = points[rows] @ factors[component].T + centres[component]
    return points + np.sqrt(0.1) * rng.normal(size=(n, d))


def grid_start(points, n_components, covariance_type, seed=1):
    """One shared start, cheap at any size: means at ``n_components`` distinct points (seeded), equal weights,
    and every component the data's covariance shrunk by ``n_components^(-2/d)``, as a precision of
    ``covariance_type``'s shape."""
    rng = np.random.default_rng(seed)
    n, d = points.shape
    means = points[rng.choice(n, n_components, replace=False)]
    covariance = np.atleast_2d(np.cov(points[:100_000].T)) * n_components ** (-2 / d)
    precision = np.linalg.inv(covariance)
    precisions = {"full": np.tile(precision, (n_components, 1, 1)), "tied": precision,
                  "diag": np.tile(1 / np.diag(covariance), (n_components, 1)),
                  "spherical": np.full(n_components, d / np.trace(covariance))}[covariance_type]
    return dict(weights_init=np.full(n_components, 1 / n_components), means_init=means, precisions_init=precisions)


class _StampedSklearn(SklearnGaussianMixture):
    """scikit-learn's GaussianMixture noting the time after every M-step: the gaps are its EM iterations
    (E-step, M-step, bound), as dgmm's callbacks are ours."""

    def _m_step(self, *args, **kwargs):
        super()._m_step(*args, **kwargs)
        self.stamps_.append(time.perf_counter())


def _gaps_sklearn(points, k, covariance_type, init, iterations):
    """scikit-learn's fit from ``init`` (tol 0): seconds between its iterations' ends, (iterations - 1,), and the
    model."""
    model = _StampedSklearn(k, covariance_type=covariance_type, max_iter=iterations, tol=0, **init)
    model.stamps_ = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(points)
    return np.diff(model.stamps_), model


def _gaps_dgmm(points, k, covariance_type, init, iterations):
    """dgmm's fit from ``init`` (tol 0, so every iteration ends with its E-step): seconds between its
    iterations' callbacks, (iterations - 1,), and the model."""
    stamps = []
    model = GaussianMixture(k, covariance_type=covariance_type, max_iter=iterations, tol=0,
                            callback=lambda iteration, fitted: stamps.append(time.perf_counter()), **init)
    model.fit(points)
    return np.diff(stamps), model


def memory_estimates(d, k, n):
    """Bytes (scikit-learn's, dgmm's) a fit holds: scikit-learn its (n, K) log-probabilities,
    log-responsibilities and responsibilities beside the data (counted from its arrays); dgmm the points' zero
    (n, d, d) covariances and its (n, columns) moment table (``dgmm.mixture.layout``), within 5% of the peak RSS
    above the interpreter's measured at n = 10^5, d = 8 and 32, on this machine."""
    return 8 * n * (3 * k + 3 * d), 8 * n * (d * d + layout(d).n_columns + 2 * d)


def grid(budget_minutes=20.0, iterations=3, memory_gb=6.0, max_iteration_seconds=60.0, out=sys.stdout):
    """Seconds per EM iteration, dgmm and scikit-learn, over the grid of shapes; a markdown table on ``out``.

    Both fit the same points from the same start (:func:`grid_start`) with tol 0 and ``iterations`` iterations,
    alternating repeat by repeat (two repeats when the cell is estimated under 30 s, else one); a library's
    time per iteration is its fastest gap between two iterations' ends, so starts and final E-steps are not
    timed. Cells run cheapest first (by n K d²). A cell is skipped, with its reason, when either library's
    estimated memory (:func:`memory_estimates`) exceeds ``memory_gb``, or when its time estimated from the
    largest cell already measured at the same d and covariance type (scaled by n K) exceeds
    ``max_iteration_seconds`` per scikit-learn iteration or what is left of the budget.
    """
    started = time.perf_counter()
    cells = sorted(itertools.product(GRID_DIMENSIONS, GRID_COMPONENTS, GRID_SIZES, COVARIANCE_TYPES),
                   key=lambda c: (c[2] * c[1] * c[0] ** 2, c))
    data, rows, measured = {}, {}, {}
    for d, k, n, covariance_type in cells:
        left = budget_minutes * 60 - (time.perf_counter() - started)
        sk_bytes, ours_bytes = memory_estimates(d, k, n)
        if max(sk_bytes, ours_bytes) > memory_gb * 1e9:
            who = (f"scikit-learn's n×K arrays would take {sk_bytes / 1e9:.1f} GB" if sk_bytes > memory_gb * 1e9
                   else f"dgmm's zero covariances and moment table would take {ours_bytes / 1e9:.1f} GB")
            rows[d, k, n, covariance_type] = f"skipped (memory: {who}; limit {memory_gb:g} GB)"
            continue
        reference = max((key for key in measured if key[0] == d and key[3] == covariance_type
                         and key[1] * key[2] <= k * n), key=lambda key: key[1] * key[2], default=None)
        estimate_sk = estimate_cell = 0.0
        if reference is not None:
            scale = k * n / (reference[1] * reference[2])
            estimate_sk, estimate_ours = (t * scale for t in measured[reference])
            estimate_cell = (iterations + 2) * estimate_sk + (iterations + 1) * estimate_ours
        if estimate_sk > max_iteration_seconds:
            rows[d, k, n, covariance_type] = (f"skipped (time: estimated {estimate_sk:.3g} s per scikit-learn "
                                              f"iteration from d={d}, K={reference[1]}, n={reference[2]}; "
                                              f"limit {max_iteration_seconds:g} s)")
            continue
        if left <= 0:
            rows[d, k, n, covariance_type] = f"skipped (time: the {budget_minutes:g}-minute budget is spent)"
            continue
        if estimate_cell > left:
            rows[d, k, n, covariance_type] = (f"skipped (time: estimated {estimate_cell:.3g} s for the cell from "
                                              f"d={d}, K={reference[1]}, n={reference[2]}; {left:.0f} s "
                                              "left of the budget)")
            continue
        if (d, n) not in data:
            data = {(d, n): grid_points(d, n)}  # one data set held at a time
        points = data[d, n]
        init = grid_start(points, k, covariance_type)
        sk_gaps, ours_gaps = [], []
        for _ in range(2 if estimate_cell < 30 else 1):
            gaps, sk = _gaps_sklearn(points, k, covariance_type, init, iterations)
            sk_gaps.extend(gaps)
            gaps, ours = _gaps_dgmm(points, k, covariance_type, init, iterations)
            ours_gaps.extend(gaps)
        t_sk, t_ours = min(sk_gaps), min(ours_gaps)
        measured[d, k, n, covariance_type] = (t_sk, t_ours)
        ll_sk, ll_ours = sk.score(points[:SCORE_ROWS]), ours.score(points[:SCORE_ROWS])
        difference = abs(ll_ours - ll_sk) / abs(ll_sk)
        rows[d, k, n, covariance_type] = (t_ours, t_sk, difference)
        print(f"d={d} K={k} n={n} {covariance_type}: dgmm {t_ours:.4g} s, scikit-learn {t_sk:.4g} s, ratio "
              f"{t_ours / t_sk:.3f}, log-likelihood difference {difference:.1e} "
              f"[{time.perf_counter() - started:.0f} s, load {os.getloadavg()[0]:.2f}]", file=sys.stderr, flush=True)

    print(f"{iterations} EM iterations from the same start, tol 0, one thread; {time.perf_counter() - started:.0f} s "
          f"of a {budget_minutes:g}-minute budget; final mean log-likelihoods on the first {SCORE_ROWS} points, "
          "agreeing when their relative difference is at most 1e-9\n", file=out)
    print("| d | K | n | covariance_type | dgmm s / iteration | scikit-learn s / iteration | ratio | "
          "log-likelihoods agree (relative difference) |", file=out)
    print("|---|---|---|---|---|---|---|---|", file=out)
    skipped = []
    for d, k, n, covariance_type in itertools.product(GRID_DIMENSIONS, GRID_COMPONENTS, GRID_SIZES,
                                                      COVARIANCE_TYPES):
        row = rows[d, k, n, covariance_type]
        cell = f"| {d} | {k} | {n:,} | {covariance_type} |"
        if isinstance(row, str):
            print(f"{cell} – | – | – | {row} |", file=out)
            skipped.append(row)
        else:
            t_ours, t_sk, difference = row
            print(f"{cell} {t_ours:.3g} | {t_sk:.3g} | {t_ours / t_sk:.3f} | "
                  f"{'yes' if difference <= 1e-9 else 'no'} ({difference:.1e}) |", file=out)
    ratios = [row[0] / row[1] for row in rows.values() if not isinstance(row, str)] or [np.nan]
    print(f"\n{len(rows) - len(skipped)} cells measured, {len(skipped)} skipped; ratio dgmm / scikit-learn from "
          f"{min(ratios):.3f} to {max(ratios):.3f}, {sum(r <= 0.1 for r in ratios)} cells at most 0.1, "
          f"{sum(r >= 1 for r in ratios)} at least 1", file=out)


def parse_args(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", action="store_true", help="run the grid of shapes (section 4) alone")
    parser.add_argument("--all", action="store_true", help="run sections 1-3 and then the grid")
    parser.add_argument("--budget-minutes", type=float, default=20.0, help="the grid's time budget")
    parser.add_argument("--iterations", type=int, default=3,
                        help="EM iterations per grid fit (the gaps between them timed)")
    parser.add_argument("--memory-gb", type=float, default=6.0, help="skip grid cells estimated above this")
    parser.add_argument("--max-iteration-seconds", type=float, default=60.0,
                        help="skip grid cells whose scikit-learn iteration is estimated above this")
    return parser.parse_args(argv)


if __name__ == "__main__":
    args = parse_args()
    with threadpool_limits(1):
        if not args.grid:
            main()
        if args.grid or args.all:
            grid(args.budget_minutes, args.iterations, args.memory_gb, args.max_iteration_seconds)
