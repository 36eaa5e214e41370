"""Odometry protocols: ours (a measured schedule, sized pixel primitives), ours with unit sizes, or the authors'
per-frame protocol.

A protocol fixes how every frame's pixel mixture is built and fitted and how two frames are registered:

- ``"ours"``: the configured schedule (``odometry.schedule``, by default ``overlap``), pixel size
  (``odometry.pixel_size``) and EM variants, flat ``patch`` covariances; every method.
- ``"ours-unit"``: ours with every pixel primitive of size 1, gmm-pixels under textbook EM only: the switch that
  measures what the pixels' footprint areas (∝ Z²) do to textbook EM's odometry (on sizes of 1 both EM variants are
  one algorithm). It runs every frame, as ours does.
- ``"authors-patch"``, ``"authors-disparity"``: the authors' notebooks (leonidk/direct_gmm ``gen_gmm-mine-patch``,
  ``gen_gmm-mine`` and ``reg_results``): every pixel primitive of size 1 (``set_areas(np.ones(n))``) with the
  notebook's flat ``patch`` or ``disparity`` box covariance (:mod:`dgmm.odometry.pixel_covariance`), fitted as
  scikit-learn's ``GaussianMixture(100)`` at its defaults (the ``"authors"`` schedule:
  :mod:`dgmm.odometry.sklearn_em`), consecutive frames registered by determinant-free D2D from the identity with
  BFGS. ``authors-patch`` also runs the plain-point mixture (``gmm-points``) the same way, as ``gen_gmm.ipynb``
  fits it: the pair the paper's Fig 7 compares (its pixel trajectory is the patch run's). On sizes of 1 both EM
  variants are one algorithm; the runs are labelled with the authors' EM, the notebooks' modified mixture.
"""
from __future__ import annotations

from dataclasses import dataclass

from dgmm.errors import InputError

OURS = "ours"


@dataclass(frozen=True)
class Protocol:
    """The per-frame settings a protocol imposes (``run_odometry``'s ``schedule``, None keeping the caller's,
    ``size``, ``covariance``), the EM variant its runs are labelled with, its methods, and whether it runs only the
    first ``odometry.authors_frames`` frames (``capped``: the authors' per-frame EM costs 6-8x ours)."""

    schedule: str | None
    size: str
    covariance: str
    variant: str = "authors"
    methods: tuple = ("gmm-pixels",)
    capped: bool = True


PROTOCOLS = {
    OURS: None,
    "ours-unit": Protocol(schedule=None, size="unit", covariance="patch", variant="textbook", capped=False),
    "authors-patch": Protocol(schedule="authors", size="unit", covariance="patch", methods=("gmm-pixels", "gmm-points")),
    "authors-disparity": Protocol(schedule="authors", size="unit", covariance="disparity"),
}
"""Protocol name -> its settings; ``"ours"`` keeps the caller's (None)."""


def check_protocol(protocol, key="protocol"):
    """``protocol`` if it names one of :data:`PROTOCOLS`, else an InputError naming ``key``."""
    if protocol not in PROTOCOLS:
        raise InputError(f"{key} must be one of {', '.join(PROTOCOLS)}, got {protocol!r}")
    return protocol


def protocol_runs(protocols, methods):
    """The runs of the protocols other than ours among ``protocols`` (``"ours"`` is left to the caller), for the
    methods each applies to among ``methods``.

    Returns
    -------
    runs : dict of str to (str, str)
        ``"gmm-pixels-authors-patch" -> ("gmm-pixels", "authors")``, in the order of ``protocols``.
    """
    runs = {}
    for name in protocols:
        protocol = PROTOCOLS[check_protocol(name, "protocols")]
        if protocol is not None:
            runs.update({f"{method}-{name}": (method, protocol.variant) for method in methods
                         if method in protocol.methods})
    return runs


def run_protocol(run):
    """The protocol of a run named as :func:`protocol_runs` or ``dgmm.odometry.odometry_runs`` names it."""
    return next((name for name in PROTOCOLS if name != OURS and run.endswith(f"-{name}")), OURS)
