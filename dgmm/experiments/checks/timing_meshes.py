"""Timing checks of what the fitting sweep does to a mesh: reduce it to a budget, and fit it.

- ``approximation`` (Conclusion: eq. 5 is "a fast approximation to our proposed method"): k-means-started EM on a
  mesh's exact triangles (``exact``), on their area × centroid approximation (``approx``) and on the centroids as
  points (``centroids``);
- ``decimation`` (§IV-B: "clustering decimation, which is fast, and quadric error decimation, which is more
  accurate"): the data stage's clustering and quadric decimations of a mesh to a face budget;
- ``sampling`` (§IV-B, random sampling "is faster" than Poisson-disk sampling): the data stage's ``random`` and
  ``poisson`` samplings of a mesh to a point budget.

The reductions are the data stage's own (:data:`dgmm.meshes.REDUCTIONS`, budget searches included); pymeshlab's
samplers draw from a generator seeded when the process starts, so their samples, unlike the seconds, repeat from run
to run only in a fresh process.
"""
from dgmm.experiments.checks.interleaved import interleaved_times
from dgmm.experiments.sweep import job_seed
from dgmm.meshes import REDUCTIONS
from dgmm.mixture import GaussianMixture
from dgmm.primitives import Primitives

EM_INPUTS = {
    "exact": lambda prims: prims,
    "approx": lambda prims: prims.without_covariances(),
    "centroids": lambda prims: Primitives.from_points(prims.means),
}
"""The ``approximation`` check's settings: the fitted form of a mesh's triangles."""


def approximation_times(mesh, *, repeats, n_components, max_iter, root_seed):
    """CPU seconds of ``repeats`` k-means-started fits (``max_iter`` iterations) of each :data:`EM_INPUTS` form.

    Parameters
    ----------
    mesh : tuple of ndarray
        ``(vertices, faces)``.
    repeats, n_components, max_iter, root_seed : int

    Returns
    -------
    list of dict
        Rows of :data:`dgmm.experiments.checks.interleaved.COLUMNS`, ``iterations`` the fit's, no ``detail``.
    """
    prims = Primitives.from_mesh(*mesh)
    forms = {name: form(prims) for name, form in EM_INPUTS.items()}
    seed = job_seed(root_seed, "checks/timing/approximation", 0)
    settings = {name: (lambda case, data=data: GaussianMixture(n_components, max_iter=max_iter,
                                                               random_state=seed).fit(data))
                for name, data in forms.items()}
    return interleaved_times("approximation", range(repeats), settings, lambda case, name, fitted: (fitted.n_iter_, ""))


def _reduction_times(check, methods, mesh, repeats, budget):
    """``repeats`` interleaved reductions of ``mesh`` to ``budget`` by each of the data stage's ``methods``."""
    vertices, faces = mesh
    settings = {method: (lambda case, method=method: REDUCTIONS[method](vertices, faces, budget)) for method in methods}

    def describe(case, method, reduced):
        points, triangles = reduced
        return "", f"{len(points)} points" if triangles is None else f"{len(triangles)} faces"
    return interleaved_times(check, range(repeats), settings, describe)


def decimation_times(mesh, *, repeats, budget):
    """CPU seconds of ``repeats`` clustering and quadric decimations of ``mesh`` (vertices, faces) to ``budget``
    faces; ``detail`` the faces reached."""
    return _reduction_times("decimation", ("clustering", "quadric"), mesh, repeats, budget)


def sampling_times(mesh, *, repeats, budget):
    """CPU seconds of ``repeats`` random and Poisson-disk samplings of ``mesh`` (vertices, faces) to ``budget``
    points; ``detail`` the points drawn."""
    return _reduction_times("sampling", ("random", "poisson"), mesh, repeats, budget)
