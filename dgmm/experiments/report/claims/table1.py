"""Claims of §V-C "Other 3D Models" (Table 1: five models, K=100, k-means; scaled trial protocol)."""
import math

from dgmm.experiments.report import paper
from dgmm.experiments.report.claims.rules import (CLOSE_NATS, OFTEN_RULE, SHARE_RULE, Claim, Grade, lost, missing,
                                                  often_verdict, per_variant, share_verdict)

SIGNIFICANT_NATS = 0.5
"""A likelihood margin this large counts as significant (half a nat per evaluation point)."""
SIGNIFICANT_RATIO = 0.5
"""An error at most this fraction of another's counts as significantly lower."""


def _pairs(rows, measure):
    """(model, mesh value, points value) of every Table 1 row with both."""
    return [(row["model"], row[f"{measure}_mesh"], row[f"{measure}_points"]) for row in rows
            if not (math.isnan(row[f"{measure}_mesh"]) or math.isnan(row[f"{measure}_points"]))]


def _graded(data, section, title, rule, paper_words, grade, what):
    """A Table 1 claim graded per EM by ``grade(rows) -> (Grade, evidence line)`` (None when it has no data)."""
    grades, lines = per_variant(lambda variant: grade(data.table1(variant)) or missing(what))
    return Claim(section, title, rule, "; ".join(lines) + ".", grades, paper_words)


LIKELIHOODS = "likelihood.csv fits of Table 1's meshes (exact and vertices, K=100, k-means)"
ERRORS = "registration.csv trials of Table 1's meshes (mesh-kmeans, points-kmeans, icp)"


def mesh_likelihood_higher(data):
    """§V-C: "In all our experiments, the mesh-based GMM always outperformed the point-based one" (likelihood)."""
    rule = f"{SHARE_RULE}; a comparison is one model: mesh > points"

    def grade(rows):
        pairs = _pairs(rows, "ll")
        if not pairs:
            return None
        failed = [f"{m} mesh {a:.2f} ≤ points {b:.2f}" for m, a, b in pairs if not a > b]
        wins = len(pairs) - len(failed)
        return (Grade(share_verdict(wins, len(pairs)), f"{wins}/{len(pairs)} models", lost(failed)),
                ", ".join(f"{m} {a:.2f} vs {b:.2f}" for m, a, b in pairs))

    return _graded(data, "Table 1", "The mesh GMM has a higher likelihood than the points GMM on every model", rule,
                   f"{len(paper.TABLE1)}/{len(paper.TABLE1)} models", grade, LIKELIHOODS)


def likelihood_margins(data):
    """§V-C: the mesh GMM outperformed the points GMM, "often significantly" (likelihood)."""
    rule = f"{OFTEN_RULE}; a comparison is one model: mesh − points ≥ {SIGNIFICANT_NATS} nat"
    margins = [row[1] - row[0] for row in paper.TABLE1.values()]
    significant = sum(margin >= SIGNIFICANT_NATS for margin in margins)

    def grade(rows):
        pairs = _pairs(rows, "ll")
        if not pairs:
            return None
        wins = sum(a - b >= SIGNIFICANT_NATS for _, a, b in pairs)
        small = [f"{m} {a - b:+.2f}" for m, a, b in pairs if a - b < SIGNIFICANT_NATS]
        return (Grade(often_verdict(wins, len(pairs)), f"{wins}/{len(pairs)} ≥ {SIGNIFICANT_NATS} nat", lost(small)),
                ", ".join(f"{m} {a - b:+.2f}" for m, a, b in pairs))

    return _graded(data, "Table 1", "The likelihood margins are often significant", rule,
                   f"{significant}/{len(margins)} (margins " + ", ".join(f"{m:+.1f}" for m in margins) + ")", grade,
                   LIKELIHOODS)


def likelihood_values(data):
    """Table 1: the paper's likelihoods per model (points and mesh)."""
    rule = f"{SHARE_RULE}; a comparison is one (model, points or mesh): |ours − paper| ≤ {CLOSE_NATS} nat"

    def grade(rows):
        values = [(row["model"], kind, row[f"ll_{kind}"], row[f"ll_{kind}_paper"]) for row in rows
                  for kind in ("points", "mesh") if not math.isnan(row[f"ll_{kind}"])]
        if not values:
            return None
        failed = [f"{m} {kind} {a:.2f} vs {b:.2f}" for m, kind, a, b in values if abs(a - b) > CLOSE_NATS]
        wins = len(values) - len(failed)
        return (Grade(share_verdict(wins, len(values)), f"{wins}/{len(values)} within {CLOSE_NATS}", lost(failed)),
                f"{wins} of {len(values)} within {CLOSE_NATS} nat")

    return _graded(data, "Table 1", "Our likelihoods match the paper's per model", rule, "Table 1 values", grade,
                   LIKELIHOODS)


def mesh_registers_better(data):
    """§V-C: the mesh GMM "always outperformed" the points GMM (and ICP) in registration."""
    rule = f"{SHARE_RULE}; comparisons are (model, error): mesh < points, and mesh < 100% of ICP"
    published = [row[2:] for row in paper.TABLE1.values()]
    paper_wins = sum((mesh < points) + (mesh < 100.0) for row in published for points, mesh in (row[:2], row[2:]))

    def grade(rows):
        wins, total, failed, lines = 0, 0, [], []
        for measure in ("rot", "trans"):
            pairs = _pairs(rows, measure)
            wins += sum((a < b) + (a < 100.0) for _, a, b in pairs)
            total += 2 * len(pairs)
            failed += [f"{measure} {m} mesh {a:.0f}% (points {b:.0f}%)" for m, a, b in pairs
                       if not (a < b and a < 100.0)]
            lines += [f"{measure} {m} {a:.0f}% vs {b:.0f}%" for m, a, b in pairs]
        if not total:
            return None
        return Grade(share_verdict(wins, total), f"{wins}/{total}", lost(failed)), ", ".join(lines)

    return _graded(data, "Table 1", "The mesh GMM registers with lower errors than the points GMM and ICP", rule,
                   f"{paper_wins}/{4 * len(published)}", grade, ERRORS)


def registration_margins(data):
    """§V-C: "often significantly" (registration errors as % of ICP)."""
    rule = f"{OFTEN_RULE}; a comparison is one (model, error): mesh ≤ {SIGNIFICANT_RATIO:g} × points"
    published = [row[2:] for row in paper.TABLE1.values()]
    paper_wins = sum(mesh <= SIGNIFICANT_RATIO * points for row in published for points, mesh in (row[:2], row[2:]))

    def grade(rows):
        pairs = [(measure, *pair) for measure in ("rot", "trans") for pair in _pairs(rows, measure)]
        if not pairs:
            return None
        failed = [f"{measure} {m} {a / b:.2f}" for measure, m, a, b in pairs if not a <= SIGNIFICANT_RATIO * b]
        wins = len(pairs) - len(failed)
        return (Grade(often_verdict(wins, len(pairs)), f"{wins}/{len(pairs)}", lost(failed)),
                ", ".join(f"{measure} {m} ×{a / b:.2f}" for measure, m, a, b in pairs))

    return _graded(data, "Table 1", "The registration margins are often significant (mesh ≤ half the points' error)",
                   rule, f"{paper_wins}/{len(published) * 2}", grade, ERRORS)


CLAIMS = (mesh_likelihood_higher, likelihood_margins, likelihood_values, mesh_registers_better, registration_margins)
