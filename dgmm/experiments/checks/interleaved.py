"""Interleaved repeats: how every timing check times its settings (:mod:`~dgmm.experiments.checks.timing`).

A check has settings (the ways of doing one thing that a claim compares) and cases (one per repeat: a trial, a
frame pair, or the same input again). Each repeat runs every setting on its case back to back, so that the settings
of one repeat see the same machine load and their ratio is one paired sample; the order is reversed from one repeat
to the next, so that a setting is not always the first (cold caches) or the last, and a drift of the load over a
pair of repeats hits every setting alike. Only the settings' calls are timed, in CPU seconds of this process
(``time.process_time``, one thread): building a case and describing a result are not.
"""
import time

COLUMNS = ("check", "setting", "repeat", "seconds", "iterations", "detail")
"""Columns of a timing table: ``iterations`` is blank where a setting has none (a decimation), ``detail`` says
what the setting produced (an error, a size)."""


def setting_order(settings, repeat):
    """The settings in their given order on even repeats, reversed on odd ones."""
    names = list(settings)
    return names if repeat % 2 == 0 else names[::-1]


def interleaved_times(check, cases, settings, describe):
    """Time every setting on every case, one repeat per case, in alternating order (module docstring).

    Parameters
    ----------
    check : str
        The ``check`` column of the rows.
    cases : iterable
        One case per repeat, each built (untimed) just before its repeat runs.
    settings : dict of str to callable
        ``setting -> run(case) -> result``; only these calls are timed.
    describe : callable
        ``describe(case, setting, result) -> (iterations, detail)`` for the row (untimed).

    Returns
    -------
    list of dict
        One per (repeat, setting) with the keys of :data:`COLUMNS`, in the order they ran.
    """
    rows = []
    for repeat, case in enumerate(cases):
        for setting in setting_order(settings, repeat):
            start = time.process_time()
            result = settings[setting](case)
            seconds = time.process_time() - start
            iterations, detail = describe(case, setting, result)
            rows.append({"check": check, "setting": setting, "repeat": repeat, "seconds": seconds,
                         "iterations": iterations, "detail": detail})
    return rows
