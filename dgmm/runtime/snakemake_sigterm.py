"""Snakemake's SIGTERM handler made safe at any moment (a workaround the Snakefile installs).

Snakemake's ``JobScheduler.exit_gracefully``, its SIGTERM handler (``kill``), takes the scheduler's
``threading.Lock``. Python runs a signal handler on the main thread between two bytecodes, and the main thread holds
that lock while it records finished jobs: a ``kill`` that lands there blocks the handler on a lock its own thread
holds, and Snakemake hangs for good (snakemake 9.27.1; seen in ``tests/test_fit_workflow.py``'s interrupted sweep,
whose jobs finish every few hundred milliseconds). :func:`install` makes the handler run Snakemake's own on a helper
thread, which takes the lock once the main thread lets go of it: the same graceful stop, without the deadlock
(``benchmarks/studies/sigterm_stress.py`` aims SIGTERMs at that moment and counts the runs that hang).
"""
from __future__ import annotations

import importlib
import threading

_SCHEDULER_MODULES = ("snakemake.scheduling.job_scheduler", "snakemake.scheduler")  # Snakemake 9, 8


def off_main_thread(handler):
    """``handler(scheduler, *args)`` started on a daemon thread, the signal handler returning at once."""
    def exit_gracefully(self, *args):
        threading.Thread(target=handler, args=(self, *args), name="snakemake-sigterm", daemon=True).start()

    exit_gracefully.wrapped = handler
    return exit_gracefully


def install():
    """Replace ``JobScheduler.exit_gracefully`` by :func:`off_main_thread` of it, once per process; nothing if this
    Snakemake has no such handler."""
    for name in _SCHEDULER_MODULES:
        try:
            scheduler = importlib.import_module(name).JobScheduler
        except (ImportError, AttributeError):
            continue
        handler = getattr(scheduler, "exit_gracefully", None)
        if handler is not None and not hasattr(handler, "wrapped"):
            scheduler.exit_gracefully = off_main_thread(handler)
        return
