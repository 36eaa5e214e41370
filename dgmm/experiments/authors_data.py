"""The authors' stored results: the numbers their notebooks printed, read from the notebooks themselves.

leonidk/direct_gmm's notebooks hold the data behind the paper's figures and tables in their stored outputs (each at
the last commit that still has them; ``../shared/data/direct_gmm/notebooks/SOURCE.md``). :func:`extract` parses
those outputs into rows, nothing typed by hand: a pandas table printed by ``mdf`` (Fig 3, Fig 4), printed lists
(Fig 6's means) and printed numbers under a model's name (Table 1). Each row keeps the value as printed, with the
notebook and cell it came from.

Columns of :data:`COLUMNS`:

- ``item``: ``fig3``, ``fig4``, ``fig6`` or ``table1``;
- ``model``, ``input``: our names (Fig 3/4 inputs as config.yaml's ``fit.experiments``, ``points``/``mesh`` for
  Table 1's columns, our method names for registration);
- ``init``, ``K``: the start and the number of components (empty where the item has none);
- ``quantity`` and ``unit``: ``eval_ll`` (nat), ``rotation`` (deg or % of ICP), ``translation`` (the model's units
  or % of ICP);
- ``value``: as printed; ``n_iter``: the mean EM iterations where printed; ``trials``: the registration trials
  averaged where the notebook's data says (empty: not stored);
- ``notebook``, ``cell``: where it was printed (cells counted from 0).

The notebooks store no spread (their plotted ±2σ bands are images), so no row has one.
"""
import json
import re
from pathlib import Path

from dgmm.data import RemoteFile, fetch
from dgmm.errors import DataError

COLUMNS = ("item", "model", "input", "init", "K", "quantity", "unit", "value", "n_iter", "trials", "notebook",
           "cell")

_REPO = "leonidk/direct_gmm"
_SOURCE = "https://github.com/leonidk/direct_gmm"


def _notebook(name, commit, sha256, note):
    return RemoteFile(name, sha256, f"https://raw.githubusercontent.com/{_REPO}/{commit}/notebooks/{name}", _SOURCE,
                      note)


NOTEBOOKS = {
    "tri_verts_graph.ipynb": _notebook(
        "tri_verts_graph.ipynb", "5603ae8bbb9447f3ae6cc707719238e717c6a2a7",
        "8c79fa0745854f1d2adaea9580fd301e40285962d7a02df6867713304c64d290", "Fig 3: bunny res4, 56 cells"),
    "format_graphs.ipynb": _notebook(
        "format_graphs.ipynb", "5603ae8bbb9447f3ae6cc707719238e717c6a2a7",
        "7e1163e93de57c13b7acde86dc36e43c92c7774035af4e8888776ca17750ff10", "Fig 4: decimations and samples, 56 cells"),
    "tri_verts_graph-Copy1.ipynb": _notebook(
        "tri_verts_graph-Copy1.ipynb", "3b9de397efc37ed29f06452ea36b46105243c916",
        "d6e96950e5536336f13c0315e9c6bbfa5dae96e4193c029e2001b099de82f110", "Table 1's likelihoods"),
    "reg_viz.ipynb": _notebook(
        "reg_viz.ipynb", "3b9de397efc37ed29f06452ea36b46105243c916",
        "18c7e1e3f412b415cf008a266444b1a59ff886354566f23d613eb1bc69819df0", "Fig 6: the bunny's registration means"),
    "reg_viz-extra.ipynb": _notebook(
        "reg_viz-extra.ipynb", "3b9de397efc37ed29f06452ea36b46105243c916",
        "832650383dfa423f6ebbb4b4f323eabba4afee06af4a4b2cb403002788aa891a", "Table 1's registration columns"),
}
"""The notebooks read, registered as the meshes are (:mod:`dgmm.data`): found in a mirror, checked by sha256."""

FIG3_INPUTS = {0: "res4-approx", 1: "res4-centroids", 2: "res4-vertices", 3: "res4-exact"}
"""Fig 3's model codes (``tri_verts_graph.ipynb`` cell 1's labels: Mesh (approx), Points (Center of Mass), Points
(Vertices), Mesh (exact))."""
FIG4_INPUTS = {0: "quadric1000-exact", 1: "clustering1000-exact", 2: "poisson1000-points", 3: "random1000-points"}
"""Fig 4's model codes (``format_graphs.ipynb`` cell 2's labels: Mesh (Quadric), Mesh (Cluster), Points (Poisson),
Points (Random))."""
MODELS = {"arma": "armadillo", "bunny": "bunny", "dragon": "dragon", "happy": "happy", "lucy": "lucy"}
"""The notebooks' model names (their log and csv file stems) and ours."""
FIG6_METHODS = ("mesh-kmeans", "mesh-random", "points-kmeans", "points-random", "icp", "cpd")
"""``reg_viz.ipynb``'s ``names`` (meshk, mesh, vertsk, verts, icp, cpd) as our methods, in its order."""
FIG6_TRIALS = 250
"""Fig 6's trials (the paper's caption: 250 random trials)."""

_NUMBER = r"-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?"


def cell_output(path, index):
    """The printed text of cell ``index`` of the notebook at ``path``: its streams and its value's ``text/plain``."""
    try:
        cell = json.loads(Path(path).read_text())["cells"][index]
    except (OSError, ValueError, KeyError, IndexError) as exc:
        raise DataError(f"{path}: no cell {index} with outputs ({exc})") from None
    parts = []
    for output in cell.get("outputs", []):
        text = output.get("text") or output.get("data", {}).get("text/plain", "")
        parts.append("".join(text))
    return "".join(parts)


def grouped_means(text):
    """Rows ``(init, model, K, l, i)`` of a printed pandas table ``df.groupby(['init', 'model', 'k']).mean()``.

    The index prints each level only where it changes; the first table of a printed tuple is read.
    """
    rows, init, model = [], None, None
    for line in text.splitlines():
        line, end, _ = line.partition(",")  # a printed tuple: its next table starts after the comma
        tokens = line.strip(" (),").split()
        if not tokens or tokens[0] in ("l", "init"):
            continue
        if not re.fullmatch(_NUMBER, tokens[0]):
            init, tokens = tokens[0], tokens[1:]
        if len(tokens) == 4:
            model, tokens = int(tokens[0]), tokens[1:]
        if len(tokens) != 3:
            raise DataError(f"unexpected line in a printed table: {line!r}")
        rows.append((init, model, int(tokens[0]), tokens[1], tokens[2]))
        if end:
            break
    return rows


def printed_lists(text):
    """Every printed Python list of numbers in ``text``, as lists of strings."""
    numbers = rf"\[\s*({_NUMBER}(?:\s*,\s*{_NUMBER})*)\s*\]"
    return [re.findall(_NUMBER, body) for body in re.findall(numbers, text)]


def values_by_name(text, names):
    """``name -> [numbers printed on the lines after it]`` for a stream of a name line then number lines."""
    result, current = {}, None
    for line in text.split():
        if line in names:
            current = result.setdefault(line, [])
        elif current is not None and re.fullmatch(_NUMBER, line):
            current.append(line)
    return result


def _row(item, model, input_name, quantity, unit, value, notebook, cell, *, init="", k="", n_iter="", trials=""):
    return dict(item=item, model=model, input=input_name, init=init, K=k, quantity=quantity, unit=unit, value=value,
                n_iter=n_iter, trials=trials, notebook=notebook, cell=cell)


def _likelihood_cells(item, path, cell, inputs):
    return [_row(item, "bunny", inputs[model], "eval_ll", "nat", value, path.name, cell, init=init, k=k,
                 n_iter=n_iter)
            for init, model, k, value, n_iter in grouped_means(cell_output(path, cell))]


def _table1_likelihoods(path, cell=2):
    """``print(mdf["l"][2])`` then ``print(mdf["l"][3])`` under each model's name: points (vertices), then mesh."""
    rows = []
    for name, values in values_by_name(cell_output(path, cell), MODELS).items():
        for input_name, value in zip(("points", "mesh"), values, strict=True):
            rows.append(_row("table1", MODELS[name], input_name, "eval_ll", "nat", value, path.name, cell, k=100,
                             init="kmeans"))
    return rows


def _table1_registration(path, cell=1):
    """Under each model's name: rotation % of ICP (points, mesh), then translation % of ICP (points, mesh)."""
    rows = []
    for name, values in values_by_name(cell_output(path, cell), MODELS).items():
        quantities = [("rotation", "points"), ("rotation", "mesh"), ("translation", "points"), ("translation", "mesh")]
        for (quantity, input_name), value in zip(quantities, values, strict=True):
            rows.append(_row("table1", MODELS[name], input_name, quantity, "% of ICP", value, path.name, cell))
    return rows


def _fig6_means(path, cell=4):
    """Two printed lists: mean rotation errors (degrees) and mean translation errors (metres) per method."""
    rotation, translation = printed_lists(cell_output(path, cell))
    return [_row("fig6", "bunny", method, quantity, unit, value, path.name, cell, trials=FIG6_TRIALS)
            for quantity, unit, values in (("rotation", "deg", rotation), ("translation", "m", translation))
            for method, value in zip(FIG6_METHODS, values, strict=True)]


def extract(mirrors, cache=None):
    """Every stored value the report compares with, as rows of :data:`COLUMNS` (all strings).

    Parameters
    ----------
    mirrors : sequence of path-like
        Directories holding the notebooks (``../shared/data/direct_gmm/notebooks``).
    cache : path-like, optional
        Where a missing notebook is downloaded to.
    """
    paths = {name: fetch(remote, mirrors, cache) for name, remote in NOTEBOOKS.items()}
    rows = (_likelihood_cells("fig3", paths["tri_verts_graph.ipynb"], 3, FIG3_INPUTS)
            + _likelihood_cells("fig4", paths["format_graphs.ipynb"], 4, FIG4_INPUTS)
            + _table1_likelihoods(paths["tri_verts_graph-Copy1.ipynb"])
            + _table1_registration(paths["reg_viz-extra.ipynb"])
            + _fig6_means(paths["reg_viz.ipynb"]))
    return [{column: str(row[column]) for column in COLUMNS} for row in rows]
