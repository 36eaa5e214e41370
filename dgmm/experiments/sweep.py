"""The paper's fitting experiments as plain functions: build an input, fit it over seeds, score it.

An *input* is named ``{source}-{representation}``: ``source`` is a file of the data stage (``res4``,
``full``, ``quadric1000``, ``poisson1000``, ...) and ``representation`` says how EM sees it (paper §IV):

* ``exact``     the mesh's triangles with their covariances and areas (eqs. 12, 13);
* ``approx``    the same triangles without covariances: area-weighted centroids (eq. 5);
* ``centroids`` the triangle centroids as plain points;
* ``vertices``  the mesh's vertices as plain points;
* ``points``    a point set as it is (Poisson-disk or random samples).
"""
from __future__ import annotations

import time
import zlib

import numpy as np

from dgmm.errors import InputError
from dgmm.mixture import VARIANTS, GaussianMixture
from dgmm.primitives import Primitives

REPRESENTATIONS = {
    "exact": lambda vertices, faces: Primitives.from_mesh(vertices, faces),
    "approx": lambda vertices, faces: Primitives.from_mesh(vertices, faces).without_covariances(),
    "centroids": lambda vertices, faces: Primitives.from_points(Primitives.from_mesh(vertices, faces).means),
    "vertices": lambda vertices, faces: Primitives.from_points(vertices),
    "points": lambda vertices, faces: Primitives.from_points(vertices),
}
SIZED = ("exact", "approx")  # representations whose primitives have sizes, where the EM variants differ
COLUMNS = ("model", "input", "K", "init", "variant", "seed", "eval_ll", "bound", "n_iter", "max_iter")
"""likelihood.csv's columns: a fit job's scores.csv has all but ``max_iter``, its iteration cap, which the table job
appends (fit.max_iter, or the experiment's own: the same fit capped at 25 and at 100 is two rows)."""


def parse_input(name):
    """Split ``{source}-{representation}`` into its two parts, checking the representation."""
    source, _, representation = name.rpartition("-")
    if not source or representation not in REPRESENTATIONS:
        raise InputError(f"input {name!r}: expected SOURCE-REPRESENTATION with a representation in "
                         f"{tuple(REPRESENTATIONS)}")
    return source, representation


def variants_for(input_name, variants):
    """The EM variants worth running on an input: all for sized primitives, only "textbook" for points
    (where every variant is the same algorithm)."""
    return list(variants) if parse_input(input_name)[1] in SIZED else ["textbook"]


def build_input(input_name, vertices, faces=None):
    """The primitives EM fits for ``input_name`` from a data-stage file's vertices (and faces)."""
    representation = parse_input(input_name)[1]
    if faces is None and representation not in ("vertices", "points"):
        raise InputError(f"input {input_name!r} needs a mesh, but its file holds only points")
    return REPRESENTATIONS[representation](vertices, faces)


def job_seed(root_seed, key, index):
    """Integer seed of fit ``index`` of the job ``key``: a SeedSequence of the root seed, a stable hash of the
    job's wildcards and the index, so that every job and seed draws independent, reproducible numbers."""
    entropy = [int(root_seed), zlib.crc32(key.encode()), int(index)]
    return int(np.random.SeedSequence(entropy).generate_state(1)[0])


def fit_seeds(prims, evaluation, *, n_components, init, variant, n_seeds, root_seed, key, max_iter, tol,
              reg_covar, recorder=None):
    """Fit ``n_seeds`` mixtures to ``prims`` and score each on the evaluation points.

    Parameters
    ----------
    prims : Primitives
    evaluation : ndarray of shape (n_points, 3)
    recorder : dgmm.recording.FitRecorder, optional
        Receives every EM iteration (``begin_seed``/``callback``/``end_seed``).

    Returns
    -------
    rows : list of dict
        One per seed: ``seed``, ``eval_ll`` (mean log-likelihood of the evaluation points), ``bound`` (final EM
        bound on the input), ``n_iter``.
    seconds : list of float
        Wall time of each fit (logging included).
    """
    if variant not in VARIANTS:
        raise InputError(f"variant {variant!r}: must be one of {tuple(VARIANTS)}")
    evaluation = Primitives.from_points(evaluation)  # checked and laid out once for the seeds' scores
    rows, seconds = [], []
    for index in range(n_seeds):
        model = GaussianMixture(n_components, init=init, max_iter=max_iter, tol=tol, reg_covar=reg_covar,
                                variant=variant, random_state=job_seed(root_seed, key, index), callback=recorder)
        if recorder is not None:
            recorder.begin_seed(index)
        start = time.perf_counter()
        model.fit(prims)
        seconds.append(time.perf_counter() - start)
        if recorder is not None:
            recorder.end_seed(model)
        rows.append({"seed": index, "eval_ll": model.score(evaluation), "bound": model.lower_bound_,
                     "n_iter": model.n_iter_})
    return rows, seconds


def representation_likelihoods(model, mesh_vertices, mesh_faces):
    """Fig 2's likelihood expressions of a fitted mixture on a mesh, in two forms each.

    ``bound`` is the size-weighted mean of ``logsumexp_i(log lambda_i + E_p[log N_i])`` (our EM bound, the
    mean log-likelihood for points). ``expected`` is the paper's plotted quantity (its Fig 2 caption: "the sum
    of individual Gaussian component log-likelihoods"), ``Σ_i eta_ip (log lambda_i + E_p[log N_i])`` averaged
    the same way: the bound without the responsibilities' entropy.

    Returns
    -------
    dict mapping "triangle", "centroid", "area x centroid" to (bound, expected).
    """
    triangles = Primitives.from_mesh(mesh_vertices, mesh_faces)
    inputs = {"triangle": triangles, "centroid": Primitives.from_points(triangles.means),
              "area x centroid": triangles.without_covariances()}
    return {name: (model.score_primitives(prims), expected_log_likelihood(model, prims))
            for name, prims in inputs.items()}


def expected_log_likelihood(model, prims):
    """Size-weighted mean over primitives of ``Σ_i eta_ip log rho_ip`` = bound − entropy of ``eta_p``."""
    eta = model.predict_proba(prims)  # never exactly 0: log-responsibilities are floored (mixture._LOG_FLOOR)
    entropy = -(eta * np.log(eta)).sum(axis=1)
    return float(np.average(model.primitive_bounds(prims) - entropy, weights=prims.weights))
