"""A frame's mixture fitted as scikit-learn's ``GaussianMixture`` fits at its defaults: the authors' odometry fit.

The authors' notebooks (leonidk/direct_gmm, ``gen_gmm.ipynb`` and its ``-mine`` copies) fit every frame with
``GaussianMixture(100)`` at scikit-learn's defaults (their modified copy for the pixel primitives): the start is one
run of scikit-learn's k-means (k-means++ seeds, Lloyd to its own convergence) and its hard labels' M-step; EM runs up
to ``max_iter = 100`` iterations and stops once the bound changes by less than ``tol = 1e-3``; ``reg_covar = 1e-6``.

dgmm's :class:`~dgmm.mixture.GaussianMixture` starts the same way (``init="kmeans"``) and runs the same EM, but the
two stop one M-step apart: scikit-learn's bound at iteration ``n`` is the one its E-step computes before the
``n``-th M-step (that of the parameters after ``n - 1`` of them), dgmm's the one after it. Where dgmm stops after
``n`` M-steps (its bound moved less than ``tol``), scikit-learn sees that change only at iteration ``n + 1`` and stops
after one more M-step; :func:`fit_sklearn_defaults` takes that M-step, so that both return the same parameters.
"""
from __future__ import annotations

import numpy as np

from dgmm.mixture import GaussianMixture

SKLEARN_MAX_ITER = 100
"""scikit-learn's default ``max_iter``."""

SKLEARN_TOL = 1e-3
"""scikit-learn's default ``tol``: EM stops once its bound (mean log-likelihood) changes by less."""


def fit_sklearn_defaults(prims, n_components, rng, *, max_iter=SKLEARN_MAX_ITER, tol=SKLEARN_TOL, **options):
    """The mixture of ``prims`` as ``sklearn.mixture.GaussianMixture(n_components).fit`` finds it on points.

    Parameters
    ----------
    prims : Primitives
    n_components : int
    rng : numpy.random.Generator
        Seeds the k-means start (the seed scikit-learn's k-means gets is drawn from it).
    max_iter : int, default=100
    tol : float, default=1e-3
        scikit-learn's stopping rule, on dgmm's bound (for points, scikit-learn's mean log-likelihood).
    **options
        Other parameters of :class:`dgmm.mixture.GaussianMixture` (``variant``, ``reg_covar``, ``screen``, ...).

    Returns
    -------
    GaussianMixture
        Fitted; ``n_iter_`` counts the M-steps as scikit-learn does, the last one included.
    """
    mixture = GaussianMixture(n_components, init="kmeans", max_iter=max_iter, tol=tol, random_state=rng,
                              **options).fit(prims)
    if not mixture.converged_ or mixture.n_iter_ >= max_iter:
        return mixture
    last = GaussianMixture(n_components, max_iter=1, tol=None, weights_init=mixture.weights_,
                           means_init=mixture.means_, precisions_init=np.linalg.inv(mixture.covariances_),
                           random_state=rng, **options).fit(prims)
    last.n_iter_, last.converged_ = mixture.n_iter_ + 1, True
    return last
