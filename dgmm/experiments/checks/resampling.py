"""The same surface as fewer, larger or more, smaller triangles (paper §II: the product integral "is invariant to
resampling": "one large primitive ... gives the same answer as many small disjoint pieces of surface").

Every triangle of a mesh is split in four at its edge midpoints (:func:`trimesh.remesh.subdivide`), which leaves
the surface unchanged. Three numbers compare the two meshes:

- ``component_gap``: the largest change, over a fitted mixture's components, of the area-weighted mean of
  ``E_p[log N_i]`` (eq. 11's per-component integral): the product integral of one Gaussian, additive over pieces;
- ``bound_gap``: the change of the EM bound (eq. 11 with one responsibility per triangle) of that mixture, which
  the split tightens;
- ``eval_gap``: the change of the evaluation log-likelihood of mixtures fitted to each mesh (same seeds);
- ``shared_gap``: the same change when the split mesh is fitted with one responsibility per original triangle
  (:func:`merged`), the switch that tells whether the pieces' own responsibilities are what moves the refit.
"""
import numpy as np
import trimesh

from dgmm.experiments.sweep import job_seed
from dgmm.mixture import GaussianMixture
from dgmm.primitives import Primitives

COLUMNS = ("variant", "seed", "eval_ll", "eval_ll_split", "eval_gap", "bound", "bound_split", "bound_gap",
           "component_gap", "eval_ll_shared", "shared_gap")


def split_in_four(vertices, faces):
    """The mesh with every triangle split in four at its edge midpoints: (vertices, faces)."""
    return trimesh.remesh.subdivide(np.asarray(vertices, dtype=np.float64), np.asarray(faces))


def pieces_by_triangle(vertices, faces):
    """The split mesh's triangles as primitives and, for each, the index of the original triangle it came from.

    Returns
    -------
    pieces : Primitives
        :func:`split_in_four`'s triangles of positive area.
    parents : ndarray of shape (len(pieces),)
    """
    split_vertices, split_faces, index = trimesh.remesh.subdivide(
        np.asarray(vertices, dtype=np.float64), np.asarray(faces), return_index=True)
    parents = np.empty(len(split_faces), dtype=np.intp)
    for parent, children in index.items():
        parents[children] = parent
    positive = trimesh.triangles.area(split_vertices[split_faces]) > 0
    return Primitives.from_mesh(split_vertices, split_faces[positive]), parents[positive]


def merged(pieces, parents):
    """One primitive per parent with the moments of its pieces together (sizes added, area-weighted mean and second
    moment).

    EM on the merged primitives is EM on the pieces with one responsibility shared by each parent's pieces: the
    expected log-density of eq. 8 and the M-step's sums are linear in a primitive's size-weighted moments, so a
    group's shared terms are its merged primitive's.
    """
    groups, labels = np.unique(parents, return_inverse=True)
    sizes = np.bincount(labels, weights=pieces.weights, minlength=len(groups))
    means = np.zeros((len(groups), pieces.dimension))
    np.add.at(means, labels, pieces.weights[:, None] * pieces.means)
    means /= sizes[:, None]
    second = np.zeros((len(groups), pieces.dimension, pieces.dimension))
    np.add.at(second, labels, pieces.weights[:, None, None] * pieces.second_moments)
    second /= sizes[:, None, None]
    return Primitives(means, second - means[:, :, None] * means[:, None, :], sizes)


def component_integrals(mixture, prims):
    """Area-weighted mean over primitives of ``E_p[log N(x; mu_i, Sigma_i)]`` for every component, shape (K,).

    ``E_p[log N_i] = log N(mu_p; mu_i, Sigma_i) - tr(Sigma_i^-1 Sigma_p) / 2`` (eq. 11's bracket without the
    weight), computed here from the covariances, independently of the EM code.
    """
    precisions = np.linalg.inv(mixture.covariances_)
    _, log_det = np.linalg.slogdet(mixture.covariances_)
    offsets = prims.means[:, None, :] - mixture.means_[None]  # (P, K, 3)
    mahalanobis = np.einsum("pkd,kde,pke->pk", offsets, precisions, offsets)
    trace = np.einsum("kde,ped->pk", precisions, prims.covariances)
    terms = -0.5 * (3 * np.log(2 * np.pi) + log_det[None] + mahalanobis + trace)
    return np.average(terms, axis=0, weights=prims.weights)


def resampling_rows(vertices, faces, evaluation, *, variants, seeds, root_seed, n_components, max_iter, tol,
                    reg_covar, key):
    """Fit the mesh and its split copy with every variant and seed and compare them (module docstring).

    Returns
    -------
    list of dict
        One per (variant, seed), with the keys of :data:`COLUMNS`.
    """
    mesh = Primitives.from_mesh(vertices, faces)
    split, parents = pieces_by_triangle(vertices, faces)
    shared = merged(split, parents)
    rows = []
    for variant in variants:
        for index in range(seeds):
            seed = job_seed(root_seed, f"{key}/{variant}", index)
            fits = [GaussianMixture(n_components, init="kmeans", max_iter=max_iter, tol=tol, reg_covar=reg_covar,
                                    variant=variant, random_state=seed).fit(prims) for prims in (mesh, split, shared)]
            scores = [fit.score(evaluation) for fit in fits]
            bounds = [fits[0].score_primitives(prims) for prims in (mesh, split)]
            components = [component_integrals(fits[0], prims) for prims in (mesh, split)]
            rows.append({"variant": variant, "seed": index, "eval_ll": scores[0], "eval_ll_split": scores[1],
                         "eval_gap": scores[1] - scores[0], "bound": bounds[0], "bound_split": bounds[1],
                         "bound_gap": bounds[1] - bounds[0],
                         "component_gap": float(np.max(np.abs(components[1] - components[0]))),
                         "eval_ll_shared": scores[2], "shared_gap": scores[2] - scores[0]})
    return rows
