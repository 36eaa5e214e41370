"""A real single-node Slurm cluster for tests, with all of its state under one directory.

``python tests/slurm_cluster.py DIR`` writes a munge key and a ``slurm.conf`` into ``DIR``, starts ``munged``,
``slurmctld`` and ``slurmd`` (Debian's packages; no systemd, no accounting database) in the foreground as its own
children, waits until the node takes jobs, prints ``SLURM_CONF=DIR/slurm.conf`` and creates ``DIR/ready``. Clients
(``sbatch``, ``squeue``, Snakemake's SLURM executor) reach the cluster with that ``SLURM_CONF`` and ``DIR/bin``
first on ``PATH`` (an ``srun`` that finds the cluster from inside a job).

It then runs until SIGTERM or SIGINT, and on either kills every process of a job and stops the daemons: it is a
child subreaper, so job steps that Slurm detaches from ``slurmd`` stay its descendants and are killed by id.
Ports are picked free, so clusters of several test runs on one machine do not meet.
"""
import ctypes
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import psutil

SBIN = Path("/usr/sbin")
START_TIMEOUT = 60
STOP_TIMEOUT = 15
PR_SET_CHILD_SUBREAPER = 36

SLURM_CONF = """\
ClusterName=dgmmtest
SlurmctldHost={host}(127.0.0.1)
SlurmctldPort={ctld_port}
SlurmdPort={slurmd_port}
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={root}/munge/munge.socket
StateSaveLocation={root}/slurmctld
SlurmdSpoolDir={root}/slurmd
SlurmctldPidFile={root}/slurmctld.pid
SlurmdPidFile={root}/slurmd.pid
SlurmctldLogFile={root}/slurmctld.log
SlurmdLogFile={root}/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
MpiDefault=none
ReturnToService=2
# Finished jobs stay visible to squeue for 5 minutes: Snakemake's executor reads their final state there.
MinJobAge=300
KillWait=5
NodeName={host} NodeAddr=127.0.0.1 CPUs=2 RealMemory={memory_mb} State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
"""


def free_port():
    """A TCP port on the loopback interface that nothing listens on now.

    Returns
    -------
    int
        The port number.
    """
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def write_config(root):
    """Write the munge key and slurm.conf of a cluster rooted at ``root``.

    Parameters
    ----------
    root : Path
        The cluster's directory; created subdirectories hold each daemon's state.

    Returns
    -------
    Path
        The slurm.conf.
    """
    for name in ("munge", "slurmctld", "slurmd"):
        (root / name).mkdir(mode=0o700, parents=True, exist_ok=True)
    key = root / "munge" / "munge.key"
    key.write_bytes(os.urandom(1024))
    key.chmod(0o400)
    memory_mb = psutil.virtual_memory().total // 2**20  # what `slurmd -C` reports as RealMemory
    conf = root / "slurm.conf"
    conf.write_text(SLURM_CONF.format(host=socket.gethostname(), root=root, ctld_port=free_port(),
                                      slurmd_port=free_port(), memory_mb=memory_mb))
    # Inside a job, Snakemake's jobstep executor starts `srun` with every SLURM_* variable removed, SLURM_CONF too;
    # a real cluster's nodes have /etc/slurm/slurm.conf, ours is found through this wrapper, first on PATH.
    srun = root / "bin" / "srun"
    srun.parent.mkdir(exist_ok=True)
    srun.write_text(f'#!/bin/sh\nSLURM_CONF={conf} exec /usr/bin/srun "$@"\n')
    srun.chmod(0o755)
    return conf


def start_daemons(root, conf):
    """Start munged, slurmctld and slurmd in the foreground, logging to files under ``root``.

    Parameters
    ----------
    root : Path
        The cluster's directory.
    conf : Path
        Its slurm.conf.

    Returns
    -------
    list of subprocess.Popen
        The daemons, in start order.
    """
    munge = root / "munge"
    commands = [
        [SBIN / "munged", "--foreground", "--force", f"--socket={munge}/munge.socket", f"--key-file={munge}/munge.key",
         f"--pid-file={munge}/munged.pid", f"--log-file={munge}/munged.log", f"--seed-file={munge}/munged.seed"],
        [SBIN / "slurmctld", "-D", "-f", conf],
        [SBIN / "slurmd", "-D", "-f", conf],
    ]
    daemons = []
    for command in commands:
        with open(root / f"{Path(command[0]).name}.out", "w") as out:
            daemons.append(subprocess.Popen(command, stdout=out, stderr=subprocess.STDOUT))
        if command[0].name == "munged":
            wait_for(lambda: (munge / "munge.socket").exists(), daemons, "munged's socket")
    return daemons


def wait_for(ready, daemons, what):
    """Poll ``ready()`` until it is true; fail if a daemon exits or START_TIMEOUT passes.

    Parameters
    ----------
    ready : callable
        Returns True once the awaited state is reached.
    daemons : list of subprocess.Popen
        Daemons that must stay up meanwhile.
    what : str
        What is awaited, for the error message.
    """
    deadline = time.monotonic() + START_TIMEOUT
    while not ready():
        dead = [d.args[0] for d in daemons if d.poll() is not None]
        if dead or time.monotonic() > deadline:
            raise RuntimeError(f"Slurm test cluster: no {what} ({'exited: ' + str(dead) if dead else 'timed out'})")
        time.sleep(0.2)


def node_idle(env):
    """Whether the cluster's node is up and idle.

    Parameters
    ----------
    env : dict
        Environment with SLURM_CONF set.

    Returns
    -------
    bool
    """
    run = subprocess.run(["sinfo", "--noheader", "--format=%T"], env=env, capture_output=True, text=True, timeout=10)
    return run.returncode == 0 and run.stdout.strip() == "idle"


def reap(daemons):
    """Collect the exit status of job processes re-parented to this process and finished since.

    Parameters
    ----------
    daemons : list of subprocess.Popen
        The daemons, left to `subprocess` to collect.
    """
    daemon_pids = {d.pid for d in daemons}
    for child in psutil.Process().children():
        if child.pid not in daemon_pids and child.status() == psutil.STATUS_ZOMBIE:
            os.waitpid(child.pid, 0)


def stop(daemons):
    """Kill every job process by id, then terminate the daemons (SIGKILL after STOP_TIMEOUT).

    Parameters
    ----------
    daemons : list of subprocess.Popen
        The daemons started by `start_daemons`.
    """
    daemon_pids = {d.pid for d in daemons}
    for d in daemons:
        if d.args[0].name != "slurmd" and d.poll() is None:  # slurmctld's own helper process is not a job
            daemon_pids |= {p.pid for p in psutil.Process(d.pid).children(recursive=True)}
    for group in ([p for p in psutil.Process().children(recursive=True) if p.pid not in daemon_pids],
                  [psutil.Process(d.pid) for d in reversed(daemons) if d.poll() is None],
                  psutil.Process().children(recursive=True)):  # anything re-parented to us meanwhile
        for process in group:
            try:
                process.terminate() if process.pid in daemon_pids else process.kill()
            except psutil.NoSuchProcess:
                pass
        _, alive = psutil.wait_procs(group, timeout=STOP_TIMEOUT)
        for process in alive:
            process.kill()
        psutil.wait_procs(alive, timeout=STOP_TIMEOUT)


def main():
    """Run a cluster in ``sys.argv[1]`` until SIGTERM or SIGINT."""
    root = Path(sys.argv[1]).resolve()
    ctypes.CDLL(None, use_errno=True).prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0)
    stopping = []
    signal.signal(signal.SIGTERM, lambda *_: stopping.append(True))
    signal.signal(signal.SIGINT, lambda *_: stopping.append(True))
    conf = write_config(root)
    env = {**os.environ, "SLURM_CONF": str(conf)}
    daemons = start_daemons(root, conf)
    try:
        wait_for(lambda: stopping or node_idle(env), daemons, "idle node")
        print(f"SLURM_CONF={conf}", flush=True)
        (root / "ready").touch()
        while not stopping and all(d.poll() is None for d in daemons):
            reap(daemons)
            time.sleep(0.2)
    finally:
        stop(daemons)
    if not stopping:
        sys.exit(f"Slurm test cluster: a daemon exited; see the logs in {root}")


if __name__ == "__main__":
    main()
