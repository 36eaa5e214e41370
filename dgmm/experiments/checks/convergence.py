"""Fits run past the paper's 25 iterations: how fast each input converges, and what 100 iterations buy.

The paper's Discussion: "When 100 iterations were used, the point-based methods performed better (nearly as good
as our proposed method). However, our method often converged in about 1/3 the number of iterations". Every fit
here runs ``max_iter`` (config: 100) EM iterations from the seed the fitting sweep gives the same (input, variant,
K, init, seed), so its state after ``SNAPSHOT`` (25) iterations is the sweep's fit. A row records the evaluation
log-likelihood at both (``eval_ll_25``, ``eval_ll_final``), how many iterations the bound took to come within each
of ``CONVERGED_NATS`` of its final value, and two "fuller model" numbers of the 25-iteration mixture (Fig 5): the
share of the evaluation points inside at least one component's 2σ ellipsoid, and the effective number of components
``exp(entropy of the weights)`` over K.

The bound is textbook EM's (eq. 8 for triangles, per unit area; the mean log-likelihood for points) under every
variant, so that "within 0.01 nat" is one scale: the authors' EM optimises its own bound, whose triangle terms are
scaled by ``α / α_min``, and its fits are scored on textbook EM's bound after each iteration.
"""
import numpy as np

from dgmm.experiments.sweep import job_seed
from dgmm.mixture import GaussianMixture

SNAPSHOT = 25
"""The paper's iterations: the state the fitting sweep scores."""
CONVERGED_NATS = (0.1, 0.01)
"""A fit has converged at the first iteration whose bound is within this of its bound after ``max_iter``."""
COVERAGE_SIGMA = 2.0
"""Radius (in standard deviations, Mahalanobis) of the ellipsoids whose union is the covered surface."""
COLUMNS = ("model", "input", "variant", "K", "init", "seed", "eval_ll_25", "eval_ll_final", "bound_25", "bound_final",
           "n_iter_within_0.1", "n_iter_within_0.01", "coverage_2sigma", "effective_components")


def iterations_to_converge(history, nats):
    """First iteration (1-based) whose bound is within ``nats`` of the last one and stays within it."""
    history = np.asarray(history)
    outside = np.flatnonzero(np.abs(history - history[-1]) > nats)
    return int(outside[-1] + 2) if len(outside) else 1


def coverage(mixture, points, n_sigma=COVERAGE_SIGMA):
    """Share of ``points`` (n_points, 3) within ``n_sigma`` Mahalanobis distance of at least one component."""
    inside = np.zeros(len(points), dtype=bool)
    for mean, prec_chol in zip(mixture.means_, mixture.precisions_cholesky_):
        inside |= np.einsum("nd,de->ne", points - mean, prec_chol) ** 2 @ np.ones(3) <= n_sigma**2
    return float(inside.mean())


def effective_components(weights):
    """``exp(entropy of the weights) / K``: 1 when every component weighs the same, 1/K for a single one."""
    weights = np.asarray(weights)
    present = weights[weights > 0]
    return float(np.exp(-(present * np.log(present)).sum()) / len(weights))


def convergence_rows(prims, evaluation, *, model, input_name, variant, components, inits, seeds, root_seed,
                     max_iter=100, tol=1e-12, reg_covar=1e-6):
    """Fit every (K, init, seed) for ``max_iter`` iterations and measure it (module docstring).

    Parameters
    ----------
    prims : Primitives
        The input, built as the fitting sweep builds ``input_name``.
    evaluation : ndarray of shape (n_points, 3)
        The input's evaluation set.
    model, input_name, variant : str
        Name the fit as the sweep does (its seeds come from them).
    components, inits : sequence
    seeds : int
        Seeds per (K, init): the sweep's first ``seeds``.
    max_iter : int
        Iterations of every fit (at least ``SNAPSHOT``); ``tol`` and ``reg_covar`` as the sweep's.

    Returns
    -------
    list of dict
        One per fit, with the keys of :data:`COLUMNS`.
    """
    rows = []
    for k in components:
        for init in inits:
            key = f"{model}/{input_name}/{variant}/k{k}-{init}"  # the fitting sweep's key: the same seeds
            for index in range(seeds):
                state = {"bounds": []}

                def keep(iteration, fitted, state=state):
                    if variant != "textbook":  # textbook EM's own bound is already the common scale
                        state["bounds"].append(fitted.score_primitives(prims))
                    if iteration == SNAPSHOT:
                        state["mixture"] = GaussianMixture.from_parameters(
                            fitted.weights_.copy(), fitted.means_.copy(), fitted.covariances_.copy())

                fitted = GaussianMixture(k, init=init, max_iter=max_iter, tol=tol, reg_covar=reg_covar,
                                         variant=variant, random_state=job_seed(root_seed, key, index),
                                         callback=keep).fit(prims)
                early = state.get("mixture", fitted)
                history = state["bounds"] or fitted.history_
                rows.append({
                    "model": model, "input": input_name, "variant": variant, "K": k, "init": init, "seed": index,
                    "eval_ll_25": early.score(evaluation), "eval_ll_final": fitted.score(evaluation),
                    "bound_25": history[min(SNAPSHOT, len(history)) - 1], "bound_final": history[-1],
                    **{f"n_iter_within_{nats:g}": iterations_to_converge(history, nats) for nats in CONVERGED_NATS},
                    "coverage_2sigma": coverage(early, evaluation),
                    "effective_components": effective_components(early.weights_)})
    return rows
