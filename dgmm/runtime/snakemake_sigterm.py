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

import threading

from snakemake.scheduling.job_scheduler import JobScheduler

WRITTEN_AGAINST = ("9.27.1", "71dc8bb2df123d88a1b57e12b570ed27028d3465578c22207ad506cc3085ce0d")
"""The Snakemake release this workaround was written and tested against, and the sha256 of the source of its
``JobScheduler.exit_gracefully`` (``inspect.getsource``). pyproject.toml pins Snakemake to that release's minor
version; tests/test_snakemake_sigterm.py fails when the method changes or disappears, so that a new release is
looked at again (and the workaround dropped if the release no longer deadlocks)."""


def off_main_thread(handler):
    """``handler(scheduler, *args)`` started on a daemon thread, the signal handler returning at once."""
    def exit_gracefully(self, *args):
        threading.Thread(target=handler, args=(self, *args), name="snakemake-sigterm", daemon=True).start()

    exit_gracefully.wrapped = handler
    return exit_gracefully


def install():
    """Replace ``JobScheduler.exit_gracefully`` by :func:`off_main_thread` of it, once per process."""
    if not hasattr(JobScheduler.exit_gracefully, "wrapped"):
        JobScheduler.exit_gracefully = off_main_thread(JobScheduler.exit_gracefully)
