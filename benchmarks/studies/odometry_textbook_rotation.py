"""Why textbook EM's pixel mixtures drift more under rotation: their weights, their thinnest components, D2D's minimum.

On every ``--every``-th consecutive pair of a case (``odometry_rotation_drift.py``'s syntax: ``spun:…``, ``room:…``,
``fr1xyz:N``) both frames are fitted exactly as ``run_odometry`` fits them (``METHODS["gmm-pixels"]``, the frame's
seed ``[seed, index]``, the ``overlap`` schedule) under each of ``--fits`` (``EM:SIZE``: textbook or authors EM,
pixel size area or unit), and registered four ways against the truth's motion:

- ``schedule``: the schedule's registration from the identity (what the odometry does);
- ``from truth``: the same cut rounds started at the true motion (the cost's own minimum near the truth: an error
  here is a bias of the minimum, not of the basin);
- ``pixel weights``: the schedule with every mixture handed to D2D reweighted to its components' pixel counts
  (``π_k`` of textbook EM is a sum of footprint areas ∝ Z²: weights × Z_k^-2, Z_k the depth of the mean; the
  authors' and unit-size weights are pixel counts already, so left as they are);
- ``area weights``: conversely, pixel-count weights × Z_k² (the authors' and unit-size mixtures weighted as
  textbook EM weighs them; textbook left as it is).

Per mixture: the effective number of components ``1 / Σ π²``, the weight on components beyond the frame's median
pixel depth, the weighted median of the thinnest standard deviation ``√λmin`` and that of the components on the
nearer half, and the components' share of the far half. One thread; the pairs' errors as RMS and median.

Usage: ``python benchmarks/studies/odometry_textbook_rotation.py --cases spun:0:300:90:1 fr1xyz:300 [--every 10]
[--fits textbook:area authors:area textbook:unit] [--seed 0]``.
"""
import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

import dgmm.odometry.measured_cut as measured_cut  # noqa: E402
import dgmm.odometry.overlap as overlap  # noqa: E402
from dgmm.odometry import METHODS, SCHEDULES, first_frames, frame_motions  # noqa: E402
from dgmm.odometry.frame_model import CUT_TOL, ROUND_TOL  # noqa: E402
from dgmm.registration import Registration, rotation_distance_deg  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from odometry_d2d_weights import depth_weighted  # noqa: E402
from odometry_rotation_drift import ROOT, case_sequence  # noqa: E402


def mixture_stats(frame, depth_median):
    """(N_eff, far weight share, weighted median thinnest sd (mm), near half's, far half's component share)."""
    weights, means, covariances = frame.weights_, frame.means_, frame.covariances_
    thinnest = np.sqrt(np.linalg.eigvalsh(covariances)[:, 0]) * 1000
    far = means[:, 2] > depth_median

    def weighted_median(values, w):
        order = np.argsort(values)
        return values[order][np.searchsorted(np.cumsum(w[order]), 0.5 * w.sum())]

    return (1.0 / np.sum(weights ** 2), weights[far].sum(), weighted_median(thinnest, weights),
            weighted_median(thinnest[~far], weights[~far]) if (~far).any() else np.nan, far.mean())


def errors(registration, truth):
    return rotation_distance_deg(registration.rotation, truth[0]), float(np.linalg.norm(registration.translation
                                                                                       - truth[1]))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", required=True)
    parser.add_argument("--fits", nargs="+", default=["textbook:area", "authors:area", "textbook:unit"])
    parser.add_argument("--every", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--cache", default=str(ROOT / "results" / "benchmarks"))
    args = parser.parse_args()
    prepare, register = METHODS["gmm-pixels"]
    schedule = SCHEDULES["overlap"]
    plain = overlap.register_d2d, measured_cut.register_d2d
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print("| case | fit | pairs | schedule: RMS (°, cm), median (°, cm) | from truth: RMS | pixel weights: RMS | "
          "area weights: RMS | N_eff | far weight | thinnest sd (mm), near half's | far half's components |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for case in args.cases:
        sequence, intrinsics, count = case_sequence(case, args.cache)
        matched, truth_poses = sequence.groundtruth_at_frames()
        frames = matched if count is None else first_frames(sequence, count)[0]
        frames = frames[np.isin(frames, matched)]
        truth_poses = truth_poses.subset(np.flatnonzero(np.isin(matched, frames)))
        pairs = [k for k in range(0, len(frames) - 1, args.every) if frames[k + 1] == frames[k] + 1]
        truths = list(zip(*frame_motions(truth_poses)))
        depths = {}
        for fit in args.fits:
            variant, size = fit.split(":")
            options = {"n_components": 100, "warm_iter": None, "schedule": schedule, "variant": variant,
                       "size": size, "intrinsics": intrinsics}
            rows = {"schedule": [], "truth": [], "pixel": [], "area": []}
            stats = []
            for k in pairs:
                models = []
                for index in frames[k:k + 2]:
                    depth = sequence.depth(index)
                    if index not in depths:
                        valid = depth[::4, ::4]
                        depths[index] = float(np.median(valid[valid > 0]))
                    with threadpool_limits(1):
                        models.append(prepare(depth, intrinsics, np.random.default_rng([args.seed, int(index)]), None,
                                              options))
                    stats.append(mixture_stats(models[-1], depths[index]))
                fixed, moving = models
                truth = truths[k]
                with threadpool_limits(1):
                    rows["schedule"].append(errors(register(fixed, moving, options), truth))
                    start = Registration(truth[0], truth[1], 0, 0.0, 0.0, True, "truth")
                    rows["truth"].append(errors(measured_cut.register_cut_rounds(
                        fixed, moving, start, schedule.cut_rounds, CUT_TOL, schedule.solver, {"tol": ROUND_TOL}),
                        truth))
                    for name, power in (("pixel", 2.0 if variant == "textbook" and size == "area" else 0.0),
                                        ("area", 0.0 if variant == "textbook" and size == "area" else -2.0)):
                        overlap.register_d2d, measured_cut.register_d2d = (depth_weighted(f, power) for f in plain)
                        try:
                            rows[name].append(errors(register(fixed, moving, options), truth))
                        finally:
                            overlap.register_d2d, measured_cut.register_d2d = plain

            def rms(name):
                e = np.array(rows[name])
                return f"{np.sqrt(np.mean(e[:, 0] ** 2)):.3f}, {100 * np.sqrt(np.mean(e[:, 1] ** 2)):.3f}"

            e = np.array(rows["schedule"])
            s = np.nanmean(np.array(stats), axis=0)
            print(f"| {case} | {fit} | {len(pairs)} | {rms('schedule')}; {np.median(e[:, 0]):.3f}, "
                  f"{100 * np.median(e[:, 1]):.3f} | {rms('truth')} | {rms('pixel')} | {rms('area')} | {s[0]:.1f} | "
                  f"{s[1]:.2f} | {s[2]:.1f}, {s[3]:.1f} | {s[4]:.2f} |", flush=True)


if __name__ == "__main__":
    main()
