"""Table 1 averages each model's first registration trials (§VI-C: 25 runs), taken by trial id."""
import numpy as np

from dgmm.experiments.report import tables


def _row(model, mesh, method, trial, rotation):
    return {"model": model, "mesh": mesh, "method": method, "trial": str(trial), "protocol": "scaled",
            "variant": "none", "rotation_error_deg": str(rotation), "translation_error_pct": str(rotation / 10)}


def test_trials_are_ordered_by_id_and_table1_keeps_the_first():
    rows = [_row("bunny", "res4", "icp", trial, 1.0 + trial) for trial in (3, 0, 2, 1)]
    rows += [_row("bunny", "full", "icp", trial, 5.0 + trial) for trial in (1, 0)]  # not Table 1's bunny mesh
    errors = tables.registration_errors(rows, "scaled", "textbook")
    np.testing.assert_array_equal(errors["bunny", "res4", "icp"]["rot"], [1.0, 2.0, 3.0, 4.0])
    first = tables.table1_errors(errors, 2)
    np.testing.assert_array_equal(first["bunny", "res4", "icp"]["rot"], [1.0, 2.0])
    np.testing.assert_array_equal(first["bunny", "res4", "icp"]["trans"], [0.1, 0.2])
    np.testing.assert_array_equal(first["bunny", "full", "icp"]["rot"], [5.0, 6.0])
    assert tables.table1_errors(errors, None) is errors
