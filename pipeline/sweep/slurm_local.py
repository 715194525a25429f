"""A real single-node SLURM on this machine, to try gyrolab's SLURM routes before a cluster (``python -m
gyrolab.sweep.slurm_local start|status|stop``; docs/cluster.md, "A SLURM on your own machine").

A process killed before its ``stop()`` leaves daemons behind: each state directory records the pid that started it
(``owner``), and the next ``start()`` ends the processes of every directory whose owner is gone. No cgroups (a
container rarely delegates a writable cgroup tree): processes are tracked by parentage, and the node's CPUs and
memory are taken as configured (``SlurmdParameters=config_overrides``), since a container's quota is not the hardware's.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from gyrolab.output.trust import proc_number
from gyrolab.sweep.orphans import alive  # a zombie (dead, not reaped) counts as dead

PACKAGES = ("slurm-wlm", "munge")
#: the programs the cluster needs; any missing one means the packages are installed first
PROGRAMS = ("munged", "slurmctld", "slurmd", "sinfo", "sbatch", "squeue", "scancel")
PREFIX = "gyrolab-slurm-"
PARTITION = "debug"
#: memory left to the operating system and the test process (MiB)
MEMORY_MARGIN_MIB = 1024
#: a Unix socket's path (sockaddr_un.sun_path) holds at most 107 bytes and the terminating NUL
SOCKET_PATH_MAX = 108
#: seconds for apt-get (nine packages, about 4 MB) and for the node to become idle
INSTALL_TIMEOUT = 300
START_TIMEOUT = 60
NOT_ROOT = ("a local SLURM needs root (it installs slurm-wlm and munge with apt-get when missing and starts "
            "munged, slurmctld and slurmd as root)")


class Unavailable(RuntimeError):
    """SLURM cannot run here (not root, no apt-get, the install failed); the tests skip with this reason."""


#: the file in a state directory that marks a cluster the command line started (``stop`` ends only those)
HELD = "held-by-command-line"
NONE_RUNNING = "slurm_local: no cluster started by 'python -m gyrolab.sweep.slurm_local start' is running"


@dataclass
class Cluster:
    """A started cluster: its state directory, config file, partition and daemon processes."""

    directory: Path
    conf: Path
    partition: str
    node: str
    processes: dict[str, subprocess.Popen] = field(default_factory=dict)
    install_seconds: float = 0.0
    start_seconds: float = 0.0
    previous_conf: str | None = None   # SLURM_CONF before start(), restored by stop()

    def env(self) -> dict[str, str]:
        """The environment for a SLURM client (sbatch, sinfo, …) of this cluster."""
        return {**os.environ, "SLURM_CONF": str(self.conf)}

    def run(self, *command: str, timeout: float = 30) -> str:
        return subprocess.run(command, env=self.env(), capture_output=True, text=True, check=True,
                              timeout=timeout).stdout

    def node_state(self) -> str:
        try:
            return self.run("sinfo", "-h", "-N", "-n", self.node, "-o", "%T", timeout=10).strip()
        except (subprocess.SubprocessError, OSError):
            return ""

    def logs(self) -> str:
        """The tail of each daemon's log, for a failure message."""
        parts = []
        for name in ("munged.stdout", "munged.log", "slurmctld.stdout", "slurmctld.log", "slurmd.stdout", "slurmd.log"):
            path = self.directory / name
            if path.is_file():
                lines = path.read_text(errors="replace").splitlines()[-15:]
                if lines:
                    parts.append(f"--- {name}\n" + "\n".join(lines))
        return "\n".join(parts)

    def stop(self) -> None:
        """Cancel every job, stop the daemons, end whatever process still belongs to the cluster."""
        with contextlib.suppress(subprocess.SubprocessError, OSError):
            self.run("scancel", "--full", "--user", str(os.getuid()), timeout=10)
            deadline = time.monotonic() + 15
            while self.run("squeue", "-h", "-o", "%i", timeout=10).strip() and time.monotonic() < deadline:
                time.sleep(0.5)
        for name in ("slurmd", "slurmctld", "munged"):   # clients of munged first
            process = self.processes.get(name)
            if process is not None and process.poll() is None:
                process.terminate()
                try:
                    process.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    process.kill()
                    process.wait(timeout=10)
        _kill_processes_naming(self.directory)   # slurmstepd and job steps left behind
        shutil.rmtree(self.directory, ignore_errors=True)
        if os.environ.get("SLURM_CONF") == str(self.conf):
            if self.previous_conf is None:
                del os.environ["SLURM_CONF"]
            else:
                os.environ["SLURM_CONF"] = self.previous_conf


def start(base: Path | None = None) -> Cluster:
    """Install (if needed) and start a single-node cluster; ``Unavailable`` when it cannot run here."""
    if os.geteuid() != 0:
        raise Unavailable(NOT_ROOT)
    install_seconds = install()
    base = Path(base or tempfile.gettempdir())
    clean_leftovers(base)
    began = time.monotonic()
    directory = Path(tempfile.mkdtemp(prefix=PREFIX, dir=base))
    if len(str(directory / "munge.socket")) >= SOCKET_PATH_MAX:
        shutil.rmtree(directory)
        raise ValueError(f"{directory} is too long a path for munged's socket (at most {SOCKET_PATH_MAX - 1} "
                         "bytes in all); start the cluster under a shorter directory")
    (directory / "owner").write_text(str(os.getpid()))
    node = socket.gethostname().split(".")[0]
    conf = directory / "slurm.conf"
    cluster = Cluster(directory, conf, PARTITION, node, install_seconds=install_seconds)
    try:
        with os.fdopen(os.open(directory / "munge.key", os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600), "wb") as key:
            key.write(os.urandom(1024))
        conf.write_text(slurm_conf(directory, node))
        for sub in ("ctld", "spool"):
            (directory / sub).mkdir()
        cluster.processes["munged"] = _daemon(
            cluster, "munged", "--foreground", "--force", f"--socket={directory / 'munge.socket'}",
            f"--key-file={directory / 'munge.key'}", f"--pid-file={directory / 'munged.pid'}",
            f"--log-file={directory / 'munged.log'}", f"--seed-file={directory / 'munged.seed'}")
        _wait_for(lambda: (directory / "munge.socket").exists(), cluster, "munged to open its socket")
        cluster.processes["slurmctld"] = _daemon(cluster, "slurmctld", "-D", "-i", "-f", str(conf))
        cluster.processes["slurmd"] = _daemon(cluster, "slurmd", "-D", "-f", str(conf), "-N", node)
        _wait_for(lambda: cluster.node_state() == "idle", cluster, f"node {node} to be idle in sinfo")
    except BaseException:
        cluster.stop()
        raise
    cluster.previous_conf = os.environ.get("SLURM_CONF")
    os.environ["SLURM_CONF"] = str(conf)
    cluster.start_seconds = time.monotonic() - began
    return cluster


def install() -> float:
    """apt-get the packages (``start`` checks for root) unless their programs are all there; seconds it took."""
    if all(shutil.which(program, path=_sbin_path()) for program in PROGRAMS):
        return 0.0
    if shutil.which("apt-get") is None:
        raise Unavailable("a local SLURM needs apt-get to install slurm-wlm and munge (Debian or Ubuntu)")
    began = time.monotonic()
    # on a machine with systemd the packages start their services: munged on its default socket and key, and
    # slurmctld/slurmd not at all without /etc/slurm/slurm.conf; this cluster uses none of them
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    command = ["apt-get", "install", "-y", "-q", "--no-install-recommends", *PACKAGES]
    try:
        result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=INSTALL_TIMEOUT)
        if result.returncode != 0:   # a fresh machine may not have the package lists yet
            update = subprocess.run(["apt-get", "update", "-q"], env=env, capture_output=True, text=True,
                                    timeout=INSTALL_TIMEOUT)
            if update.returncode == 0:
                result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=INSTALL_TIMEOUT)
    except subprocess.TimeoutExpired as expired:
        raise Unavailable(f"apt-get did not finish within {INSTALL_TIMEOUT} s ({' '.join(expired.cmd)})") from None
    if result.returncode != 0:
        last = (result.stderr or result.stdout).strip().splitlines()[-1:] or ["no output"]
        raise Unavailable(f"apt-get install {' '.join(PACKAGES)} failed: {last[0]}")
    os.environ["PATH"] = _sbin_path()
    return time.monotonic() - began


def slurm_conf(directory: Path, node: str) -> str:
    """A minimal slurm.conf for one node, this host, everything under ``directory``."""
    controller_port, node_port = _free_ports(2)
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    memory = max(512, (proc_number("/proc/meminfo", "MemTotal:") or 2048 * 1024) // 1024 - MEMORY_MARGIN_MIB)
    return f"""\
# written by gyrolab.sweep.slurm_local for one cluster
ClusterName=gyrolabtest
SlurmctldHost={node}(127.0.0.1)
SlurmctldPort={controller_port}
SlurmdPort={node_port}
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={directory / 'munge.socket'}
StateSaveLocation={directory / 'ctld'}
SlurmdSpoolDir={directory / 'spool'}
SlurmctldPidFile={directory / 'slurmctld.pid'}
SlurmdPidFile={directory / 'slurmd.pid'}
SlurmctldLogFile={directory / 'slurmctld.log'}
SlurmdLogFile={directory / 'slurmd.log'}
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
SlurmdParameters=config_overrides
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=30
KillWait=5
NodeName={node} NodeAddr=127.0.0.1 CPUs={cpus} RealMemory={memory} State=UNKNOWN
PartitionName={PARTITION} Nodes={node} Default=YES MaxTime=INFINITE State=UP
"""


def clean_leftovers(base: Path) -> None:
    """End the processes of, and remove, every cluster directory whose starting process is gone."""
    for directory in base.glob(PREFIX + "*"):
        owner = _pid_in(directory / "owner")
        if owner is not None and alive(owner):
            continue
        if owner is None and _age(directory) < 60:   # another session is creating it right now
            continue
        _kill_processes_naming(directory)
        shutil.rmtree(directory, ignore_errors=True)


def _daemon(cluster: Cluster, program: str, *args: str) -> subprocess.Popen:
    log = open(cluster.directory / f"{program}.stdout", "wb")   # noqa: SIM115 - the child keeps it
    with log:
        return subprocess.Popen([shutil.which(program, path=_sbin_path()) or program, *args], env=cluster.env(),
                                stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                                start_new_session=True)


def _wait_for(condition, cluster: Cluster, what: str) -> None:
    deadline = time.monotonic() + START_TIMEOUT
    while not condition():
        for name, process in cluster.processes.items():
            if process.poll() is not None:
                raise RuntimeError(f"{name} exited with status {process.returncode} while waiting for {what}\n"
                                   + cluster.logs())
        if time.monotonic() > deadline:
            raise RuntimeError(f"timed out after {START_TIMEOUT} s waiting for {what}\n" + cluster.logs())
        time.sleep(0.2)


def _kill_processes_naming(directory: Path) -> None:
    """SIGKILL every process (not this one or its ancestors) of the cluster in ``directory``: whose command line
    names it (the daemons), or whose environment names it and that is slurmstepd or a job (``SLURM_JOB_ID``); one
    that merely has ``SLURM_CONF`` set (a user's shell after ``eval "$(... start)"``) is left alone."""
    needle = str(directory).encode()
    spared = _ancestors()
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit() or int(entry.name) in spared:
            continue
        try:
            if needle in (entry / "cmdline").read_bytes():
                os.kill(int(entry.name), signal.SIGKILL)
                continue
            environ = b"\0" + (entry / "environ").read_bytes()
            if needle in environ and (b"\0SLURM_JOB_ID=" in environ
                                      or (entry / "comm").read_text().strip() == "slurmstepd"):
                os.kill(int(entry.name), signal.SIGKILL)
        except (OSError, ProcessLookupError):
            continue


def _ancestors() -> set[int]:
    pids, pid = set(), os.getpid()
    while pid > 1:
        pids.add(pid)
        try:
            pid = int((Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            break
    return pids


def _age(path: Path) -> float:
    try:
        return time.time() - path.stat().st_mtime
    except OSError:
        return 0.0


def _free_ports(count: int) -> list[int]:
    """Ports free now (held together while chosen, so they differ); the defaults 6817/6818 may be taken."""
    with contextlib.ExitStack() as stack:
        probes = [stack.enter_context(socket.socket()) for _ in range(count)]
        for probe in probes:
            probe.bind(("127.0.0.1", 0))
        return [probe.getsockname()[1] for probe in probes]


def _sbin_path() -> str:
    """PATH with the sbin directories (the daemons live there; a non-login root shell may lack them)."""
    parts = os.environ.get("PATH", "").split(os.pathsep)
    return os.pathsep.join(parts + [d for d in ("/usr/sbin", "/sbin", "/usr/local/sbin") if d not in parts])


def _hold(base: Path | None) -> int:
    """Start a cluster, tell the parent on stdout, then keep it until SIGTERM, SIGINT or SIGHUP."""
    stopping = []

    def _on_signal(signum, frame):
        stopping.append(signum)

    for signum in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
        signal.signal(signum, _on_signal)
    try:
        cluster = start(base)
    except (Unavailable, RuntimeError, ValueError, OSError) as err:
        print(f"error: {err}", flush=True)
        return 1
    (cluster.directory / HELD).write_text(str(os.getpid()))
    print(f"SLURM_CONF={cluster.conf}", flush=True)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())   # the parent has read its line and exits: nothing more goes there
    try:
        while not stopping:
            signal.pause()
    finally:
        cluster.stop()
    return 0


def held_clusters(base: Path) -> list[tuple[int, Path]]:
    """(holding process, state directory) of every running cluster the command line started under ``base``."""
    held = ((_pid_in(directory / HELD), directory) for directory in sorted(base.glob(PREFIX + "*")))
    return [(owner, directory) for owner, directory in held if owner is not None and alive(owner)]


def _pid_in(path: Path) -> int | None:
    try:
        return int(path.read_text())
    except (OSError, ValueError):
        return None


def _start_command(base: Path | None) -> int:
    holder = subprocess.Popen(
        [sys.executable, "-m", "gyrolab.sweep.slurm_local", "_hold", *(["--base", str(base)] if base else [])],
        stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
        start_new_session=True)   # not ended with this shell's process group (Ctrl-C) or terminal
    line = holder.stdout.readline().strip()
    holder.stdout.close()
    if not line.startswith("SLURM_CONF="):
        holder.wait(timeout=60)
        print(f"slurm_local: {line.removeprefix('error: ') or 'the cluster did not start'}", file=sys.stderr)
        return 1
    conf = line.split("=", 1)[1]
    print(f"export SLURM_CONF={conf}")
    print(f"slurm_local: a one-node SLURM is running (partition {PARTITION}, pid {holder.pid} holds it); "
          "sbatch, squeue and gyrolab's SLURM routes find it through SLURM_CONF; "
          "'python -m gyrolab.sweep.slurm_local stop' stops it", file=sys.stderr)
    return 0


def _status_command(base: Path) -> int:
    clusters = held_clusters(base)
    for owner, directory in clusters:
        print(f"SLURM_CONF={directory / 'slurm.conf'}  (pid {owner})")
    if not clusters:
        print(NONE_RUNNING, file=sys.stderr)
    return 0


def _stop_command(base: Path, timeout: float = 60) -> int:
    clusters = held_clusters(base)
    for owner, directory in clusters:
        os.kill(owner, signal.SIGTERM)
    deadline = time.monotonic() + timeout
    left = clusters
    while left and time.monotonic() < deadline:
        time.sleep(0.2)
        left = [(owner, directory) for owner, directory in left if alive(owner) or directory.exists()]
    for owner, directory in clusters:
        print(f"slurm_local: {'did not stop within ' + str(timeout) + ' s' if (owner, directory) in left else 'stopped'}"
              f" {directory}", file=sys.stderr)
    if not clusters:
        print(NONE_RUNNING, file=sys.stderr)
    return 1 if left else 0


def main(argv: list[str] | None = None) -> int:
    """``python -m gyrolab.sweep.slurm_local start|status|stop [--base DIR]``."""
    parser = argparse.ArgumentParser(
        prog="python -m gyrolab.sweep.slurm_local",
        description="A one-node SLURM on this machine (root; installs slurm-wlm and munge when missing), "
                    "to try gyrolab's SLURM routes (docs/cluster.md).")
    parser.add_argument("action", choices=["start", "status", "stop", "_hold"], metavar="{start,status,stop}",
                        help="start: start one and print 'export SLURM_CONF=...'; status: list the running ones; "
                             "stop: stop every one that start started")
    parser.add_argument("--base", type=Path, default=None,
                        help="where the state directories go (default: the system's temporary directory)")
    args = parser.parse_args(argv)
    base = args.base or Path(tempfile.gettempdir())
    if args.action in ("_hold", "start"):
        return (_hold if args.action == "_hold" else _start_command)(args.base)
    return (_status_command if args.action == "status" else _stop_command)(base)


if __name__ == "__main__":
    sys.exit(main())
