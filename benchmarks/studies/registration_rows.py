"""Which rows of registration.csv a change moved, and by how much: two sweeps' tables compared trial by trial.

Per (model, protocol, variant, method): how many trials moved at all, the largest change of the rotation and
translation errors, how many changed their iteration count or their ``converged`` flag; then every trial whose
rotation or translation error moved by more than ``--beyond`` (degrees, % of the diagonal), before and after.

Run: ``python benchmarks/studies/registration_rows.py BEFORE.csv AFTER.csv [--beyond 1e-3]``
(two sweeps' ``results/tables/registration.csv``, e.g. of clones at two commits).
"""
import argparse
import csv

KEY = ("model", "mesh", "protocol", "variant", "method", "trial")
ERRORS = ("rotation_error_deg", "translation_error_pct")


def read(path):
    """``key -> row`` of a registration.csv."""
    with open(path, newline="") as table:
        return {tuple(row[k] for k in KEY): row for row in csv.DictReader(table)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before")
    parser.add_argument("after")
    parser.add_argument("--beyond", type=float, default=1e-3)
    args = parser.parse_args()
    before, after = read(args.before), read(args.after)
    if before.keys() != after.keys():
        raise SystemExit(f"the tables hold different trials: {len(before.keys() ^ after.keys())} differ")
    groups, far = {}, []
    for key, old in before.items():
        new = after[key]
        changes = [abs(float(new[e]) - float(old[e])) for e in ERRORS]
        group = groups.setdefault((key[0], key[2], key[3], key[4]), [0, 0, 0.0, 0.0, 0, 0])
        group[0] += 1
        group[1] += any(old[e] != new[e] for e in ERRORS)
        group[2], group[3] = max(group[2], changes[0]), max(group[3], changes[1])
        group[4] += old["iterations"] != new["iterations"]
        group[5] += old["converged"] != new["converged"]
        if max(changes) > args.beyond:
            far.append((key, old, new))
    print("| model | protocol | variant | method | trials | moved | largest change, rotation (°) / translation (%) "
          "| iterations changed | converged changed |")
    print("|---|---|---|---|---:|---:|---|---:|---:|")
    for (model, protocol, variant, method), (n, moved, rotation, translation, iterations, converged) in sorted(
            groups.items()):
        print(f"| {model} | {protocol} | {variant} | {method} | {n} | {moved} | {rotation:.2g} / {translation:.2g} | "
              f"{iterations} | {converged} |")
    print(f"\n{len(far)} trials moved by more than {args.beyond:g}° or {args.beyond:g}%:\n")
    print("| model | protocol | variant | method | trial | rotation (°) before → after | translation (%) before → "
          "after | iterations before → after |")
    print("|---|---|---|---|---:|---|---|---|")
    for (model, _, protocol, variant, method, trial), old, new in far:
        print(f"| {model} | {protocol} | {variant} | {method} | {trial} | "
              + " | ".join(f"{float(old[e]):.4g} → {float(new[e]):.4g}" for e in ERRORS)
              + f" | {old['iterations']} → {new['iterations']} |")


if __name__ == "__main__":
    main()
