"""The job server runs scripts in forks of a preloaded process, with their streams, exit codes and signals."""
import csv
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from dgmm.runtime.job_server import ADDRESS_VARIABLE, JobServer, script_imports
from tests.workflow import run_snakemake

HAND_OVER = "from dgmm.runtime.job_server import hand_over\nhand_over()\n"
# A job that waits a minute in short sleeps: a Python signal handler runs between bytecodes, so one that lands just
# before a single long sleep would wait out the minute (a race of the test's job, not of the server).
WAIT = "for _ in range(6000):\n    time.sleep(0.01)\n"


@pytest.fixture
def server(tmp_path, monkeypatch):
    """A server preloading ``probe``, a module that records which process imported it."""
    (tmp_path / "probe.py").write_text("import os\nIMPORTED_BY = os.getpid()\n")
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    monkeypatch.chdir(tmp_path)
    # The server and its forks inherit this process's signal dispositions: under `nohup make test` SIGHUP would be
    # ignored there, and the tests that send it could not see it act. Default while the server starts.
    hangup = signal.signal(signal.SIGHUP, signal.SIG_DFL)
    try:
        server = JobServer(["probe"]).start()
    finally:
        signal.signal(signal.SIGHUP, hangup)
    yield server
    server.stop()


def script(tmp_path, name, body):
    path = tmp_path / name
    path.write_text(HAND_OVER + body)
    return str(path)


def alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def test_a_script_runs_in_a_fork_of_the_server_with_its_modules_loaded(server, tmp_path):
    job = script(tmp_path, "job.py", "import os, sys, probe\n"
                                     "print(os.getppid(), probe.IMPORTED_BY, os.getcwd(), os.environ['PROBE'],\n"
                                     "      sys.argv[1:])\n"
                                     "print('to stderr', file=sys.stderr)\n")
    (tmp_path / "work").mkdir()
    run = subprocess.run([sys.executable, job, "--flag", "value"], cwd=tmp_path / "work",
                         env={**os.environ, "PROBE": "x"}, capture_output=True, text=True, timeout=60)
    parent, imported_by, cwd, probe, arguments = run.stdout.split(maxsplit=4)
    assert run.returncode == 0 and run.stderr == "to stderr\n"
    assert int(parent) == int(imported_by) == server._process.pid  # forked from the server, module from before
    assert (cwd, probe, arguments) == (str(tmp_path / "work"), "x", "['--flag', 'value']\n")


def test_without_a_server_the_script_runs_in_its_own_process(tmp_path, monkeypatch):
    """... with the signal handling it had: hand_over's handlers and wakeup socket are undone."""
    (tmp_path / "probe.py").write_text("import os\nIMPORTED_BY = os.getpid()\n")
    job = script(tmp_path, "job.py", "import os, probe, signal\nprint(os.getpid() == probe.IMPORTED_BY,"
                                     " signal.getsignal(signal.SIGTERM) is signal.SIG_DFL, signal.set_wakeup_fd(-1))\n")
    env = {**os.environ, "PYTHONPATH": str(tmp_path), ADDRESS_VARIABLE: str(tmp_path / "no-such-socket")}
    run = subprocess.run([sys.executable, job], env=env, capture_output=True, text=True, timeout=60)
    assert (run.returncode, run.stdout) == (0, "True True -1\n")


@pytest.mark.parametrize("body, code, stderr", [
    ("raise ValueError('bad input')\n", 1, "ValueError: bad input\n"),
    ("import sys\nsys.exit(3)\n", 3, ""),
    ("import sys\nsys.exit('one line')\n", 1, "one line\n"),
    ("import sys\nsys.exit()\n", 0, ""),
])
def test_the_exit_status_and_error_are_the_script_s(server, tmp_path, body, code, stderr):
    """As Python itself: a traceback ending in the error, an exit message alone on stderr, silence otherwise."""
    run = subprocess.run([sys.executable, script(tmp_path, "job.py", body)], capture_output=True, text=True,
                         timeout=60)
    assert run.returncode == code
    if stderr:
        assert run.stderr.endswith(stderr)
    else:
        assert run.stderr == ""


@pytest.mark.parametrize("how", ["interrupt", "kill"])
def test_stopping_the_script_stops_its_fork(server, tmp_path, how):
    job = script(tmp_path, "job.py", "import os, time\nprint(os.getpid(), flush=True)\n" + WAIT)
    client = subprocess.Popen([sys.executable, job], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    fork = int(client.stdout.readline())
    client.send_signal(signal.SIGINT if how == "interrupt" else signal.SIGKILL)
    code = client.wait(timeout=10)
    deadline = time.monotonic() + 5
    while alive(fork) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not alive(fork)
    if how == "interrupt":  # as Python itself: a KeyboardInterrupt traceback, then death by SIGINT
        assert code == -signal.SIGINT and "KeyboardInterrupt" in client.stderr.read()
    client.stderr.close()
    client.stdout.close()


def test_stop_removes_the_socket_and_unsets_the_address(server):
    address = os.environ[ADDRESS_VARIABLE]
    server.stop()
    assert ADDRESS_VARIABLE not in os.environ and not Path(address).parent.exists()


def test_script_imports_lists_absolute_imports_once_in_order(tmp_path):
    (tmp_path / "a.py").write_text('"""doc"""\nimport sys\nfrom dgmm.data import load_mesh\nfrom . import x\n')
    (tmp_path / "b.py").write_text("import numpy as np, sys\nfrom dgmm.data import save_ply\n")
    assert script_imports([tmp_path / "a.py", tmp_path / "b.py"]) == ["sys", "dgmm.data", "numpy"]


def started_job(tmp_path, body, name="job.py", setup=""):
    """Start a job script that runs ``setup``, prints its pid, then runs ``body``; returns (client, fork pid)."""
    job = script(tmp_path, name, "import os, signal, sys, time\n" + setup + "print(os.getpid(), flush=True)\n" + body)
    client = subprocess.Popen([sys.executable, job], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    return client, int(client.stdout.readline())


def finish(client, timeout=10):
    """Wait for a client; return (exit status, rest of stdout, stderr), read once its fork has closed them too."""
    code = client.wait(timeout=timeout)
    with client.stdout, client.stderr:
        return code, client.stdout.read(), client.stderr.read()


def wait_dead(pid, seconds=5):
    deadline = time.monotonic() + seconds
    while alive(pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    return not alive(pid)


@pytest.mark.parametrize("number", [signal.SIGTERM, signal.SIGHUP])
def test_termination_signals_reach_the_fork_as_themselves(server, tmp_path, number):
    """Snakemake cancels a job with SIGTERM (a closed terminal sends SIGHUP): the fork must get that very signal.
    Its handler here prints the number and exits 7, which must be the client's status. Without forwarding, the
    client dies of the signal itself (status -n) and the server's fallback sends the fork SIGTERM (tried)."""
    client, fork = started_job(tmp_path, WAIT, setup="signal.signal(signal.%s, lambda n, f: "
                               "(print('got', n), sys.exit(7)))\n" % signal.Signals(number).name)
    client.send_signal(number)
    code, out, _ = finish(client)
    assert (code, out) == (7, f"got {int(number)}\n")
    assert wait_dead(fork)


@pytest.mark.parametrize("number", [signal.SIGTERM, signal.SIGHUP])
def test_a_job_killed_by_a_termination_signal_kills_its_client_with_it(server, tmp_path, number):
    client, fork = started_job(tmp_path, WAIT)
    client.send_signal(number)
    code, _, _ = finish(client)
    assert code == -number
    assert wait_dead(fork)


def test_a_server_that_dies_under_a_job_fails_the_job_and_ends_the_fork(server, tmp_path):
    """The job did not finish, so its client must fail (status 1), never succeed; and the fork, orphaned, must not
    go on writing the job's outputs after Snakemake has counted it failed."""
    client, fork = started_job(tmp_path, WAIT)
    server._process.kill()
    assert client.wait(timeout=10) == 1
    assert wait_dead(fork)
    finish(client)  # closes the pipes


def test_two_jobs_run_at_once_each_with_its_own_streams_and_status(server, tmp_path):
    """Job A waits for a file that job B writes, so they must run concurrently; each client gets its own output and
    exit status (a server that ran jobs one at a time, or mixed up their connections, fails)."""
    flag = tmp_path / "b-started"
    a, _ = started_job(tmp_path, f"import pathlib\nflag = pathlib.Path({str(flag)!r})\n"
                                 "deadline = time.monotonic() + 20\n"
                                 "while not flag.exists() and time.monotonic() < deadline:\n    time.sleep(0.01)\n"
                                 "print('a saw b' if flag.exists() else 'a alone')\nsys.exit(3)\n", "a.py")
    b, _ = started_job(tmp_path, f"import pathlib\npathlib.Path({str(flag)!r}).touch()\nprint('b done')\n"
                                 "sys.exit(4)\n", "b.py")
    assert finish(b, 30)[:2] == (4, "b done\n")
    assert finish(a, 30)[:2] == (3, "a saw b\n")


def test_jobs_run_with_one_blas_thread_whatever_their_environment(server, tmp_path):
    """The server imports numpy with BLAS and OpenMP at one thread, as a one-thread job has them; its forks keep
    that pool even when the client's environment asks for nothing (a server started without the one-thread
    environment gives the machine's core count on a multi-core machine: tried on 2 cores)."""
    server.stop()
    (tmp_path / "probe.py").write_text("import numpy\n")
    server = JobServer(["probe", "threadpoolctl"]).start()
    try:
        env = {name: value for name, value in os.environ.items() if not name.endswith("_NUM_THREADS")}
        job = script(tmp_path, "threads.py", "from threadpoolctl import threadpool_info\n"
                                             "print(sorted({p['num_threads'] for p in threadpool_info()"
                                             " if p['user_api'] == 'blas'}))\n")
        run = subprocess.run([sys.executable, job], env=env, capture_output=True, text=True, timeout=60)
        assert (run.returncode, run.stdout) == (0, "[1]\n"), run.stderr
    finally:
        server.stop()


def test_a_preloaded_function_runs_once_in_the_server_before_its_jobs(server, tmp_path):
    """``"module:function"`` imports the module and calls the function in the server: its forks inherit what it
    loaded (the sweep loads P2D's compiled kernels so)."""
    server.stop()
    (tmp_path / "probe.py").write_text("import os\nLOADED_BY = []\n\ndef load():\n    LOADED_BY.append(os.getpid())\n")
    server = JobServer(["probe:load"]).start()
    try:
        job = script(tmp_path, "loaded.py", "import probe\nprint(probe.LOADED_BY)\n")
        runs = [subprocess.run([sys.executable, job], capture_output=True, text=True, timeout=60) for _ in range(2)]
        assert [(run.returncode, run.stdout) for run in runs] == [(0, f"[{server._process.pid}]\n")] * 2
    finally:
        server.stop()


@pytest.mark.slow  # two real Snakemake runs of one data job
def test_job_server_false_runs_each_job_in_its_own_process_with_the_same_bytes(tmp_path):
    """`job_server: false` (a profile or `--config` setting) starts no server: the job's own process imports its
    libraries (several times the CPU in its benchmark of the client that hands a job to the server), and writes the
    bytes the server's fork writes."""
    target = "results/data/bunny/res4.ply"
    served = run_snakemake(tmp_path / "served", target)
    plain = run_snakemake(tmp_path / "plain", target, "--config", "job_server=False")
    assert served.returncode == 0 and plain.returncode == 0, (served.stderr + plain.stderr)[-3000:]
    assert (tmp_path / "served" / target).read_bytes() == (tmp_path / "plain" / target).read_bytes()
    cpu = {}
    for run in ("served", "plain"):
        with open(tmp_path / run / "results/benchmarks/data_mesh/bunny/res4.tsv", newline="") as benchmark:
            cpu[run] = float(next(csv.DictReader(benchmark, delimiter="\t"))["cpu_time"])
    assert cpu["plain"] > 3 * cpu["served"], cpu  # here 0.76 against 0.10 s: the imports the server had made
