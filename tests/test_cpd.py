"""dgmm's rigid CPD against pycpd's RigidRegistration, the paper's CPD baseline, on the same inputs.

pycpd is the reference: same objective at every iteration, same iteration count and stopping reason, and the same
rigid part (read from pycpd's moved points with scipy's Kabsch, not dgmm's) to 1e-9.
"""
import numpy as np
import pytest
from pycpd import RigidRegistration
from scipy.spatial.transform import Rotation

from dgmm.errors import InputError
from dgmm.registration import register_cpd


def _problem(vertices, seed, n_source, n_target):
    """Source: ``n_source`` bunny vertices moved by a random trial (±15° per axis, ±0.05 per axis, about the
    centroid); target: ``n_target`` other draws of the vertices with 1 mm of noise."""
    rng = np.random.default_rng(seed)
    source = vertices[rng.choice(len(vertices), n_source, replace=False)]
    target = vertices[rng.choice(len(vertices), n_target, replace=False)] + rng.normal(scale=1e-3, size=(n_target, 3))
    rotation = Rotation.from_euler("xyz", rng.uniform(-15, 15, 3), degrees=True).as_matrix()
    centre = source.mean(axis=0)
    return (source - centre) @ rotation.T + centre + rng.uniform(-0.05, 0.05, 3), target


def _rigid_part(source, moved):
    """The rotation and translation that best map ``source`` onto ``moved`` (scipy's Kabsch)."""
    rotation, _ = Rotation.align_vectors(moved - moved.mean(axis=0), source - source.mean(axis=0))
    rotation = rotation.as_matrix()
    return rotation, moved.mean(axis=0) - rotation @ source.mean(axis=0)


# (seed, n_source, n_target, w, max_iter, whether pycpd stops by its tolerance before max_iter)
CASES = {
    "early stop": (3, 200, 200, 0.0, 150, True),
    "early stop near the tolerance": (1, 200, 200, 0.0, 150, True),  # pycpd's last change is 0.997e-9
    "iteration cap": (7, 200, 200, 0.0, 150, False),
    "short cap": (0, 200, 200, 0.0, 20, False),
    "outliers, more target points": (1, 180, 240, 0.1, 150, True),
    "outliers, more source points": (2, 240, 180, 0.2, 150, True),
}


@pytest.mark.parametrize("case", CASES.values(), ids=CASES.keys())
def test_cpd_follows_pycpd_iteration_by_iteration(bunny_res4, case):
    seed, n_source, n_target, w, max_iter, stops_early = case
    source, target = _problem(np.asarray(bunny_res4.vertices), seed, n_source, n_target)
    reference = RigidRegistration(X=target, Y=source, max_iterations=max_iter, tolerance=1e-9, w=w)
    expected_q = []
    moved, _ = reference.register(lambda iteration, error, X, Y: expected_q.append(error))
    assert (reference.iteration < max_iter) == stops_early  # the case covers what its name says

    seen_q = []
    result = register_cpd(source, target, max_iter=max_iter, tol=1e-9, w=w,
                          callback=lambda iteration, registration: seen_q.append(registration.objective))
    rotation, translation = _rigid_part(source, moved)
    assert result.iterations == reference.iteration == len(seen_q)
    assert result.converged == (reference.diff <= 1e-9)
    np.testing.assert_allclose(seen_q, expected_q, rtol=1e-9)
    np.testing.assert_allclose(result.rotation, rotation, rtol=0, atol=1e-9)
    np.testing.assert_allclose(result.translation, translation, rtol=0, atol=1e-9)


def test_cpd_rejects_bad_options():
    points = np.random.default_rng(0).normal(size=(10, 3))
    for options, word in (({"w": 1.0}, "w must"), ({"w": -0.1}, "w must"), ({"max_iter": 0}, "max_iter"),
                          ({"tol": -1.0}, "tol")):
        with pytest.raises(InputError, match=word):
            register_cpd(points, points, **options)
