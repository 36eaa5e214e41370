"""The start-method claims' shared helpers (Fig 3 and Fig 4): per-cell estimates of one model's inputs, the
k-means − random gaps, and the two contrasts the paper draws from them."""
from functools import partial

import numpy as np

from dgmm.experiments.report.claims.grading import LOSS, OFTEN_WORDS, TIE, WIN, compare, estimate, inside, magnitude
from dgmm.experiments.report.claims.record import LIKELIHOOD, PerEmClaim
from dgmm.experiments.report.claims.rules import (FIG3_MODEL, OWN_CELLS, SIGNIFICANT_NAT, Cause, em, fitted_variant,
                                                  is_mesh, listing, switch_or_not_found)


def still_climbing(data, variant, k=100):
    """The mean evaluation log-likelihood of res4's exact mesh from random starts at 25 iterations and at the end of
    convergence.csv's fits, as words: how far those fits still had to go at the paper's 25."""
    rows = [row for row in data.convergence or [] if row["input"] == "res4-exact" and row["variant"] == variant
            and row["init"] == "random" and int(row["K"]) == k]
    if not rows:
        return "convergence.csv missing"
    early, final = (estimate([float(row[column]) for row in rows]) for column in ("eval_ll_25", "eval_ll_final"))
    return f"res4-exact's random starts at K={k} score {early:.2f} at iteration 25 and {final:.2f} after 100"


def cells(estimates, model, inputs, variant):
    """``(init, K) -> {input: Estimate}`` for ``model``'s ``inputs`` with mesh inputs fitted by ``variant``
    (``estimates``: :attr:`~.measurements.Measurements.estimates`)."""
    result = {}
    for (row_model, input_name, row_variant, init, k), value in estimates.items():
        if row_model == model and input_name in inputs and row_variant == fitted_variant(input_name, variant):
            result.setdefault((init, k), {})[input_name] = value
    return dict(sorted(result.items()))


def init_gaps(estimates, model, inputs, variant):
    """``(input, K) -> kmeans − random`` (an Estimate) for the ``inputs`` fitted from both starts."""
    table = cells(estimates, model, inputs, variant)
    return {(name, k): cell[name] - table[("random", k)][name]
            for (init, k), cell in table.items() if init == "kmeans"
            for name in inputs if name in cell and name in table.get(("random", k), {})}


def versus_rivals(label, ours, rivals, detail):
    """``ours`` (an Estimate) against every rival of ``rivals`` (name -> Estimate), each with its own tie band: lost
    when any rival is above it beyond its band, won when it is above every one beyond theirs, else tied. (Against
    only the highest rival mean, the maximum of noisy means, with that rival's error alone, ours would lose to
    noise: a winner's curse.)

    Returns
    -------
    rival : the name that decides: the one ours loses to by most, else the one it ties nearest, else the one it
        beats by least (None when ``rivals`` is empty).
    comparison : its Comparison, labelled ``label``, its detail ``detail(rival, rival's Estimate)``.
    """
    if not rivals:
        return None, None
    compared = {name: compare(label, ours - value) for name, value in rivals.items()}
    rival = min(compared, key=lambda name: _deciding(compared[name]))
    return rival, compare(label, ours - rivals[rival], detail=detail(rival, rivals[rival]))


def _deciding(comparison):
    """Sort key of the rival that decides: lost by most, else tied nearest, else beaten by least."""
    c = comparison
    return {LOSS: (0, c.margin + c.band), TIE: (1, c.margin), WIN: (2, c.margin - c.band)}[c.outcome]


def median(values):
    return float(np.median(values))


# -- shared claims: the start-method contrasts of Fig 3 and Fig 4 ---------------------------------------------------

def init_contrast(name, words, section, figure, title, inputs, quantifier, paper_words):
    """The claim that mesh inputs are (largely) invariant to the start where point inputs are not. Both halves of the
    paper's sentence are compared: per (mesh input, K), the mesh's kmeans − random within
    ±:data:`~.rules.SIGNIFICANT_NAT` (invariant in itself: the two starts' likelihoods "very similar", short of a
    practical difference), and per (mesh input, point input, K), the mesh's |kmeans − random| below the point
    input's (the contrast)."""
    return PerEmClaim(
        name, words, section, figure, title,
        rule=(f"share, {quantifier.name}: one (mesh input, K), its kmeans − random within ±{SIGNIFICANT_NAT:.2f} nat "
              "(a practical difference; its whole tie band inside); and one (mesh input, point input, K), the point "
              "input's |kmeans − random| − the mesh input's > 0"),
        quantifier=quantifier, comparisons=partial(_contrast_comparisons, inputs),
        cause=partial(_contrast_cause, inputs), table=LIKELIHOOD, needs="mesh and point fits from both starts",
        paper=paper_words)


def _contrast_comparisons(inputs, data, variant):
    """:func:`init_contrast`'s comparisons on ``variant``'s fits of ``inputs``, and the median gaps."""
    mesh, points = _mesh_and_points(inputs)
    gaps = init_gaps(data.estimates, FIG3_MODEL, inputs, variant)
    invariant = [inside(f"{name} K={k} invariant", gap, -SIGNIFICANT_NAT, SIGNIFICANT_NAT,
                        detail=f"{gap:+.3f} ± {gap.band:.3f}") for (name, k), gap in gaps.items() if name in mesh]
    compared = invariant + [
        compare(f"{name} vs {other} K={k}", magnitude(gaps[other, k]) - magnitude(gap),
                detail=f"{gap:+.3f} vs {gaps[other, k]:+.3f}")
        for (name, k), gap in gaps.items() if name in mesh for other in points if (other, k) in gaps]
    if not compared:
        return None
    return compared, (f"median |kmeans − random| meshes {_median_gap(gaps, mesh):.3f}, points "
                      f"{_median_gap(gaps, points):.3f} nat; kmeans − random, mesh vs point input: {listing(compared)}")


def _contrast_cause(inputs, data, variant, grades, compared):
    """The meshes' random starts still climbing at iteration 25, or the EM (:func:`~.rules.switch_or_not_found`)."""
    mesh, points = _mesh_and_points(inputs)
    gaps = init_gaps(data.estimates, FIG3_MODEL, inputs, variant)
    finding = (f"{em(variant)}'s random starts end a median {_median_gap(gaps, mesh):.2f} nat below k-means on "
               f"the meshes, as far as on the points ({_median_gap(gaps, points):.2f}), still short of convergence "
               f"at iteration 25 ({still_climbing(data, variant)})")
    return switch_or_not_found(finding, variant, grades, compared)


def _mesh_and_points(inputs):
    """``inputs`` split into mesh inputs and point inputs."""
    return tuple(n for n in inputs if is_mesh(n)), tuple(n for n in inputs if not is_mesh(n))


def _median_gap(gaps, names):
    """Median |kmeans − random| over the (input, K) of ``names``."""
    return median([abs(gap.value) for (name, _), gap in gaps.items() if name in names])


def prefer_an_init(name, words, section, figure, title, inputs, towards_kmeans, paper_words):
    """The claim that point inputs "often" prefer a start: per (point input, K), kmeans − random beyond its band
    either way, or towards k-means (``towards_kmeans``); point fits are textbook EM in both EMs' grades."""
    bars = "" if towards_kmeans else "|"
    return PerEmClaim(
        name, words, section, figure, title, f"share, often: one (point input, K), {bars}kmeans − random{bars} > 0",
        OFTEN_WORDS, comparisons=partial(_preferences, inputs, towards_kmeans),
        cause=partial(_prefer_cause, towards_kmeans), table=LIKELIHOOD,
        needs="point fits from both starts in likelihood.csv", paper=paper_words,
        evidence="{lines}. Point fits are the same for both EMs.", mesh=False)


def _preferences(inputs, towards_kmeans, data, variant):
    """Per (point input, K), its kmeans − random (its magnitude unless ``towards_kmeans``)."""
    gaps = init_gaps(data.estimates, FIG3_MODEL, inputs, "textbook")
    compared = [compare(f"{name} K={k}", gap if towards_kmeans else magnitude(gap), detail=f"{gap:+.3f}")
                for (name, k), gap in gaps.items()]
    return (compared, f"kmeans − random: {listing(compared)}") if compared else None


def _prefer_cause(towards_kmeans, data, variant, grades, compared):
    """Why point inputs do not often prefer (k-means): collapse of k-means starts at high K, when that is where the
    comparisons are lost."""
    lost = [c for c in compared[variant] if c.outcome != WIN]
    if towards_kmeans and lost and all(c.margin < 0 for c in lost):
        return Cause("K-means-started point fits collapse at high K and end below the random starts.",
                     f"the k-means starts end below the random ones at {'; '.join(map(str, lost))}", OWN_CELLS)
    return Cause("Cause not found: the point fits end as high from either start.")
