"""Experimental per-frame schedules: the alternatives the studies measured the sweep's ``overlap`` against.

Not the sweep's (:data:`dgmm.odometry.frame_model.SCHEDULES` holds the library's); kept runnable by name, so that
the studies (``benchmarks/studies/odometry_schedules.py``, ``odometry_rotation_room.py``; the docs' Visual odometry
benchmarks) can be repeated: ``odometry.schedule``, ``dgmm odometry --schedule`` and ``run_odometry(schedule=...)``
take any name of :func:`schedule_named`.
"""
from dataclasses import replace

from dgmm.errors import InputError
from dgmm.odometry.frame_model import SCHEDULES, Schedule

_FAST = replace(SCHEDULES["overlap"], overlap_rounds=0, overlap_scales=(0.0,), cut_rounds=0)

STUDY_SCHEDULES = {
    "fast": _FAST,
    "common-view": replace(_FAST, overlap_rounds=2, overlap_scales=(0.25, 0.125, 0.0625, 0.03125, 0.0),
                           overlap_refits=2),
    "reference": Schedule(seed_sample=None, lloyd_iter=0, em_iter=25, solver="bfgs"),
}
"""``"fast"``: ``overlap``'s mixtures (k-means++ seeds from 1,024 primitives, 3 Lloyd and 2 EM iterations),
Gauss-Newton D2D of the whole mixtures (cheapest; under-measures lateral motion, slides under fast turns).
``"common-view"``: two overlap rounds at each of five widenings, then both frames refitted twice on the primitives
the other camera sees (robust where views change fastest, at about five times the CPU). ``"reference"``:
scikit-learn's k-means on every primitive, 25 EM iterations (the fitting experiments' count; the paper does not
state the odometry's) and the paper's BFGS: the code before the choice."""


def schedule_named(name):
    """The :class:`~dgmm.odometry.frame_model.Schedule` of ``name``, the library's or a study's, else an InputError."""
    schedules = {**SCHEDULES, **STUDY_SCHEDULES}
    if name not in schedules:
        raise InputError(f"schedule must be one of {sorted(schedules)} or a Schedule, got {name!r}")
    return schedules[name]
