"""Claims about convergence (Discussion, Introduction, Conclusion), from the 100-iteration fits of
``convergence.csv`` (:mod:`dgmm.experiments.checks.convergence`: the Fig 3 sweep's seeds run on to 100 iterations)."""
from dgmm.experiments.report.claims.rules import (CLOSE_NATS, REPRODUCED, SHARE_RULE, Claim, Grade, lost, mean, median,
                                                  missing, pending, per_variant, ratio_verdict, same, share_verdict)

CONVERGED = "n_iter_within_0.01"
"""Iterations the bound took to come within 0.01 nat of its value after 100 (convergence.csv)."""
WHAT = "convergence.csv (config section `checks.convergence`)"


def _fits(data, variant):
    """``{(K, init, seed): {"exact": row, "points": [rows]}}`` of the exact mesh (``variant``) and point inputs."""
    fits = {}
    for row in data.convergence or []:
        key = (int(row["K"]), row["init"], int(row["seed"]))
        if row["input"].endswith("-exact") and row["variant"] == variant:
            fits.setdefault(key, {"points": []})["exact"] = row
        elif row["input"].endswith(("-centroids", "-vertices", "-points")):
            fits.setdefault(key, {"points": []})["points"].append(row)
    return {key: fit for key, fit in sorted(fits.items()) if "exact" in fit and fit["points"]}


def converges_in_a_third(data):
    """Discussion: "our method often converged in about 1/3 the number of iterations"."""
    section, title = "§IV-C", "The exact mesh converges in about 1/3 the iterations of point inputs"
    rule = ("median over fits of the iterations until the bound is within 0.01 nat of its 100-iteration value, "
            "exact mesh / point inputs (centroids, vertices), same K, start and seed: ≤ 0.5 reproduced, < 1 partly, "
            "else not reproduced")

    def grade(variant):
        fits = _fits(data, variant)
        if not fits:
            return missing(WHAT)
        exact = median([int(fit["exact"][CONVERGED]) for fit in fits.values()])
        points = median([int(row[CONVERGED]) for fit in fits.values() for row in fit["points"]])
        ratio = exact / points
        verdict = ratio_verdict(ratio, (0.0, 0.5), (0.0, 1.0 - 1e-12))
        return (Grade(verdict, f"{exact:g} / {points:g} = {ratio:.2f}", "" if verdict == REPRODUCED else
                      f"The exact mesh needs a median {exact:g} iterations against the points' {points:g}."),
                f"median {exact:g} iterations (exact) vs {points:g} (points), {len(fits)} fits")

    grades, lines = per_variant(grade)
    return Claim(section, title, rule, "; ".join(lines) + ".", grades, "≈ 1/3")


def converges_faster(data):
    """Introduction and Conclusion: mesh GMMs "converge faster", are built "more quickly"."""
    section, title = "§I, §VI", "Mesh GMMs converge faster than point GMMs"
    rule = (f"{SHARE_RULE}; a comparison is one (K, start, seed, point input): the exact mesh reaches 0.01 nat of its "
            "100-iteration bound in fewer iterations")

    def grade(variant):
        fits = _fits(data, variant)
        if not fits:
            return missing(WHAT)
        pairs = [(key, int(fit["exact"][CONVERGED]), int(row[CONVERGED]), row["input"])
                 for key, fit in fits.items() for row in fit["points"]]
        failed = [f"K={k} {init} seed {seed}: exact {e} vs {name} {p}" for (k, init, seed), e, p, name in pairs
                  if not e < p]
        wins = len(pairs) - len(failed)
        return (Grade(share_verdict(wins, len(pairs)), f"{wins}/{len(pairs)} faster", lost(failed)),
                f"faster in {wins} of {len(pairs)}")

    grades, lines = per_variant(grade)
    return Claim(section, title, rule, "; ".join(lines) + ".", grades, "faster")


def points_better_with_100(data):
    """Discussion: "When 100 iterations were used, the point-based methods performed better"."""
    section, title = "§IV-C", "With 100 iterations point inputs fit better than with 25"
    rule = f"{SHARE_RULE}; a comparison is one point fit (input, K, start, seed): eval log-likelihood at 100 > at 25"
    rows = [row for row in data.convergence or [] if row["input"].endswith(("-centroids", "-vertices", "-points"))]
    if not rows:
        return pending(section, title, rule, WHAT, "better")
    gains = [float(row["eval_ll_final"]) - float(row["eval_ll_25"]) for row in rows]
    failed = [f"{row['input']} K={row['K']} {row['init']} seed {row['seed']} {gain:+.3f}"
              for row, gain in zip(rows, gains) if not gain > 0]
    wins = len(rows) - len(failed)
    verdict = share_verdict(wins, len(rows))
    worst = min(gains)
    return Claim(section, title, rule + ". Point fits are the same for both EMs",
                 f"better in {wins} of {len(rows)} fits, mean gain {mean(gains):+.3f} nat.",
                 same(Grade(verdict, f"{wins}/{len(rows)}, mean {mean(gains):+.2f} nat",
                            "" if not failed else f"{len(failed)} point fits end lower on the evaluation set after "
                                                  f"100 iterations than after 25 (down to {worst:+.3f} nat). "
                                                  f"{lost(failed)}")), "better")


def points_nearly_match_at_100(data):
    """Discussion: with 100 iterations the point-based methods were "nearly as good as our proposed method"."""
    section, title = "§IV-C", "At 100 iterations point inputs are nearly as good as the exact mesh"
    rule = (f"{SHARE_RULE}; a comparison is one (K, start): the best point input's mean eval log-likelihood at 100 "
            f"iterations is within {CLOSE_NATS} nat below the exact mesh's (or above it)")

    def grade(variant):
        fits = _fits(data, variant)
        if not fits:
            return missing(WHAT)
        groups = {}
        for (k, init, seed), fit in fits.items():
            group = groups.setdefault((k, init), {"exact": [], "points": {}})
            group["exact"].append(float(fit["exact"]["eval_ll_final"]))
            for row in fit["points"]:
                group["points"].setdefault(row["input"], []).append(float(row["eval_ll_final"]))
        gaps = {key: mean(group["exact"]) - max(mean(values) for values in group["points"].values())
                for key, group in groups.items()}
        failed = [f"K={k} {init} {gap:+.2f}" for (k, init), gap in gaps.items() if gap > CLOSE_NATS]
        wins = len(gaps) - len(failed)
        return (Grade(share_verdict(wins, len(gaps)), f"{wins}/{len(gaps)} within {CLOSE_NATS}", lost(failed)),
                "exact − best points at 100 iterations "
                + ", ".join(f"K={k} {init} {gap:+.2f}" for (k, init), gap in gaps.items()))

    grades, lines = per_variant(grade)
    return Claim(section, title, rule, "; ".join(lines) + ".", grades, "nearly as good")


CLAIMS = (converges_in_a_third, converges_faster, points_better_with_100, points_nearly_match_at_100)
