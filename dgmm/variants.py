"""The EM variants and initialisations of :class:`dgmm.mixture.GaussianMixture`, by name.

A module of its own that imports nothing at load, so that the command line offers the names at once.
"""


def _textbook(sizes):
    """Textbook EM: the E-step is unscaled and sizes weight the M-step (rescaled to mean 1, so that masses
    count primitives whatever the units, as scikit-learn's ``10 eps`` on masses assumes)."""
    import numpy as np

    return np.ones_like(sizes), sizes / sizes.mean()


def _authors(sizes):
    """leonidk/direct_gmm's modified scikit-learn 0.20: the E-step's Mahalanobis-plus-trace term is scaled by
    ``alpha_p / min(alpha)`` and the M-step is not weighted by size (every primitive counts once)."""
    present = sizes > 0
    return sizes / sizes[present].min(), present.astype(float)


def _authors_estep(sizes):
    """The authors' E-step (scaled by ``alpha_p / min(alpha)``) with textbook EM's size-weighted M-step: one half
    of what the authors' EM changes, to measure which half moves a result (docs/studies/em_halves.md)."""
    return _authors(sizes)[0], _textbook(sizes)[1]


def _authors_mstep(sizes):
    """Textbook EM's unscaled E-step with the authors' unweighted M-step: the other half."""
    return _textbook(sizes)[0], _authors(sizes)[1]


# variant -> function(sizes) -> (E-step scale per primitive, M-step weight per primitive)
VARIANTS = {"textbook": _textbook, "authors": _authors, "authors-estep": _authors_estep,
            "authors-mstep": _authors_mstep}
INITS = ("kmeans", "random")
