"""The authors' stored results: read from their notebooks, they match the committed table and the paper's print."""
import json
from pathlib import Path

import pytest

from dgmm.errors import DataError
from dgmm.experiments.authors_data import (FIG3_INPUTS, FIG4_INPUTS, cell_output, extract, grouped_means,
                                           printed_lists, values_by_name)
from dgmm.experiments.report import paper
from dgmm.runtime.tables import read_csv

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOK_DIR = ROOT.parent / "shared" / "data" / "direct_gmm" / "notebooks"


@pytest.fixture(scope="module")
def rows():
    return extract([NOTEBOOK_DIR])


def _value(rows, **keys):
    (row,) = [row for row in rows if all(row[key] == str(value) for key, value in keys.items())]
    return float(row["value"])


def test_the_committed_table_is_what_the_notebooks_print(rows):
    assert read_csv(ROOT / "reports" / "authors.csv") == rows


def test_every_cell_of_figs_3_and_4_once(rows):
    for item, inputs in (("fig3", FIG3_INPUTS), ("fig4", FIG4_INPUTS)):
        keys = [(row["input"], row["init"], row["K"]) for row in rows if row["item"] == item]
        assert len(keys) == len(set(keys)) == 56
        assert {key[0] for key in keys} == set(inputs.values())
        assert {int(key[2]) for key in keys} == {6, 12, 25, 50, 100, 200, 400}


def test_table1_as_the_paper_prints_it(rows):
    """The paper's Table 1 (typed from paper.tex) is each stored value rounded as printed."""
    columns = {"ll_points": ("points", "eval_ll", 1), "ll_mesh": ("mesh", "eval_ll", 1),
               "rot_points": ("points", "rotation", 0), "rot_mesh": ("mesh", "rotation", 0),
               "trans_points": ("points", "translation", 0), "trans_mesh": ("mesh", "translation", 0)}
    for model, published in paper.TABLE1.items():
        for column, value in zip(paper.TABLE1_COLUMNS, published):
            kind, quantity, digits = columns[column]
            stored = _value(rows, item="table1", model=model, input=kind, quantity=quantity)
            assert round(stored, digits) == pytest.approx(value), (model, column)


def test_fig3_and_fig6_as_the_paper_quotes_them(rows):
    for k, value in paper.FIG3_EXACT_KMEANS.items():
        assert round(_value(rows, item="fig3", input="res4-exact", init="kmeans", K=k), 2) == value
    for method, (rotation, translation) in paper.FIG6_MEANS.items():
        assert round(_value(rows, item="fig6", input=method, quantity="rotation"), 2) == rotation
        metres = _value(rows, item="fig6", input=method, quantity="translation")
        assert metres / 0.24077 * 100 == pytest.approx(translation, abs=0.006)


def test_the_model_codes_are_the_notebooks_labels():
    """Each model code's label in the plotting cell names the input we map it to."""
    labels = {"res4-approx": "Mesh (approx)", "res4-centroids": "Points (Center of Mass)",
              "res4-vertices": "Points (Vertices)", "res4-exact": "Mesh (exact)",
              "quadric1000-exact": "Mesh (Quadric)", "clustering1000-exact": "Mesh (Cluster)",
              "poisson1000-points": "Points (Poisson)", "random1000-points": "Points (Random)"}
    for notebook, cell, codes in (("tri_verts_graph.ipynb", 1, FIG3_INPUTS), ("format_graphs.ipynb", 2, FIG4_INPUTS)):
        source = "".join(json.loads((NOTEBOOK_DIR / notebook).read_text())["cells"][cell]["source"])
        for code, name in codes.items():
            assert f"if model == {code}:\n            label = '{labels[name]}'" in source


def test_a_printed_grouped_table_and_a_printed_tuple_of_two():
    table = ("                 l     i\ninit   model k              \nkmeans 0     6    6.5  25.0\n"
             "             12   7.0  24.5\n       1     6    6.6  25.0\nrandom 0     6   -1e-3  3.0")
    expected = [("kmeans", 0, 6, "6.5", "25.0"), ("kmeans", 0, 12, "7.0", "24.5"), ("kmeans", 1, 6, "6.6", "25.0"),
                ("random", 0, 6, "-1e-3", "3.0")]
    assert grouped_means(table) == expected
    twice = "(" + table.replace("\n", "\n ") + ",                 l     i\n init   model k\n kmeans 0  6  9.9  1.0)"
    assert grouped_means(twice) == expected


def test_printed_lists_and_names():
    text = "UserWarning: family ['sans-serif'] not found\n[0.5, 1.25e-3, -2]\n[3, 4]\n"
    assert printed_lists(text) == [["0.5", "1.25e-3", "-2"], ["3", "4"]]
    assert values_by_name("arma\n-1.5\n2\nbunny\n7.5\n", {"arma", "bunny"}) == {"arma": ["-1.5", "2"],
                                                                                "bunny": ["7.5"]}


def test_a_changed_or_missing_notebook_is_named(tmp_path):
    changed = tmp_path / "tri_verts_graph.ipynb"
    changed.write_text("{}")
    with pytest.raises(DataError, match="tri_verts_graph.ipynb: sha256"):
        extract([tmp_path, NOTEBOOK_DIR])
    with pytest.raises(DataError, match="tri_verts_graph.ipynb: not found"):
        extract([tmp_path / "none"])
    with pytest.raises(DataError, match="no cell 99"):
        cell_output(NOTEBOOK_DIR / "reg_viz.ipynb", 99)
