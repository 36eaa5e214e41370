"""The report's tables, computed from the sweep's tidy CSVs (rows are dicts of strings, as ``dgmm.runtime.tables``
reads).

- ``likelihood.csv``: model, input, K, init, variant, seed, eval_ll, bound, n_iter, max_iter (one row per fitted seed;
  max_iter the fit's iteration cap: the paper's text's 25, or the authors' stored protocol's 100 for Fig 4);
- ``fig2.csv``: measure, n, draw, bound, expected (Fig 2's likelihood expressions of one fit, and the triangles
  scored with a responsibility per point: :mod:`dgmm.experiments.shared_responsibility`);
- ``registration.csv``: model, mesh, protocol, variant, method, trial, rotation_error_deg, translation_error_pct,
  iterations, ...

Registration methods are named ``{mesh|points}-{kmeans|random}`` (P2D with a GMM fitted to the mesh or to its
vertices), ``icp`` and ``cpd``.
"""
import math
from collections import defaultdict

import numpy as np

from dgmm.errors import DataError
from dgmm.experiments.report import paper
from dgmm.experiments.shared_responsibility import PER_POINT_MEASURE
from dgmm.experiments.sweep import SIZED
from dgmm.experiments.trials import NO_VARIANT, method_variants

FIG2_EXPRESSIONS = ("triangle", "centroid", "area x centroid")
TABLE1_MESH = "quadric1000"  # the mesh of Table 1 (the data stage's quadric decimation), except for ...
TABLE1_MESHES = {"bunny": "res4"}  # ... the bunny: res4, as the authors' gmm_fit_extra.py and registration_test.py
FIG6_MESH = ("bunny", "res4")  # (model, mesh) of Fig 6
TABLE1_INPUTS = {"points": "vertices", "mesh": "exact"}  # representations of Table 1's mesh
TABLE1_FIT = {"K": 100, "init": "kmeans", "variant": "textbook"}
TABLE1_METHODS = {"points": "points-kmeans", "mesh": "mesh-kmeans", "mesh_c2f": "mesh-kmeans-c2f",
                  "reference": "icp"}
TABLE1_C2F_COLUMNS = ("trans_mesh_c2f", "rot_mesh_c2f")
"""Table 1's columns of the coarse-to-fine P2D (dgmm.registration.coarse_to_fine), which the paper does not have."""
ERRORS = {"rot": "rotation_error_deg", "trans": "translation_error_pct"}
TEXT_MAX_ITER = 25
"""The fits' iteration cap in the paper's text (§IV: "We run 25 iterations of EM for all methods"), the report's
view of likelihood.csv."""
STORED_MAX_ITER = 100
"""The cap of the authors' stored Fig 4 data (format_graphs.ipynb: 100 iterations for every point fit), config
experiment fig4_100."""


def likelihood_rows(rows, max_iter=TEXT_MAX_ITER):
    """The rows of ``likelihood.csv`` whose fits were capped at ``max_iter`` EM iterations; a table without the
    max_iter column (before it was added) holds fits at :data:`TEXT_MAX_ITER`."""
    return [row for row in rows if int(row.get("max_iter", TEXT_MAX_ITER)) == max_iter]


def likelihood_means(rows, max_iter=TEXT_MAX_ITER):
    """Mean and standard deviation over seeds of the evaluation log-likelihood of every fit job capped at
    ``max_iter`` iterations.

    Parameters
    ----------
    rows : list of dict
        Rows of ``likelihood.csv``.
    max_iter : int, default=TEXT_MAX_ITER
        The protocol read (:func:`likelihood_rows`): the text's 25 iterations, or e.g. the authors' 100 for Fig 4.

    Returns
    -------
    dict
        ``(model, input, variant, init, K) -> (mean, std)``, std the population standard deviation over seeds.
    """
    groups = defaultdict(list)
    for row in likelihood_rows(rows, max_iter):
        key = (row["model"], row["input"], row["variant"], row["init"], int(row["K"]))
        groups[key].append(float(row["eval_ll"]))
    return {key: (float(np.mean(values)), float(np.std(values))) for key, values in sorted(groups.items())}


def likelihood_curves(means, model, inputs):
    """Fig 3/4 curves: for each (input, variant, init) of ``model`` among ``inputs``, the K values in order.

    Returns
    -------
    dict
        ``(input, variant, init) -> (ks, mean, std)``, three ndarrays of shape (n_k,); inputs in the order given,
        textbook EM before other variants.
    """
    curves = defaultdict(list)
    for (row_model, input_name, variant, init, k), stats in means.items():
        if row_model == model and input_name in inputs:
            curves[input_name, variant, init].append((k, *stats))
    order = sorted(curves, key=lambda key: (inputs.index(key[0]), key[1] != "textbook", key[2]))
    return {key: tuple(np.array(column) for column in zip(*sorted(curves[key]))) for key in order}


def fig2_bars(rows, column):
    """Fig 2's bars for one column (``"expected"``, the paper's quantity, or ``"bound"``, ours).

    Returns
    -------
    bars : list of (label, mean, std)
        The three expressions (std 0), then sampled points per n (mean and std over draws), in file order.
    reference : float
        The value of all the points the mixture was fitted to (the paper's horizontal line).
    """
    draws = defaultdict(list)
    reference = math.nan
    for row in rows:
        if row["measure"] == "all points":
            reference = float(row[column])
        elif row["measure"] != PER_POINT_MEASURE:  # not a bar: the claims read it
            label = row["measure"] if row["measure"] in FIG2_EXPRESSIONS else f"{int(row['n']):,} points"
            draws[label].append(float(row[column]))
    bars = [(label, float(np.mean(values)), float(np.std(values))) for label, values in draws.items()]
    return bars, reference


def registration_settings(rows):
    """The (protocol, variant) settings of ``registration.csv``'s rows, scaled before literal, the authors' EM (the
    report's headline) first; ICP and CPD rows (variant "none") belong to every setting of their protocol."""
    protocols = sorted({row.get("protocol", "scaled") for row in rows}, key=lambda p: p != "scaled")
    variants = sorted({row.get("variant", "textbook") for row in rows} - {NO_VARIANT} or {"textbook"},
                      key=lambda v: (v != "authors", v))
    return [(protocol, variant) for protocol in protocols for variant in variants]


def registration_errors(rows, protocol="scaled", variant="textbook"):
    """Errors of every registration trial run under a trial protocol with mixtures from an EM variant.

    A method's rows are those of the variant it runs under when ``variant`` is asked for
    (``dgmm.experiments.trials.method_variants``: ``variant`` for mesh mixtures, textbook for point mixtures, "none" for
    ICP and CPD). Rows without ``protocol`` or ``variant`` columns count as scaled trials run as under textbook EM.
    Every method of a (model, mesh) has the same trial ids, so that comparisons pair the methods' trials by position
    (sorted by id): a table where they differ is a :class:`~dgmm.errors.DataError` naming the model and methods.

    Returns
    -------
    dict
        ``(model, mesh, method) -> {"rot": ndarray of shape (n_trials,), "trans": ndarray of shape (n_trials,)}``.
    """
    groups = defaultdict(list)
    for row in rows:
        method = row["method"]
        own = method_variants(method, [variant])[0]
        if (row.get("protocol", "scaled") == protocol
                and row.get("variant", method_variants(method, ["textbook"])[0]) == own):
            groups[row["model"], row["mesh"], method].append(row)
    groups = {key: sorted(trials, key=lambda row: int(row["trial"])) for key, trials in groups.items()}
    ids = defaultdict(dict)
    for (model, mesh, method), trials in groups.items():
        ids[model, mesh][method] = tuple(int(row["trial"]) for row in trials)
    for (model, mesh), by_method in ids.items():
        if len(set(by_method.values())) > 1:
            raise DataError(f"registration.csv: {model} {mesh}: methods {', '.join(sorted(by_method))} ran different "
                            f"trials ({', '.join(f'{m} {len(t)}' for m, t in sorted(by_method.items()))}); their "
                            f"trials cannot be paired")
    return {key: {name: np.array([float(row[column]) for row in trials]) for name, column in ERRORS.items()}
            for key, trials in groups.items()}


def table1_errors(errors, trials):
    """``errors`` (:func:`registration_errors`) with the trials of each model's Table 1 mesh cut to its first
    ``trials`` (by trial id): §VI-C's "average of 25 runs", as the authors' stored Table 1 (for the bunny, the first 25
    of Fig 6's 250 on the same mesh). ``trials`` None keeps every trial."""
    if errors is None or trials is None:
        return errors
    return {key: {name: values[:trials] for name, values in errors_of.items()} if key[1] == table1_mesh(key[0])
            else errors_of for key, errors_of in errors.items()}


def table1_mesh(model):
    """The data-stage mesh of ``model``'s Table 1 row."""
    return TABLE1_MESHES.get(model, TABLE1_MESH)


def _percent_of_reference(errors, model, method, name):
    """Mean error of ``method`` on Table 1's mesh as % of the reference method's (ICP); nan when either is missing."""
    measured = errors.get((model, table1_mesh(model), method))
    reference = errors.get((model, table1_mesh(model), TABLE1_METHODS["reference"]))
    if measured is None or reference is None:
        return math.nan
    return 100.0 * float(np.mean(measured[name])) / float(np.mean(reference[name]))


def table1(means, errors=None, variant="textbook", protocol="scaled"):
    """Table 1 for the paper's five models: ours beside the paper's, nan where we have no measurement.

    Parameters
    ----------
    means : dict
        From :func:`likelihood_means`.
    errors : dict, optional
        From :func:`registration_errors` (of ``protocol`` and ``variant``); None while the registration stage is
        pending.
    variant : str, default="textbook"
        EM variant of the mesh fits (points fits are textbook EM whatever the variant).
    protocol : str, default="scaled"
        Trial protocol of the errors, recorded in the rows.

    Returns
    -------
    list of dict
        One per model: ``model``, ``mesh`` (its Table 1 mesh, :func:`table1_mesh`), ``variant``, ``protocol``,
        for each column of
        ``paper.TABLE1_COLUMNS`` ours and ``{column}_paper``, then ours of ``TABLE1_C2F_COLUMNS``.
        Likelihoods are mean eval log-likelihoods (nats); errors are % of ICP's mean error.
    """
    fit = {**TABLE1_FIT, "variant": variant}
    rows = []
    for model, published in paper.TABLE1.items():
        mesh = table1_mesh(model)
        ours = {f"ll_{kind}": means.get((model, f"{mesh}-{representation}",
                                         fit["variant"] if representation in SIZED else "textbook", fit["init"],
                                         fit["K"]), (math.nan,))[0]
                for kind, representation in TABLE1_INPUTS.items()}
        for name in ERRORS:
            for kind in ("points", "mesh", "mesh_c2f"):
                ours[f"{name}_{kind}"] = _percent_of_reference(errors or {}, model, TABLE1_METHODS[kind], name)
        row = {"model": model, "mesh": mesh, "variant": variant, "protocol": protocol}
        for column, value in zip(paper.TABLE1_COLUMNS, published):
            row[column], row[f"{column}_paper"] = ours[column], value
        row.update({column: ours[column] for column in TABLE1_C2F_COLUMNS})
        rows.append(row)
    return rows


def table1_columns():
    """Column order of ``table1.csv``: model, mesh, EM variant, trial protocol, each measure as ours and the
    paper's, then the coarse-to-fine P2D's errors (ours only)."""
    return ["model", "mesh", "variant", "protocol",
            *(name for column in paper.TABLE1_COLUMNS for name in (column, f"{column}_paper")), *TABLE1_C2F_COLUMNS]


def format_number(value, digits=2):
    """A table cell: fixed digits, an en dash for a missing (nan) value."""
    return "–" if math.isnan(value) else f"{value:.{digits}f}"
