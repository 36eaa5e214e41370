"""P2D registration speed: analytic gradient vs BFGS forward differences (the paper's setup), same trials.

A scikit-learn GMM (K=100, k-means, 100 iterations, tol 1e-5; the registration GMMs of paper §V) is fitted to the
vertices of bunny res4. Each trial draws a fresh surface sample of as many points as the mesh has vertices,
moves it by a random rigid trial (±15°, ±0.05 per axis) and registers it back with both gradient modes,
interleaved so that load on the shared machine hits both alike.

Run: ``.venv/bin/python benchmarks/registration_speed.py [--trials 20] [--components 100] [--seed 0]``
"""
import argparse
from pathlib import Path

import numpy as np
import trimesh
from sklearn.mixture import GaussianMixture

from dgmm import registration as reg

BUNNY = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "stanford" / "bunny_res4.ply"
MODES = ("analytic", "numeric")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--components", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    mesh = trimesh.load(BUNNY, process=False)
    vertices = np.asarray(mesh.vertices)
    diagonal = float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))
    mixture = GaussianMixture(args.components, init_params="kmeans", tol=1e-5, max_iter=100,
                              random_state=args.seed).fit(vertices)
    rng = np.random.default_rng(args.seed)
    rows = {mode: [] for mode in MODES}
    for trial_index in range(args.trials):
        sample = np.asarray(trimesh.sample.sample_surface(mesh, len(vertices), seed=rng)[0])
        trial = reg.random_trials(1, rng, diagonal, sample.mean(axis=0))[0]
        source = trial.apply(sample)
        for mode in MODES:
            result = reg.register_p2d(source, mixture, gradient=mode)
            rows[mode].append((result.seconds, result.iterations, result.objective,
                               *reg.registration_errors(result, trial, diagonal)))
        print(f"trial {trial_index:3d}: " + "  ".join(
            f"{mode} {rows[mode][-1][0] * 1e3:7.1f} ms {rows[mode][-1][3]:.3f}° {rows[mode][-1][4]:.3f}%"
            for mode in MODES), flush=True)

    print(f"\nbunny res4, sklearn GMM K={args.components} on {len(vertices)} vertices, {args.trials} trials, "
          f"{len(vertices)} source points")
    print(f"{'gradient':>9} {'ms/reg':>8} {'iters':>6} {'-mean ll':>9} {'rot° mean':>10} {'trans% mean':>12}")
    means = {mode: np.mean(rows[mode], axis=0) for mode in MODES}
    for mode in MODES:
        seconds, iterations, objective, rotation, translation = means[mode]
        print(f"{mode:>9} {seconds * 1e3:8.1f} {iterations:6.1f} {objective:9.4f} {rotation:10.4f} {translation:12.4f}")
    total = {mode: np.sum(np.array(rows[mode])[:, 0]) for mode in MODES}
    print(f"time ratio numeric / analytic: {total['numeric'] / total['analytic']:.1f}x")


if __name__ == "__main__":
    main()
