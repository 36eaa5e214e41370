"""The authors' ICP against ours on the sweep's registration trials: errors, iterations, CPU time, Table 1's % of ICP.

Our ICP (:func:`dgmm.registration.register_icp`) and the authors' (:func:`register_icp_authors`, the loop of
``registration_test.py`` in leonidk/direct_gmm) differ in two details (docs/user_guide/registration.md): the step
(ours: one weighted Kabsch step on the pooled forward and backward pairs; theirs: the two cross-covariances each
centred on its own means and summed, the backward one scaled by the point counts, and the two translations averaged)
and the stop (ours: the mean matching distance changes by less than 1e-9; theirs: the norm of the change of the
per-point forward residual vector is below 1e-9). Both run on the sweep's own trials, built as
``workflow/scripts/registration_chunk.py`` builds them (:func:`dgmm.experiments.trials.make_trials`, the config's
root seed and trial settings, the scaled protocol): bunny res4 (Fig 6, and the bunny's Table 1 row) and the four
other Table 1 models' quadric1000 meshes, from the data stage's files.

Per model it prints mean and median rotation error (°) and translation error (% of the diagonal,
:func:`dgmm.registration.registration_errors`), mean iterations and CPU seconds per trial, for both ICPs, and the
paired difference of the means (theirs − ours) with its paired-bootstrap standard error
(:func:`dgmm.experiments.report.claims.grading.paired_difference`); beside them, the authors' ICP's errors as their
script books its pose (:func:`their_bookkeeping`: the steps' rotations multiplied in the reverse order). Then
Table 1's registration columns, the mesh and points GMMs' mean errors as % of ICP's, with each ICP (and theirs as
booked) as the denominator, beside the paper's
(:data:`dgmm.experiments.report.paper.TABLE1`): P2D (BFGS, the config's gradient) on the workflow's mixtures (K=100,
k-means, the scaled covariance floor, the workflow's seeds), ``mesh-kmeans`` under each EM of
``registration.variants``, ``points-kmeans`` under textbook EM. Measured: docs/user_guide/registration.md, "The
authors' ICP".

Run, from the repository's root, after the data stage's files::

    snakemake --cores 1 results/data/bunny/res4_eval.ply \\
        results/data/{armadillo,dragon,happy,lucy}/{quadric1000,full_eval}.ply
    python benchmarks/studies/icp_authors.py [--trials 250] [--table1-trials 25] [--models bunny armadillo ...]

(about 70 s of one thread on a loaded 2-core machine, most of it the bunny's P2D).
"""
import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import yaml  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from dgmm.data import load_mesh, load_points  # noqa: E402
from dgmm.experiments.report import paper  # noqa: E402
from dgmm.experiments.report.claims.grading import paired_difference  # noqa: E402
from dgmm.experiments.sweep import job_seed  # noqa: E402
from dgmm.experiments.trials import (bounding_diagonal, fit_mixture, make_trials, protocol_reg_covar,  # noqa: E402
                                     run_trials)
from dgmm.registration import Registration, register_icp, registration_errors  # noqa: E402
from dgmm.registration.checks import as_points  # noqa: E402
from dgmm.registration.rotations import rotation_distance_deg  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
MESHES = {"bunny": ("res4", "res4_eval"), **{model: ("quadric1000", "full_eval")
                                             for model in ("armadillo", "dragon", "happy", "lucy")}}
"""model -> (registered mesh, its dense sample): config.yaml's fig6 and table1 experiments, and the sample
``workflow/rules/common.smk``'s ``dense_sample`` gives them."""
PROTOCOL = "scaled"


def register_icp_authors(source, target, max_iter=50_000, tol=1e-9, callback=None):
    """Point-to-point ICP both ways as the authors' ``registration_test.py`` (leonidk/direct_gmm) runs it.

    Follows their loop (``flag = True``): per iteration, every moved source point's nearest target point (forward)
    and every target point's nearest moved source point (backward); the translation is the mean of the forward one
    (moved mean − matched mean) and the backward one (matched moved mean − target mean); the rotation is the Kabsch
    rotation of the sum of the forward cross-covariance, centred on the moved and the matched means, and the
    backward one, centred on the matched-moved and the target means and scaled by ``n_source / n_target``. The step
    rotates the moved points about their mean and shifts them by minus the translation. It stops, after the step,
    when ``|e_k - e_{k-1}|`` < ``tol``, ``e_k`` the vector of the distances of each moved point to the target point
    it was matched to before the step. Their ``cdist`` + ``argmin`` neighbours are exact k-d tree queries here.

    The pose returned is that of the final moved points: the composition of every step taken, the last one too.
    Their script's bookkeeping differs (it keeps ``R @ rotmat``, the steps' rotations in the reverse order, and leaves
    the last step out); ``callback`` receives each step, so that :func:`their_bookkeeping` can rebuild it.

    Parameters
    ----------
    source : array-like of shape (n_source, 3)
        Points moved onto the target.
    target : array-like of shape (n_target, 3)
    max_iter : int, default=50000
        Their ``ICP_ITERS``.
    tol : float, default=1e-9
        Their ``ICP_THRESH``.
    callback : callable, optional
        ``callback(iteration, step, shift)`` after every step: the step's rotation about the moved points' mean and
        the translation subtracted (their ``rotmat`` and ``it``).

    Returns
    -------
    Registration
        ``iterations`` is the number of steps taken, ``objective`` the last mean forward residual.
    """
    source, target = as_points("source", source), as_points("target", target)
    start = time.perf_counter()
    source_tree, target_tree = cKDTree(source), cKDTree(target)
    back_scale = len(source) / len(target)
    target_mean = target.mean(axis=0)
    target_centred = target - target_mean
    rotation, translation = np.eye(3), np.zeros(3)
    moved = source.copy()
    previous = None
    converged = False
    for iteration in range(1, int(max_iter) + 1):
        matched = target[target_tree.query(moved)[1]]
        # The moved point nearest to target point p is the source point nearest to Rᵀ(p − t).
        matched_back = moved[source_tree.query((target - translation) @ rotation)[1]]
        moved_mean, matched_mean, back_mean = moved.mean(axis=0), matched.mean(axis=0), matched_back.mean(axis=0)
        shift = 0.5 * (moved_mean - matched_mean) + 0.5 * (back_mean - target_mean)
        cross = (moved - moved_mean).T @ (matched - matched_mean)
        cross += back_scale * (matched_back - back_mean).T @ target_centred
        u, _, vt = np.linalg.svd(cross)
        step = vt.T @ np.diag([1.0, 1.0, np.linalg.det(vt.T @ u.T)]) @ u.T
        moved = (moved - moved_mean) @ step.T + moved_mean - shift
        # x -> step (x - m) + m - shift, composed after the pose so far
        rotation, translation = step @ rotation, step @ translation + moved_mean - step @ moved_mean - shift
        if callback is not None:
            callback(iteration, step, shift)
        residual = np.linalg.norm(moved - matched, axis=1)
        if previous is not None and np.linalg.norm(residual - previous) < tol:
            converged = True
            break
        previous = residual
    return Registration(rotation, translation, iteration, time.perf_counter() - start, float(residual.mean()),
                        converged, "icp")


ICPS = {"ours": register_icp, "theirs": register_icp_authors}


def their_bookkeeping(steps, trial, diagonal):
    """The errors registration_test.py reports for its ICP, from the ``(step, shift)`` of every step taken.

    Their script keeps ``R = R @ rotmat`` and ``icp_t += it`` after the stopping test, so the last step is left out
    and the rotations are multiplied in the reverse order; it reports the quaternion dot product with the true
    rotation's and ``|icp_t - t|``. Read as :func:`dgmm.registration.registration_errors` reads a pose: the rotation
    angle of the residual and how far the source centroid ends from where it started (every step turns the points
    about their mean, so the centroid moves by ``-it`` each step), in % of ``diagonal``.
    """
    rotation, shift = np.eye(3), np.zeros(3)
    for step, it in steps[:-1]:
        rotation, shift = rotation @ step, shift + it
    return (rotation_distance_deg(rotation.T, trial.rotation),
            float(100.0 * np.linalg.norm(trial.translation - shift) / diagonal))


def load_experiment(model, config, n_trials):
    """``(vertices, faces, diagonal, setups)`` of ``model``'s first ``n_trials`` trials, as the sweep builds them."""
    registration = config["registration"]
    mesh, dense = MESHES[model]
    data = ROOT / config["results"] / "data" / model
    vertices, faces = load_mesh(data / f"{mesh}.ply")
    diagonal = bounding_diagonal(vertices)
    setups = make_trials(load_points(data / f"{dense}.ply"), len(vertices), range(n_trials),
                         root_seed=config["seed"], key=f"registration/{model}/{mesh}", diagonal=diagonal,
                         max_angle_deg=registration["max_angle_deg"],
                         max_translation=registration["max_translation"], protocol=PROTOCOL)
    return vertices, faces, diagonal, setups


def run_icps(setups, diagonal, options):
    """``name -> {"rot", "trans", "iterations", "converged", "cpu"}`` arrays over the trials, for both ICPs, and
    ``"booked" -> {"rot", "trans"}``: the authors' ICP's errors as their script books them (:func:`their_bookkeeping`,
    from a second, untimed run)."""
    result = {}
    for name, register in ICPS.items():
        rows = []
        for setup in setups:
            start = time.process_time()
            registration = register(setup.moved, setup.target, **options)
            cpu = time.process_time() - start
            rows.append((*registration_errors(registration, setup.trial, diagonal), registration.iterations,
                         registration.converged, cpu))
        result[name] = dict(zip(("rot", "trans", "iterations", "converged", "cpu"), map(np.array, zip(*rows))))
    booked = []
    for setup in setups:
        steps = []
        register_icp_authors(setup.moved, setup.target, **options,
                             callback=lambda iteration, step, shift: steps.append((step, shift)))
        booked.append(their_bookkeeping(steps, setup.trial, diagonal))
    result["booked"] = dict(zip(("rot", "trans"), map(np.array, zip(*booked))))
    return result


def run_p2d(model, vertices, faces, diagonal, setups, config):
    """``(kind, variant) -> {"rot", "trans"}`` of P2D on Table 1's mixtures (the workflow's fits and seeds)."""
    registration = config["registration"]
    mesh = MESHES[model][0]
    settings = {key: registration[key] for key in ("max_iter", "tol")}
    settings["reg_covar"] = protocol_reg_covar(registration["reg_covar"], diagonal, PROTOCOL)
    runs = [("mesh", "mesh-kmeans", variant) for variant in registration["variants"]]
    runs.append(("points", "points-kmeans", "textbook"))
    result = {}
    for kind, method, variant in runs:
        mixture = fit_mixture(method, vertices, faces, n_components=registration["components"], variant=variant,
                              seed=job_seed(config["seed"], f"registration/{model}/{mesh}/{method}", 0), **settings)
        rows, _ = run_trials(method, setups, diagonal, mixture=mixture,
                             options={"p2d": {"gradient": registration["gradient"]}})
        result[kind, variant] = {"rot": np.array([r["rotation_error_deg"] for r in rows]),
                                 "trans": np.array([r["translation_error_pct"] for r in rows])}
    return result


def icp_table(icps, model):
    """Markdown rows of one model's ICP comparison."""
    ours, theirs, booked = icps["ours"], icps["theirs"], icps["booked"]
    lines = []
    for name, unit in (("rot", "°"), ("trans", "%")):
        diff, booked_diff = paired_difference(theirs[name], ours[name]), paired_difference(booked[name], ours[name])
        lines.append(f"| {model} | {'rotation' if name == 'rot' else 'translation'} ({unit}) | "
                     f"{ours[name].mean():.4g} / {np.median(ours[name]):.4g} | "
                     f"{theirs[name].mean():.4g} / {np.median(theirs[name]):.4g} | "
                     f"{diff.value:+.3g} ± {diff.error:.2g} | "
                     f"{booked[name].mean():.4g} / {np.median(booked[name]):.4g} | "
                     f"{booked_diff.value:+.3g} ± {booked_diff.error:.2g} |")
    diff = paired_difference(theirs["cpu"], ours["cpu"])
    lines.append(f"| {model} | iterations; CPU s per trial | "
                 f"{ours['iterations'].mean():.1f}; {ours['cpu'].mean():.4f} | "
                 f"{theirs['iterations'].mean():.1f}; {theirs['cpu'].mean():.4f} | "
                 f"CPU {diff.value:+.3g} ± {diff.error:.2g} s; not converged {int((~ours['converged']).sum())} / "
                 f"{int((~theirs['converged']).sum())} | | |")
    return lines


def percent_rows(model, icps, p2d, variants):
    """Markdown rows of Table 1's % of ICP, with each ICP as the denominator, beside the paper's."""
    published = dict(zip(paper.TABLE1_COLUMNS, paper.TABLE1[model]))
    lines = []
    for variant in variants:
        cells = []
        for name in ("rot", "trans"):
            for kind in ("mesh", "points"):
                errors = p2d[kind, "textbook" if kind == "points" else variant][name]
                ours, theirs, booked = (100 * errors.mean() / icps[icp][name].mean()
                                        for icp in ("ours", "theirs", "booked"))
                cells.append(f"{ours:.0f} / {theirs:.0f} / {booked:.0f} / {published[f'{name}_{kind}']:.0f}")
        lines.append(f"| {model} | {variant} | " + " | ".join(cells) + " |")
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=250, help="bunny res4 trials (Fig 6: 250)")
    parser.add_argument("--table1-trials", type=int, default=25, help="trials of the other Table 1 models")
    parser.add_argument("--models", nargs="+", default=list(MESHES), choices=list(MESHES))
    args = parser.parse_args()
    config = yaml.safe_load((ROOT / "config.yaml").read_text())
    options = config["registration"]["icp"]
    icp_lines, percent_lines = [], []
    with threadpool_limits(1):
        for model in args.models:
            n_trials = args.trials if model == "bunny" else args.table1_trials
            start = time.perf_counter()
            vertices, faces, diagonal, setups = load_experiment(model, config, n_trials)
            icps = run_icps(setups, diagonal, options)
            p2d = run_p2d(model, vertices, faces, diagonal, setups, config)
            icp_lines += icp_table(icps, f"{model} ({n_trials})")
            percent_lines += percent_rows(model, icps, p2d, config["registration"]["variants"])
            print(f"{model}: {time.perf_counter() - start:.0f} s", flush=True)
    print("\n| model (trials) | measure | ours: mean / median | theirs: mean / median | theirs − ours (mean) "
          "| theirs, booked as their script: mean / median | booked − ours (mean) |")
    print("|---|---|---|---|---|---|---|")
    print("\n".join(icp_lines))
    print("\n% of ICP's mean error, mesh GMM and points GMM: with our ICP / with theirs / with theirs as booked by "
          "their script / the paper's")
    print("\n| model | mesh EM | rotation, mesh | rotation, points | translation, mesh | translation, points |")
    print("|---|---|---|---|---|---|")
    print("\n".join(percent_lines))
    rotation, translation = paper.FIG6_MEANS["icp"]
    print(f"\nThe paper's Fig 6 ICP means (bunny, 250 trials): rotation {rotation}°, translation {translation}%")


if __name__ == "__main__":
    main()
