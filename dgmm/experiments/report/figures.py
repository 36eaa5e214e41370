"""The report's figures: one function per paper figure, drawn headless with matplotlib's Agg canvas.

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot (no global state, no display);
:func:`save_png` writes it with no software/time metadata so the same data give the same bytes. Shapes are in
the models' own units (metres); 3-D pictures show the bunny upright (its +y axis up).
"""
from contextlib import contextmanager

import matplotlib
import numpy as np
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from dgmm.experiments.report import paper
from dgmm.experiments.report.tables import FIG6_MESH, fig2_bars
from dgmm.experiments.sweep import SIZED, job_seed, parse_input
from dgmm.mixture import GaussianMixture
from dgmm.primitives import Primitives
from dgmm.recording import covariance_ellipsoids

STYLE = {
    "font.size": 9, "axes.titlesize": 10, "axes.labelsize": 9, "legend.fontsize": 8, "axes.grid": True,
    "grid.alpha": 0.3, "axes.spines.top": False, "axes.spines.right": False, "figure.dpi": 110,
    "savefig.dpi": 110, "svg.hashsalt": "dgmm", "path.simplify": True, "figure.constrained_layout.use": True,
}
LOG_LIKELIHOOD = "mean log-likelihood of the evaluation points (nats)"
METHOD_ORDER = ("mesh-kmeans", "mesh-random", "points-kmeans", "points-random", "icp", "cpd")
PICTURE_VIEW = {"elev": 10.0, "azim": -80.0}
LIGHT = np.array([0.3, -0.8, 0.6]) / np.linalg.norm([0.3, -0.8, 0.6])
N_SIGMA = 1.5
"""Ellipsoids of triangles (Fig 1, as the paper: "plotted to 1.5σ") and of mixtures (Fig 5) span 1.5σ."""
PICTURED_K = 100
Y_LIMITS = (2.0, 9.0)
"""Figs 3 and 4's y axis, as the authors' notebooks set it (nats)."""
BAND_SD = {3: 2.0, 4: 1.0}
"""Figs 3 and 4's bands: ± this many standard deviations over seeds, as the authors' notebooks draw them
(``tri_verts_graph.ipynb``: ``2*sdf``; ``format_graphs.ipynb``: ``sdf``)."""
MESH_KEYS = ("res4", "full", "random", "clustering", "dense", "poisson", "quadric")
"""Data-stage files of the bunny the pictures read (Fig 1: res4; Fig 5: all)."""
HEAD = (np.array([-0.065, 0.125, 0.035]), 0.022)
"""Centre and radius (metres) of the bunny's head region in Fig 1."""


@contextmanager
def styled():
    """The report's matplotlib style, for drawing and saving."""
    with matplotlib.rc_context(STYLE):
        yield


def new_figure(width, height):
    """An empty figure of ``width`` x ``height`` inches in the report's style."""
    with styled():
        return Figure(figsize=(width, height))


def save_png(figure, path):
    """Write ``figure`` as PNG with no metadata beyond its pixels (reproducible bytes)."""
    with styled():
        figure.savefig(path, format="png", metadata={"Software": None})


# ---------------------------------------------------------------------------------------------------------
# 3-D pictures (Figs 1 and 5)
# ---------------------------------------------------------------------------------------------------------

def upright(points):
    """Bunny coordinates (+y up) to matplotlib's (+z up): a rotation by 90° about x."""
    points = np.asarray(points)
    return np.stack([points[..., 0], -points[..., 2], points[..., 1]], axis=-1)


def ellipsoid_quads(means, covariances, n_sigma, n_u=14, n_v=8):
    """Quadrilaterals tiling the ``n_sigma`` ellipsoid of each Gaussian.

    Parameters
    ----------
    means : ndarray of shape (n_components, 3)
    covariances : ndarray of shape (n_components, 3, 3)
    n_sigma : float

    Returns
    -------
    ndarray of shape (n_components * n_u * n_v, 4, 3)
    """
    rotations, half_sizes, _ = covariance_ellipsoids(covariances, n_sigma)
    u, v = np.linspace(0, 2 * np.pi, n_u + 1), np.linspace(0, np.pi, n_v + 1)
    sphere = np.stack([np.outer(np.cos(u), np.sin(v)), np.outer(np.sin(u), np.sin(v)),
                       np.outer(np.ones_like(u), np.cos(v))], axis=-1)  # (n_u + 1, n_v + 1, 3)
    corners = np.stack([sphere[:-1, :-1], sphere[1:, :-1], sphere[1:, 1:], sphere[:-1, 1:]], axis=2)
    unit = corners.reshape(-1, 4, 3)
    scaled = unit[None] * half_sizes[:, None, None, :]
    return (np.einsum("kij,kqcj->kqci", rotations, scaled) + means[:, None, None, :]).reshape(-1, 4, 3)


def _shade(polygons, color):
    """Face colours of ``polygons`` (n, m, 3) lit by ``LIGHT`` (Lambert, two-sided, with ambient light)."""
    normals = np.cross(polygons[:, 2] - polygons[:, 0], polygons[:, -1] - polygons[:, 1])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-30)
    intensity = 0.35 + 0.65 * np.abs(normals @ LIGHT)
    rgb = np.atleast_2d(matplotlib.colors.to_rgb(color) if isinstance(color, str) else color)
    return np.clip(rgb * intensity[:, None], 0, 1)


def _add_polygons(ax, polygons, color):
    """Draw bunny-frame ``polygons`` (n, m, 3) shaded on a 3-D axes, in one colour or one RGB row each."""
    polygons = upright(polygons)
    ax.add_collection3d(Poly3DCollection(polygons, facecolors=_shade(polygons, color), edgecolors="none"))


def _frame(ax, points, title):
    """Equal-aspect limits around bunny-frame ``points``, the common view, no axes."""
    points = upright(points)
    low, high = points.min(axis=0), points.max(axis=0)
    centre, half = (low + high) / 2, (high - low).max() / 2
    ax.set(xlim=(centre[0] - half, centre[0] + half), ylim=(centre[1] - half, centre[1] + half),
           zlim=(centre[2] - half, centre[2] + half))
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(**PICTURE_VIEW)
    ax.set_axis_off()
    ax.set_title(title)


def _mixture_colours(n_components):
    """One colour per component, from a fixed colormap."""
    return matplotlib.colormaps["tab20"](np.arange(n_components) % 20)[:, :3]


def _draw_ellipsoids(ax, means, covariances, n_sigma, alpha=1.0):
    """The ``n_sigma`` ellipsoids of Gaussians in bunny coordinates, shaded, one colour each."""
    quads = upright(ellipsoid_quads(means, covariances, n_sigma))
    colours = np.repeat(_mixture_colours(len(means)), len(quads) // len(means), axis=0)
    ax.add_collection3d(Poly3DCollection(quads, facecolors=colours * _shade(quads, "white"), alpha=alpha,
                                         linewidths=0))


def fig1_triangles(meshes):
    """Fig 1: bunny res4 with its head region, and the head's triangles with their 1.5σ covariance ellipses."""
    vertices, faces = meshes["res4"]
    prims = Primitives.from_mesh(vertices, faces)
    centre, radius = HEAD
    head = np.linalg.norm(prims.means - centre, axis=1) < radius
    figure = new_figure(8.0, 4.0)
    whole = figure.add_subplot(1, 2, 1, projection="3d")
    colours = np.where(head[:, None], matplotlib.colors.to_rgb("tab:orange"), matplotlib.colors.to_rgb("lightgray"))
    _add_polygons(whole, vertices[faces], colours)  # one collection: matplotlib depth-sorts within it only
    _frame(whole, vertices, f"bunny res4, {len(faces)} triangles, head in orange")
    detail = figure.add_subplot(1, 2, 2, projection="3d")
    detail.add_collection3d(Poly3DCollection(upright(vertices[faces[head]]), facecolors="none", edgecolors="k",
                                             linewidths=0.4))
    _draw_ellipsoids(detail, prims.means[head], prims.covariances[head], N_SIGMA, alpha=0.85)
    _frame(detail, vertices[faces[head]].reshape(-1, 3),
           f"{int(head.sum())} head triangles, {N_SIGMA}σ ellipses")
    return figure


def pictured_mixtures(meshes, seed):
    """The K=100 GMMs of Fig 5, fitted here: to bunny res4's triangles (mesh) and to their centroids (points: §IV-A
    contrasts the mesh GMM with "the center-of-mass GMM").

    Fitted with the sweep's defaults (k-means start, 25 iterations) from seeds derived from ``seed``.
    """
    mesh = Primitives.from_mesh(*meshes["res4"])
    inputs = {"mesh": mesh, "points": Primitives.from_points(mesh.means)}
    return {name: GaussianMixture(PICTURED_K, random_state=job_seed(seed, f"report/fig5/{name}", 0)).fit(prims)
            for name, prims in inputs.items()}


FIG5_PANELS = (
    # (title, mesh key, how to draw it)
    ("Stanford bunny (full mesh)", "full", "mesh"),
    ("random samples", "random", "points"),
    ("clustering decimated", "clustering", "mesh"),
    (f"points GMM, K={PICTURED_K}\n(res4 triangle centroids)", "points", "mixture"),
    ("dense sampled (evaluation set)", "dense", "points"),
    ("Poisson-disk sampled", "poisson", "points"),
    ("quadric decimated", "quadric", "mesh"),
    (f"mesh GMM, K={PICTURED_K}\n(res4 triangles)", "mesh", "mixture"),
)


def fig5_representations(meshes, mixtures):
    """Fig 5: the input representations of the bunny and the points and mesh GMMs, in the paper's layout.

    Parameters
    ----------
    meshes : dict
        ``name -> (vertices, faces or None)`` for every mesh key of ``FIG5_PANELS``.
    mixtures : dict
        :func:`pictured_mixtures`.
    """
    figure = new_figure(11.0, 6.0)
    for index, (title, key, kind) in enumerate(FIG5_PANELS):
        ax = figure.add_subplot(2, 4, index + 1, projection="3d")
        vertices = meshes["full"][0]
        if kind == "mesh":
            _add_polygons(ax, meshes[key][0][meshes[key][1]], "lightgray")
            title = f"{title}\n{len(meshes[key][1]):,} triangles"
        elif kind == "points":
            shown = upright(meshes[key][0])
            ax.scatter(*shown.T, s=0.05 if len(shown) > 5000 else 1.5, c="k", linewidths=0, depthshade=False)
            title = f"{title}\n{len(shown):,} points"
        else:
            _draw_ellipsoids(ax, mixtures[key].means_, mixtures[key].covariances_, N_SIGMA)
            title = f"{title}, {N_SIGMA:g}σ"
        _frame(ax, vertices, title)
    return figure


# ---------------------------------------------------------------------------------------------------------
# Plots (Figs 2 to 5)
# ---------------------------------------------------------------------------------------------------------

def fig2_expressions(rows):
    """Fig 2: the likelihood expressions of one fit, bars of the paper's quantity, markers of our EM bound."""
    paper_bars, paper_ref = fig2_bars(rows, "expected")
    bound_bars, bound_ref = fig2_bars(rows, "bound")
    labels = [label for label, _, _ in paper_bars]
    x = np.arange(len(labels))
    figure = new_figure(8.0, 4.6)
    ax = figure.add_subplot()
    values = [mean for _, mean, _ in paper_bars] + [mean for _, mean, _ in bound_bars] + [paper_ref, bound_ref]
    low = min(values) - 0.3
    ax.bar(x, [mean - low for _, mean, _ in paper_bars], bottom=low, yerr=[std for _, _, std in paper_bars],
           color=["tab:orange"] * 3 + ["tab:blue"] * (len(labels) - 3), capsize=3,
           label="paper's quantity Σᵢ ηᵢₚ log ρᵢₚ (no entropy), ±1 std")
    ax.errorbar(x, [mean for _, mean, _ in bound_bars], yerr=[std for _, _, std in bound_bars], fmt="D",
                color="k", markersize=4, capsize=2, label="our EM bound (with entropy)")
    ax.axhline(paper_ref, color="tab:red", label=f"all points, paper's quantity ({paper_ref:.3f})")
    ax.axhline(bound_ref, color="tab:red", linestyle="--", label=f"all points, our bound ({bound_ref:.3f})")
    ax.set(xticks=x, xticklabels=labels, ylim=(low, max(values) + 0.35),
           ylabel="log-likelihood per unit size (nats)", xlabel="expression (mesh) or number of sampled points")
    ax.tick_params(axis="x", labelrotation=20)
    figure.legend(loc="outside lower center", ncols=2)
    return figure


def _input_colours(inputs):
    """One colour per input name, in order."""
    return {name: matplotlib.colormaps["tab10"](index) for index, name in enumerate(inputs)}


def likelihood_vs_k(curves, inputs, variant, band_sd, stored=None):
    """Figs 3, 4 as the authors drew them: mean eval log-likelihood vs K (log scale) per input, one panel per start,
    a band of ±``band_sd`` standard deviations over seeds, y from 2 to 9 nats; the authors' stored means overlaid.

    Parameters
    ----------
    curves : dict
        :func:`dgmm.experiments.report.tables.likelihood_curves`.
    inputs : sequence of str
        Input names in legend order (their colours).
    variant : str
        The EM whose mesh fits are drawn (point inputs: textbook EM, the same algorithm).
    band_sd : float
        Half-width of the band in standard deviations over seeds (:data:`BAND_SD`).
    stored : dict, optional
        ``(input, init) -> (ks, means)`` of the authors' stored values, drawn as crosses on a thin line.
    """
    curves = {key: curve for key, curve in curves.items()
              if key[1] == (variant if parse_input(key[0])[1] in SIZED else "textbook")}
    inits = sorted({init for _, _, init in curves} | {init for _, init in stored or {}})
    colours = _input_colours(inputs)
    figure = new_figure(4.0 * len(inits) + 2.8, 4.2)
    axes = figure.subplots(1, len(inits), sharey=True, squeeze=False)[0]
    for ax, init in zip(axes, inits):
        for (name, _, curve_init), (ks, mean, std) in curves.items():
            if curve_init == init:
                line = "--" if parse_input(name)[1] in SIZED else "-"
                ax.plot(ks, mean, linestyle=line, marker="o", markersize=3.5, color=colours[name], label=f"{name}")
                ax.fill_between(ks, mean - band_sd * std, mean + band_sd * std, color=colours[name], alpha=0.15,
                                linewidth=0)
        for name in inputs:
            if (name, init) in (stored or {}):
                ks, means = stored[name, init]
                ax.plot(ks, means, linestyle=":", linewidth=1.0, marker="x", markersize=6, color=colours[name],
                        label=f"{name}, authors' stored")
        ax.set(xscale="log", title=f"{init} initialisation", xlabel="number of components K (log scale)")
        ax.set_ylim(*Y_LIMITS)
    axes[0].set_ylabel(LOG_LIKELIHOOD)
    handles = {label: handle for ax in axes for handle, label in zip(*ax.get_legend_handles_labels())}
    figure.legend(handles.values(), handles.keys(), loc="outside right center")
    return figure


def _methods(errors, model_mesh):
    """Registration methods of a (model, mesh) in the paper's order, unknown ones after."""
    methods = {method for *key, method in errors if tuple(key) == model_mesh}
    return [m for m in METHOD_ORDER if m in methods] + sorted(methods - set(METHOD_ORDER))


def fig6_registration(errors, model_mesh=FIG6_MESH, seed=0):
    """Fig 6: rotation and translation errors per method: trials, box and whisker (notched median), mean dot.

    Paper means (DESIGN.md) are marked with a red cross.
    """
    methods = _methods(errors, model_mesh)
    figure = new_figure(10.0, 4.0)
    jitter = np.random.default_rng(seed)
    for column, (name, unit) in enumerate((("rot", "rotation error (degrees)"),
                                           ("trans", "translation error (% of bounding-box diagonal)"))):
        ax = figure.add_subplot(1, 2, column + 1)
        data = [errors[(*model_mesh, method)][name] for method in methods]
        ax.boxplot(data, notch=True, showfliers=False, showmeans=True, tick_labels=methods,
                   meanprops={"marker": "o", "markerfacecolor": "tab:green", "markeredgecolor": "k", "markersize": 6})
        for index, values in enumerate(data):
            ax.scatter(index + 1 + jitter.uniform(-0.18, 0.18, len(values)), values, s=3, color="tab:blue",
                       alpha=0.4, linewidths=0)
        published = [(i + 1, paper.FIG6_MEANS[m][column]) for i, m in enumerate(methods) if m in paper.FIG6_MEANS]
        if published:
            ax.plot(*zip(*published), "x", color="tab:red", markersize=8, label="paper mean")
        ax.plot([], [], "o", color="tab:green", markeredgecolor="k", label="our mean")
        ax.set(yscale="log", ylabel=unit, xlabel="method")
        ax.tick_params(axis="x", labelrotation=20)
        ax.legend(fontsize=7)
    return figure
