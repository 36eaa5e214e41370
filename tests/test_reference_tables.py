"""The comparison of a workflow table with its reference (tests/reference_tables.py): a planted change beyond a band
fails naming the row and column, one within it passes."""
import numpy as np
import pytest

from dgmm.runtime.tables import read_csv, write_csv
from tests.reference_tables import REFERENCE, TABLES, assert_within_bands


def planted(tmp_path, name, index, column, value):
    """The reference ``name`` with row ``index``'s ``column`` set to ``value``, written under ``tmp_path``."""
    rows = read_csv(REFERENCE / name)
    rows[index][column] = value
    write_csv(tmp_path / name, rows)
    return tmp_path / name


@pytest.mark.parametrize("name", TABLES)
def test_a_reference_is_within_its_own_bands(name):
    assert_within_bands(REFERENCE / name)


@pytest.mark.parametrize("factor, passes", [(0.5, True), (2.0, False)])
def test_a_likelihood_cell_moves_within_a_tenth_of_its_seeds_spread(tmp_path, factor, passes):
    rows = read_csv(REFERENCE / "likelihood.csv")
    first, second = (float(row["eval_ll"]) for row in rows[:2])  # the two seeds of one cell
    band = 0.1 * np.std([first, second], ddof=1)
    path = planted(tmp_path, "likelihood.csv", 0, "eval_ll", float(first + factor * band))
    if passes:
        assert_within_bands(path)
    else:
        with pytest.raises(AssertionError, match=r"'quadric1000-exact', '25', 'kmeans', 'authors', '0', '100'\) "
                                                 r"eval_ll"):
            assert_within_bands(path)


def test_a_trial_in_another_minimum_moves_its_method_s_mean_and_is_listed(tmp_path):
    rows = read_csv(REFERENCE / "registration.csv")
    path = planted(tmp_path, "registration.csv", 1, "rotation_error_deg", float(rows[1]["rotation_error_deg"]) + 1)
    with pytest.raises(AssertionError) as failure:
        assert_within_bands(path)
    message = str(failure.value)
    assert "'mesh-kmeans') mean rotation_error_deg" in message
    assert "trials whose minimum changed:\n('bunny', 'res4', 'scaled', 'textbook', 'mesh-kmeans', '1') " \
           "rotation_error_deg" in message
    assert_within_bands(planted(tmp_path, "registration.csv", 1, "rotation_error_deg",
                                float(rows[1]["rotation_error_deg"]) + 1e-6))


@pytest.mark.parametrize("factor, passes", [(1.005, True), (1.02, False)])
def test_an_ate_moves_within_a_tenth_of_the_seed_spread(tmp_path, factor, passes):
    """Our protocol's seed spread is 11.4% of a run's ATE: a tenth of it, 1.14%."""
    ate = float(read_csv(REFERENCE / "odometry.csv")[0]["ate_rmse_m"])
    path = planted(tmp_path, "odometry.csv", 0, "ate_rmse_m", ate * factor)
    if passes:
        assert_within_bands(path)
    else:
        with pytest.raises(AssertionError, match="'gmm-pixels', 'textbook', 'overlap', '8', 'ours', ''\\) ate_rmse_m"):
            assert_within_bands(path)


@pytest.mark.parametrize("name, column, value", [("registration.csv", "trial", "17"),
                                                 ("odometry.csv", "frames", "7")])
def test_other_columns_match_exactly(tmp_path, name, column, value):
    with pytest.raises(AssertionError, match="rows not in the run"):
        assert_within_bands(planted(tmp_path, name, 0, column, value))


def test_a_converged_flag_may_flip_only_in_the_same_minimum(tmp_path):
    """Trial 3 of the textbook mesh-kmeans rows stopped on scipy's precision loss (False) in the reference."""
    rows = read_csv(REFERENCE / "registration.csv")
    row = next(i for i, r in enumerate(rows)
               if (r["variant"], r["method"], r["trial"]) == ("textbook", "mesh-kmeans", "3"))
    assert rows[row]["converged"] == "False"
    flipped = [{**r, "converged": "True"} if i == row else r for i, r in enumerate(rows)]
    write_csv(tmp_path / "registration.csv", flipped)
    assert_within_bands(tmp_path / "registration.csv")
    moved = [{**r, "rotation_error_deg": str(float(r["rotation_error_deg"]) + 1)} if i == row else r
             for i, r in enumerate(flipped)]
    write_csv(tmp_path / "registration.csv", moved)
    with pytest.raises(AssertionError, match=r"'mesh-kmeans', '3'\) converged: True, reference False, in a minimum "
                                             "that changed"):
        assert_within_bands(tmp_path / "registration.csv")


def test_a_missing_row_fails(tmp_path):
    rows = read_csv(REFERENCE / "likelihood.csv")
    write_csv(tmp_path / "likelihood.csv", rows[1:])
    with pytest.raises(AssertionError, match=r"rows not in the run \[\('bunny', 'quadric1000-exact'"):
        assert_within_bands(tmp_path / "likelihood.csv")
