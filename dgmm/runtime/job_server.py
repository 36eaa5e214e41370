"""A job server: scripts run in forks of one Python process that has already imported the libraries they need.

A cold sweep runs hundreds of jobs of a second's work each, and each used to spend about two more seconds
starting Python and importing scikit-learn, trimesh, rerun and this library. One :class:`JobServer` per sweep
(the Snakefile starts it) imports them once; a job script that calls :func:`hand_over` first sends the server
its command line, working directory, environment and standard streams, and waits. The server forks, the fork
runs the script from the top (its imports are already loaded, and ``hand_over`` returns at once there), and
the fork's exit status becomes the script's. A signal to the waiting script (Ctrl-C, Snakemake cancelling the
job) goes on to the fork, a script that dies kills its fork, and a server that dies under a job fails the job
and ends its fork. Without a server (a script run by hand, a cluster node) ``hand_over`` returns and the job
runs where it is. The fork runs the same interpreter and libraries on the same inputs, so results are bit for
bit those of a fresh process.

The server computes next to nothing: a fork of a process whose thread pools (OpenMP, BLAS) have run would inherit
them broken, so it imports, with BLAS and OpenMP at one thread as a one-thread job has them, and runs only the
preload's functions (the sweep's: one tiny P2D registration that loads numba's compiled kernels, and threadpoolctl's
scan of the loaded libraries, which reads their thread counts; neither starts a thread).
"""
from __future__ import annotations

import ast
import atexit
import importlib
import json
import os
import runpy
import select
import selectors
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import traceback

ADDRESS_VARIABLE = "DGMM_JOB_SERVER"
"""Environment variable holding the server's socket path; jobs started under it hand over to the server."""
ONE_THREAD = {name: "1" for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
_FORWARDED = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


def hand_over():
    """Run the calling job script in the server named by ``$DGMM_JOB_SERVER`` and exit with its status; return
    at once (the caller goes on itself) when there is no server, or in the server's fork (whose environment
    names none)."""
    address = os.environ.get(ADDRESS_VARIABLE)
    if not address:
        return
    connection = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    request = dict(argv=[os.path.abspath(sys.argv[0]), *sys.argv[1:]], cwd=os.getcwd(), env=dict(os.environ))
    # Signals are caught from before the request and written to a wakeup socket, which the wait for the job's end
    # watches beside the connection. Forwarding them from a handler would lose a race: a handler runs between
    # bytecodes, so a signal landing just before a blocking recv would wait for the very job it was meant to end.
    wakeup, woken = socket.socketpair()
    wakeup.setblocking(False)
    woken.setblocking(False)
    handlers = {number: signal.signal(number, lambda number, frame: None) for number in _FORWARDED}
    previous_wakeup = signal.set_wakeup_fd(woken.fileno(), warn_on_full_buffer=False)
    try:
        connection.connect(address)
        socket.send_fds(connection, [json.dumps(request).encode()], [0, 1, 2])
        pid = int(connection.recv(32))  # b"" (no fork made): ValueError
    except (OSError, ValueError):  # no server here: nothing ran, so run the job in this process
        signal.set_wakeup_fd(previous_wakeup)
        for number, handler in handlers.items():
            signal.signal(number, handler)
        pending = _received(wakeup)
        for sock in (connection, wakeup, woken):
            sock.close()
        for number in pending:
            os.kill(os.getpid(), number)
        return
    reply = None
    while reply is None:
        readable, _, _ = select.select([connection, wakeup], [], [])
        for number in _received(wakeup):
            _signal(pid, number)
        if connection in readable:
            reply = connection.recv(32)
    if not reply:  # the server died under the job: fail it, and stop its orphaned fork from writing on
        _signal(pid, signal.SIGTERM)
    code = int(reply) if reply else 1
    if code < 0:  # the fork died of a signal: die of it too, as the script itself would have
        signal.signal(-code, signal.SIG_DFL)
        os.kill(os.getpid(), -code)
    sys.exit(code)


def _received(wakeup):
    """The signal numbers waiting in the non-blocking socket ``wakeup``, in order of arrival (a byte each)."""
    numbers = []
    try:
        while True:
            numbers.extend(wakeup.recv(64))
    except BlockingIOError:
        return numbers


def _signal(pid, number):
    try:
        os.kill(pid, number)
    except ProcessLookupError:  # the fork has just exited; its status is on its way
        pass


def script_imports(paths):
    """Top-level modules imported by the Python scripts ``paths``, in order of first appearance."""
    names = {}
    for path in paths:
        with open(path) as source:
            for node in ast.parse(source.read(), path).body:
                if isinstance(node, ast.Import):
                    names.update(dict.fromkeys(alias.name for alias in node.names))
                elif isinstance(node, ast.ImportFrom) and node.level == 0:
                    names[node.module] = None
    return list(names)


class JobServer:
    """A server process for :func:`hand_over`, alive between :meth:`start` and :meth:`stop`.

    Parameters
    ----------
    preload : list of str
        Modules the server imports for its forks; ``"module:function"`` also calls ``function()`` of the module once
        imported (loading compiled code, say, that every fork would otherwise load for itself).
    """

    def __init__(self, preload):
        self.preload = list(preload)
        self._process = None

    def start(self):
        """Start the server and point this process's environment (so every job started from here) at it."""
        self._directory = tempfile.mkdtemp(prefix="dgmm-jobs-")
        address = os.path.join(self._directory, "socket")
        self._process = subprocess.Popen([sys.executable, "-m", __name__, address, *self.preload],
                                         env={**os.environ, **ONE_THREAD}, stdin=subprocess.DEVNULL,
                                         start_new_session=True)
        while not os.path.exists(address) and self._process.poll() is None:
            time.sleep(0.01)  # the server listens before it imports: milliseconds
        if self._process.poll() is None:
            os.environ[ADDRESS_VARIABLE] = address
        return self

    def stop(self):
        """Stop the server; jobs started afterwards run in their own process."""
        os.environ.pop(ADDRESS_VARIABLE, None)
        if self._process is not None:
            self._process.terminate()
            self._process.wait()
            shutil.rmtree(self._directory, ignore_errors=True)
            self._process = None


def serve(address, preload):
    """Listen on ``address``, import ``preload``, then fork one child per request until the parent exits."""
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    listener.bind(address)
    listener.listen(64)  # requests queue here while the imports run
    for name in preload:
        module, _, function = name.partition(":")
        loaded = importlib.import_module(module)
        if function:
            getattr(loaded, function)()
    parent = os.getppid()
    selector = selectors.DefaultSelector()
    selector.register(listener, selectors.EVENT_READ)
    while os.getppid() == parent:
        for key, _ in selector.select(timeout=1.0):
            if key.fileobj is listener:
                _fork_job(listener, selector)
            elif key.data[0] == "exited":
                _report_exit(selector, key.fileobj, *key.data[1:])
            else:  # the client closed its end: its job was cancelled
                selector.unregister(key.fileobj)
                _signal(key.data[1], signal.SIGTERM)
    shutil.rmtree(os.path.dirname(address), ignore_errors=True)  # the parent died without stopping us


def _fork_job(listener, selector):
    """Accept one request and fork its job; watch the child's exit and the client's connection."""
    connection, _ = listener.accept()
    message, fds, _, _ = socket.recv_fds(connection, 1 << 20, 3)
    if len(fds) != 3:
        connection.close()
        return
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:
        inherited = {listener.fileno(), selector.fileno(), connection.fileno()}
        inherited.update(key.fd for key in selector.get_map().values())
        _run_job(json.loads(message), fds, inherited)
    for fd in fds:
        os.close(fd)
    exit_watch = os.pidfd_open(pid)
    selector.register(exit_watch, selectors.EVENT_READ, ("exited", connection, pid))
    selector.register(connection, selectors.EVENT_READ, ("client", pid))
    connection.send(str(pid).encode())


def _report_exit(selector, exit_watch, connection, pid):
    """Reap the child ``pid`` and send its exit code to its client, if the client still listens."""
    _, status = os.waitpid(pid, 0)
    selector.unregister(exit_watch)
    os.close(exit_watch)
    if connection in selector.get_map():  # not if the client has closed its end already
        selector.unregister(connection)
    try:
        connection.send(str(os.waitstatus_to_exitcode(status)).encode())
    except OSError:
        pass
    connection.close()


def _run_job(request, fds, inherited):
    """In the fork: become the client's process (streams, directory, environment), run its script, exit. Never
    returns: whatever happens, the fork ends here and not in the server's loop."""
    code, interrupted = 1, False
    try:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        for fd in inherited:
            os.close(fd)
        for target, fd in enumerate(fds):
            os.dup2(fd, target)
            os.close(fd)
        os.chdir(request["cwd"])
        os.environ.clear()
        os.environ.update(request["env"])
        del os.environ[ADDRESS_VARIABLE]  # so that the script's own hand_over returns
        sys.argv = request["argv"]
        runpy.run_path(sys.argv[0], run_name="__main__")
        code = 0
    except SystemExit as exit_:
        code = exit_.code if isinstance(exit_.code, int) else 0 if exit_.code is None else 1
        if not isinstance(exit_.code, (int, type(None))):
            print(exit_.code, file=sys.stderr)
    except KeyboardInterrupt:
        traceback.print_exc()
        interrupted = True
    except BaseException:
        traceback.print_exc()
    finally:
        atexit._run_exitfuncs()  # what interpreter shutdown would run: logging, recorders' flushes
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                pass
        if interrupted:  # die of the interrupt, as Python does
            signal.signal(signal.SIGINT, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGINT)
        os._exit(code)


if __name__ == "__main__":
    serve(sys.argv[1], sys.argv[2:])
