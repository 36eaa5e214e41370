"""Fig 6 and Fig 7 draw the numbers of their tables: read back from the matplotlib figures' artists (not the PNG).

References are built here: hand-made registration errors with known means; a hand-made trajectory, rigidly
moved and scaled copies of it whose aligned positions and ATE are known in closed form.
"""
import re

import numpy as np
import pytest
from matplotlib.collections import PathCollection
from scipy.spatial.transform import Rotation

from dgmm.experiments.report import paper
from dgmm.experiments.report.figures import fig6_registration
from dgmm.odometry.figure import fig7
from dgmm.odometry.tum import Trajectory

METHODS = ["mesh-kmeans", "points-random", "icp", "cpd"]


def fig6_errors():
    """Per method, 7 trials of rotation and translation errors with distinct, known values (and an unrelated model)."""
    rng = np.random.default_rng(0)
    errors = {("bunny", "res4", method): {"rot": rng.uniform(0.1, 3.0, 7) * (k + 1),
                                          "trans": rng.uniform(0.01, 1.0, 7) * (k + 1)}
              for k, method in enumerate(METHODS)}
    errors["dragon", "res4", "icp"] = {"rot": np.full(7, 50.0), "trans": np.full(7, 50.0)}
    return errors


def test_fig6_draws_every_trial_our_means_and_the_paper_s_means_per_method():
    """Each panel's tick labels are the methods in the paper's order; the dots above tick i are method i's trials
    of that panel's error (rotation left, translation right); the mean markers are their means; the red crosses
    the paper's means. Tried and failing: swapped panels, methods drawn in another order than their labels, the
    paper's means of the other panel."""
    errors = fig6_errors()
    figure = fig6_registration(errors)
    rotation_axes, translation_axes = figure.axes
    for ax, name, column in ((rotation_axes, "rot", 0), (translation_axes, "trans", 1)):
        labels = [label.get_text() for label in ax.get_xticklabels()]
        assert labels == METHODS
        drawn_dots = [c for c in ax.collections if isinstance(c, PathCollection)]
        assert len(drawn_dots) == len(METHODS)
        for position, (method, collection) in enumerate(zip(METHODS, drawn_dots), start=1):
            offsets = np.asarray(collection.get_offsets())
            assert np.all(np.abs(offsets[:, 0] - position) <= 0.18)
            np.testing.assert_array_equal(np.sort(offsets[:, 1]), np.sort(errors["bunny", "res4", method][name]))
        means = [line for line in ax.lines if line.get_marker() == "o" and len(line.get_xdata()) == 1]
        assert len(means) == len(METHODS)
        for method, line in zip(METHODS, sorted(means, key=lambda line: line.get_xdata()[0])):
            assert line.get_ydata()[0] == pytest.approx(np.mean(errors["bunny", "res4", method][name]), rel=1e-12)
        (crosses,) = [line for line in ax.lines if line.get_marker() == "x"]
        np.testing.assert_array_equal(crosses.get_xdata(), np.arange(1, len(METHODS) + 1))
        np.testing.assert_allclose(crosses.get_ydata(), [paper.FIG6_MEANS[m][column] for m in METHODS])


def hand_made_trajectory(n=30):
    """A z-up camera path spiralling in the xy-plane at 30 Hz."""
    t = np.arange(n) / 30
    translations = np.column_stack([np.cos(4 * t) * (1 + t), np.sin(4 * t) * (1 + t), 0.2 * t])
    rotations = Rotation.from_rotvec(np.outer(4 * t, [0, 0, 1])).as_matrix()
    return Trajectory(100.0 + t, rotations, translations)


def test_fig7_draws_the_ground_truth_and_each_estimate_aligned_with_its_ate():
    """A rigidly moved copy of the ground truth must be drawn on top of it (the figure applies the ATE's
    alignment) with ATE 0 in its label; a copy scaled by 1.3 about its centroid aligns by the identity, so it is
    drawn as that scaled copy, labelled with 0.3 times the positions' RMS spread. Tried and failing: the estimate
    drawn unaligned, or with the alignment applied the wrong way round."""
    truth = hand_made_trajectory()
    moved_by, offset = Rotation.from_rotvec([0.4, -0.2, 1.0]).as_matrix(), np.array([3.0, -2.0, 1.0])
    moved = Trajectory(truth.timestamps, moved_by @ truth.rotations, truth.translations @ moved_by.T + offset)
    centroid = truth.translations.mean(axis=0)
    scaled = Trajectory(truth.timestamps, truth.rotations, centroid + 1.3 * (truth.translations - centroid))
    spread = np.sqrt(np.mean(np.sum((truth.translations - centroid) ** 2, axis=1)))

    figure = fig7({"hand-made": (truth, {"gmm-pixels-textbook": moved, "icp": scaled})})
    (ax,) = figure.axes
    lines = {line.get_label(): line for line in ax.lines}
    ground = lines["ground truth"]
    np.testing.assert_allclose(np.column_stack([ground.get_xdata(), ground.get_ydata()]), truth.translations[:, :2])
    (moved_label,) = [label for label in lines if label.startswith("GMM, pixel primitives, textbook EM")]
    (scaled_label,) = [label for label in lines if label.startswith("ICP")]
    drawn = lines[moved_label]
    np.testing.assert_allclose(np.column_stack([drawn.get_xdata(), drawn.get_ydata()]), truth.translations[:, :2],
                               atol=1e-9)
    drawn = lines[scaled_label]
    np.testing.assert_allclose(np.column_stack([drawn.get_xdata(), drawn.get_ydata()]),
                               scaled.translations[:, :2], atol=1e-9)
    ate = {label: float(re.search(r"ATE (\S+) m", label).group(1)) for label in (moved_label, scaled_label)}
    assert ate[moved_label] < 1e-9
    assert ate[scaled_label] == pytest.approx(0.3 * spread, rel=1e-3)  # the label's 3 significant digits


def test_fig7_of_a_recording_without_ground_truth_draws_the_estimate_as_it_is():
    """No ground truth (a recording's): no ground-truth line, no ATE, the estimate's own x and z (the first
    camera's frame seen from above), beside a panel with ground truth."""
    truth = hand_made_trajectory()
    figure = fig7({"scored": (truth, {"icp": truth}), "unscored": (None, {"icp": truth})})
    _, ax = figure.axes
    (line,) = ax.lines
    assert line.get_label() == "ICP" and "no ground truth" in ax.get_title()
    np.testing.assert_allclose(np.column_stack([line.get_xdata(), line.get_ydata()]), truth.translations[:, [0, 2]])
