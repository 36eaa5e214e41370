"""Snakemake's SIGTERM handler under dgmm.runtime.snakemake_sigterm: a kill that lands while the main thread holds the
scheduler's lock stops the run instead of hanging it. Real signals, in a child process (a hang cannot take the test
run with it)."""
import hashlib
import inspect
import subprocess
import sys
import textwrap
from importlib.metadata import version

from snakemake.scheduling.job_scheduler import JobScheduler

from dgmm.runtime.snakemake_sigterm import WRITTEN_AGAINST

# A scheduler with only what exit_gracefully touches; SIGTERM delivered to the main thread inside `with _lock`, where
# Snakemake's main loop records finished jobs.
_CHILD = textwrap.dedent("""
    import os, signal, sys, threading
    from snakemake.scheduling.job_scheduler import JobScheduler
    from dgmm.runtime.snakemake_sigterm import install
    install()
    install()  # a second Snakefile parse (e.g. a job re-reading it) wraps nothing twice
    assert not hasattr(JobScheduler.exit_gracefully.wrapped, "wrapped")
    scheduler = JobScheduler.__new__(JobScheduler)
    scheduler._lock, scheduler._open_jobs, scheduler._user_kill = threading.Lock(), threading.Semaphore(0), None
    signal.signal(signal.SIGTERM, scheduler.exit_gracefully)
    with scheduler._lock:
        os.kill(os.getpid(), signal.SIGTERM)
        signal.sigtimedwait([], 0.05)  # the handler runs here, the lock held
        assert scheduler._user_kill is None, "the handler ran on the main thread under the lock"
    assert scheduler._open_jobs.acquire(timeout=10), "the main loop would not wake"
    assert scheduler._user_kill == "graceful"
    print("stopped")
""")


def test_sigterm_under_the_scheduler_lock_stops_the_run():
    # Without the workaround the child blocks on its own lock and the run times out.
    result = subprocess.run([sys.executable, "-c", _CHILD], capture_output=True, text=True, timeout=30)
    assert result.returncode == 0 and result.stdout.strip() == "stopped", result.stderr[-2000:]


def test_the_patched_method_is_the_one_the_workaround_was_written_against():
    """A Snakemake whose exit_gracefully changed (or has none) fails here: look at the release again."""
    handler = getattr(JobScheduler.exit_gracefully, "wrapped", JobScheduler.exit_gracefully)
    source = hashlib.sha256(inspect.getsource(handler).encode()).hexdigest()
    assert source == WRITTEN_AGAINST[1], f"snakemake {version('snakemake')}: exit_gracefully changed"
    assert version("snakemake").rsplit(".", 1)[0] == WRITTEN_AGAINST[0].rsplit(".", 1)[0]
