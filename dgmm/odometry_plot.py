"""Fig 6: top-down view of visual-odometry trajectories against the ground truth (paper §V, Fig 6).

Drawn headless: a :class:`matplotlib.figure.Figure` built without pyplot (Agg canvas when saved), and
:func:`save_png` writes it with no software or time metadata, so the same trajectories give the same bytes.
Positions are in metres, in the ground truth's world frame, which is z-up for TUM's motion capture and for
``dgmm.synthetic``: the top-down view is the x–y plane, with equal axes. Each estimate is first moved onto the
ground truth by the rigid alignment of its ATE (``dgmm.trajectory_metrics.absolute_trajectory_error``), as TUM's and evo's
trajectory plots do.
"""
from matplotlib.figure import Figure

from dgmm.errors import InputError
from dgmm.files import atomic_path
from dgmm.trajectory_metrics import absolute_trajectory_error
from dgmm.tum import MAX_TIME_DIFFERENCE, read_trajectory

PLANES = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}
"""Top-down plane name -> the two world axes drawn (horizontal, vertical)."""

METHOD_STYLE = {
    "gmm-pixels": ("GMM, pixel primitives", "tab:blue", "-"),
    "gmm-points": ("GMM, points", "tab:orange", "--"),
    "icp": ("ICP", "tab:red", ":"),
}
"""Odometry method -> (legend label, colour, line style); other names are drawn with matplotlib's defaults."""


def fig6(groundtruth, estimates, *, plane="xy", sequence=None, max_difference=MAX_TIME_DIFFERENCE):
    """Top-down view of the ground truth and each method's aligned trajectory (paper Fig 6).

    Parameters
    ----------
    groundtruth : dgmm.tum.Trajectory
        The sequence's ground truth (e.g. ``read_trajectory(folder / "groundtruth.txt")``); only the part spanned
        by the estimates' timestamps is drawn.
    estimates : dict of str to dgmm.tum.Trajectory
        Method name -> estimated trajectory, drawn in this order.
    plane : {"xy", "xz", "yz"}, default="xy"
        World axes of the top-down view (z-up worlds: "xy").
    sequence : str, optional
        Sequence name, shown in the title.
    max_difference : float
        Timestamp association tolerance (s).

    Returns
    -------
    matplotlib.figure.Figure
        One axes, metres, equal aspect; the legend gives each method's ATE RMSE.
    """
    if plane not in PLANES:
        raise InputError(f"plane must be one of {sorted(PLANES)}, got {plane!r}")
    if not estimates:
        raise InputError("fig6 needs at least one estimated trajectory")
    h, v = PLANES[plane]
    figure = Figure(figsize=(5.5, 5.0), dpi=110, layout="constrained")
    axes = figure.add_subplot()
    span = [min(e.timestamps[0] for e in estimates.values()), max(e.timestamps[-1] for e in estimates.values())]
    inside = (groundtruth.timestamps >= span[0] - max_difference) & (groundtruth.timestamps <= span[1] + max_difference)
    truth = groundtruth.translations[inside]
    axes.plot(truth[:, h], truth[:, v], color="black", lw=2.0, label="ground truth")
    axes.plot(truth[0, h], truth[0, v], "o", color="black", ms=5)
    for method, estimate in estimates.items():
        error = absolute_trajectory_error(estimate, groundtruth, max_difference)
        aligned = estimate.translations @ error.rotation.T + error.translation
        label, color, style = METHOD_STYLE.get(method, (method, None, "-"))
        axes.plot(aligned[:, h], aligned[:, v], color=color, ls=style, lw=1.4,
                  label=f"{label} (ATE {error.rmse:.3g} m)")
    axes.set_aspect("equal", adjustable="datalim")
    axes.set_xlabel(f"{'xyz'[h]} (m)")
    axes.set_ylabel(f"{'xyz'[v]} (m)")
    axes.grid(True, alpha=0.3)
    axes.legend(loc="best", fontsize=8)
    n_frames = max(len(e) for e in estimates.values())
    axes.set_title(f"{sequence or 'visual odometry'}: top-down ({plane}), {n_frames} frames", fontsize=10)
    return figure


def fig6_from_files(groundtruth_path, trajectory_paths, **options):
    """:func:`fig6` of TUM trajectory files.

    Parameters
    ----------
    groundtruth_path : path-like
        The sequence's ``groundtruth.txt``.
    trajectory_paths : dict of str to path-like
        Method name -> its estimated trajectory file (``results/odometry/{sequence}/{method}/trajectory.txt``).
    **options
        Passed to :func:`fig6`.
    """
    estimates = {method: read_trajectory(path) for method, path in trajectory_paths.items()}
    return fig6(read_trajectory(groundtruth_path), estimates, **options)


def save_png(figure, path):
    """Write ``figure`` as PNG (Agg) with no software or time metadata, through a temporary file and a rename."""
    with atomic_path(path) as partial:
        figure.savefig(partial, format="png", metadata={"Software": None})

