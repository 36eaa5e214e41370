"""Fig 7: top-down view of visual-odometry trajectories against the ground truth (paper §VI-D, Fig 7).

Drawn headless: a :class:`matplotlib.figure.Figure` built without pyplot (Agg canvas when saved), and
:func:`save_png` writes it with no software or time metadata, so the same trajectories give the same bytes.
Positions are in metres, in the ground truth's world frame, which is z-up for TUM's motion capture and for
``dgmm.odometry.synthetic``: the top-down view is the x–y plane, with equal axes. Each estimate is first moved onto
the ground truth by the rigid alignment of its ATE (``dgmm.odometry.metrics.absolute_trajectory_error``), as TUM's
and evo's trajectory plots do.
"""
from dgmm.errors import InputError, needs
from dgmm.files import atomic_path
from dgmm.odometry.metrics import absolute_trajectory_error
from dgmm.odometry.protocols import PROTOCOLS
from dgmm.odometry.tum import MAX_TIME_DIFFERENCE, read_trajectory

with needs("figures"):
    from matplotlib.figure import Figure

PLANES = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}
"""Top-down plane name -> the two world axes drawn (horizontal, vertical)."""

METHOD_STYLE = {
    "gmm-pixels": ("GMM, pixel primitives", "tab:blue"),
    "gmm-points": ("GMM, points", "tab:orange"),
    "icp": ("ICP", "tab:red"),
}
"""Odometry method -> (legend label, colour); other names are drawn with matplotlib's defaults."""

VARIANT_LINE = {"": ":", "textbook": "-", "authors": "--"}
"""EM variant of a run (``""``: none, ICP) -> line style."""

PROTOCOL_LINE = {"authors-patch": "-.", "authors-disparity": (0, (6, 2, 1, 2, 1, 2))}
"""An authors' protocol of a run (``dgmm.odometry.protocols``) -> line style."""


def _run_style(run):
    """(label, colour, line style) of a run named ``method``, ``method-variant`` or ``method-protocol``
    (``dgmm.odometry.odometry_runs``)."""
    method = max((name for name in METHOD_STYLE if run.startswith(name)), key=len, default=run)
    variant = run[len(method) + 1:]
    label, color = METHOD_STYLE.get(method, (method, None))
    if variant in PROTOCOLS:  # a run of an authors' protocol (dgmm.odometry.protocols.protocol_runs)
        return f"{label}, {variant} protocol", color, PROTOCOL_LINE.get(variant, "-.")
    return (f"{label}, {variant} EM" if variant else label), color, VARIANT_LINE.get(variant, "-.")


def _panel(axes, groundtruth, estimates, plane, sequence, max_difference):
    """One sequence's top-down view: the ground truth over the estimates' span and each aligned estimate; without
    ground truth, each estimate as it is, in the first camera's frame seen from above (its x–z plane)."""
    plane = plane if groundtruth is not None else "xz"
    h, v = PLANES[plane]
    if groundtruth is not None:
        span = [min(e.timestamps[0] for e in estimates.values()), max(e.timestamps[-1] for e in estimates.values())]
        inside = ((groundtruth.timestamps >= span[0] - max_difference)
                  & (groundtruth.timestamps <= span[1] + max_difference))
        truth = groundtruth.translations[inside]
        axes.plot(truth[:, h], truth[:, v], color="black", lw=2.0, label="ground truth")
        axes.plot(truth[0, h], truth[0, v], "o", color="black", ms=5)
    for run, estimate in estimates.items():
        label, color, style = _run_style(run)
        positions = estimate.translations
        if groundtruth is not None:
            error = absolute_trajectory_error(estimate, groundtruth, max_difference)
            positions = positions @ error.rotation.T + error.translation
            label = f"{label} (ATE {error.rmse:.3g} m)"
        axes.plot(positions[:, h], positions[:, v], color=color, ls=style, lw=1.4, label=label)
    axes.set_aspect("equal", adjustable="datalim")
    axes.set_xlabel(f"{'xyz'[h]} (m)")
    axes.set_ylabel(f"{'xyz'[v]} (m)")
    axes.grid(True, alpha=0.3)
    axes.legend(loc="best", fontsize=7)
    n_frames = max(len(e) for e in estimates.values())
    where = f"top-down ({plane})" if groundtruth is not None else "no ground truth, first camera's x-z"
    axes.set_title(f"{sequence}: {where}, {n_frames} frames", fontsize=10)


def fig7(panels, *, plane="xy", max_difference=MAX_TIME_DIFFERENCE):
    """Top-down views of the ground truth and each run's aligned trajectory, one panel per sequence (paper Fig 7).

    Parameters
    ----------
    panels : dict of str to (dgmm.odometry.tum.Trajectory or None, dict of str to dgmm.odometry.tum.Trajectory)
        Sequence name -> (its ground truth, run name -> estimated trajectory), drawn left to right in this order;
        only the part of the ground truth spanned by the estimates' timestamps is drawn. A sequence without ground
        truth (None; a recording's) is drawn unaligned, in its first camera's frame from above. Run names are
        ``method`` or ``method-variant`` (colour by method, line style by EM variant).
    plane : {"xy", "xz", "yz"}, default="xy"
        World axes of the top-down view (z-up worlds: "xy").
    max_difference : float
        Timestamp association tolerance (s).

    Returns
    -------
    matplotlib.figure.Figure
        One axes per sequence, metres, equal aspect; each legend gives the runs' ATE RMSE.
    """
    if plane not in PLANES:
        raise InputError(f"plane must be one of {sorted(PLANES)}, got {plane!r}")
    if not panels or not all(estimates for _, estimates in panels.values()):
        raise InputError("fig7 needs at least one sequence, each with at least one estimated trajectory")
    figure = Figure(figsize=(5.5 * len(panels), 5.0), dpi=110, layout="constrained")
    for axes, (sequence, (groundtruth, estimates)) in zip(figure.subplots(1, len(panels), squeeze=False)[0],
                                                           panels.items()):
        _panel(axes, groundtruth, estimates, plane, sequence, max_difference)
    return figure


def fig7_from_files(panels, **options):
    """:func:`fig7` of TUM trajectory files.

    Parameters
    ----------
    panels : dict of str to (path-like or None, dict of str to path-like)
        Sequence name -> (its ``groundtruth.txt`` or None, run name -> its estimated trajectory file
        ``results/odometry/{sequence}/{run}/trajectory.txt``).
    **options
        Passed to :func:`fig7`.
    """
    return fig7({sequence: (None if truth is None else read_trajectory(truth),
                            {run: read_trajectory(path) for run, path in runs.items()})
                 for sequence, (truth, runs) in panels.items()}, **options)


def save_png(figure, path):
    """Write ``figure`` as PNG (Agg) with no software or time metadata, through a temporary file and a rename."""
    with atomic_path(path) as partial:
        figure.savefig(partial, format="png", metadata={"Software": None})

