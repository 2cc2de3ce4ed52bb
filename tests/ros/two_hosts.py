"""Two emulated hosts for tests: Linux network namespaces joined by one veth pair.

``TwoHosts`` creates namespaces ``A`` and ``B`` (unique names per test process), a veth
pair with one end in each (created directly inside them: nothing is ever added to the
machine's own namespace), addresses ``10.213.0.1/30`` and ``10.213.0.2/30``, and brings
the loopback and veth interfaces up. Nothing else: no other interface, no default route,
so a process run inside (``exec_argv``) reaches only the other namespace and itself.

Each host also gets a ``/dev/shm`` of its own (a directory of the machine's, bind-mounted
over ``/dev/shm`` in the process's private mount namespace), shared by the processes of
that host only, as on two machines: Fast DDS's shared-memory transport and its port locks
live there, so they neither cross between the hosts nor number one host's participants
after the other's.

``close()`` deletes both namespaces (the veth pair goes with them) and the ``/dev/shm``
directories. Needs root, iproute2's ``ip`` and util-linux's ``mount``; :class:`Unavailable`
says why it cannot be done here.
"""

from __future__ import annotations

import json
import os
import pathlib
import shutil
import subprocess
import time

PREFIX = "bearing-host"
ADDRESSES = {"A": "10.213.0.1", "B": "10.213.0.2"}
PREFIX_LEN = 30
VETH = {"A": "veth_a", "B": "veth_b"}
SHM_ROOT = pathlib.Path("/dev/shm")


class Unavailable(RuntimeError):
    """Network namespaces cannot be created on this machine (the reason is the message)."""


def ip_command() -> str | None:
    for path in (shutil.which("ip"), "/usr/sbin/ip", "/sbin/ip"):
        if path and os.access(path, os.X_OK):
            return path
    return None


def _run(argv: list, timeout: float = 10.0) -> subprocess.CompletedProcess:
    return subprocess.run(argv, capture_output=True, text=True, timeout=timeout)


class TwoHosts:
    """Hosts ``"A"`` and ``"B"``; see the module docstring."""

    def __init__(self):
        self.ip = ip_command()
        tag = os.getpid()
        self.netns = {"A": f"{PREFIX}-a-{tag}", "B": f"{PREFIX}-b-{tag}"}
        self.shm = {host: SHM_ROOT / name for host, name in self.netns.items()}
        self.created: list[str] = []

    def address(self, host: str) -> str:
        return ADDRESSES[host]

    def other(self, host: str) -> str:
        return "B" if host == "A" else "A"

    def _ip(self, *args, host: str | None = None) -> subprocess.CompletedProcess:
        argv = [self.ip] + (["-n", self.netns[host]] if host else []) + list(args)
        return _run(argv)

    def _check(self, *args, host: str | None = None) -> str:
        done = self._ip(*args, host=host)
        if done.returncode != 0:
            raise RuntimeError(f"`ip {' '.join(args)}` failed: {done.stderr.strip()}")
        return done.stdout

    def create(self) -> TwoHosts:
        """Create both namespaces and the link; Unavailable where this machine cannot."""
        if self.ip is None:
            raise Unavailable("iproute2's `ip` command is not installed")
        if os.geteuid() != 0:
            raise Unavailable("creating network namespaces needs root")
        if shutil.which("mount") is None or not SHM_ROOT.is_dir():
            raise Unavailable("util-linux's `mount` or /dev/shm is missing")
        remove_stale(self.ip)
        for host in ("A", "B"):
            done = self._ip("netns", "add", self.netns[host])
            if done.returncode != 0:
                raise Unavailable(f"`ip netns add` failed (e.g. an unprivileged container): {done.stderr.strip()}")
            self.created.append(self.netns[host])
            self.shm[host].mkdir(mode=0o1777, exist_ok=True)
        done = self._ip("link", "add", VETH["A"], "netns", self.netns["A"], "type", "veth",
                        "peer", "name", VETH["B"], "netns", self.netns["B"])
        if done.returncode != 0:
            raise Unavailable(f"cannot create a veth pair between namespaces: {done.stderr.strip()}")
        for host in ("A", "B"):
            self._check("address", "add", f"{ADDRESSES[host]}/{PREFIX_LEN}", "dev", VETH[host], host=host)
            self._check("link", "set", "lo", "up", host=host)
            self._check("link", "set", VETH[host], "up", host=host)
        return self

    def wait_link_running(self, timeout: float = 10.0) -> float:
        """Wait until both veth ends are operationally up (carrier); return the seconds waited.

        Fast DDS lists the machine's interfaces once, when a participant is created, and skips
        those not running. Right after ``ip link set ... up`` a veth end can still be DOWN
        (NO-CARRIER): processes started at once announced only 127.0.0.1 (6 of 6 trials) and
        were never reached from the other host; started after both ends reported UP, they
        announced the veth address (6 of 6).
        """
        start = time.monotonic()
        while True:
            states = {host: self.link(host)["operstate"] for host in ("A", "B")}
            if all(state == "UP" for state in states.values()):
                return time.monotonic() - start
            if time.monotonic() - start > timeout:
                raise RuntimeError(f"veth pair not up after {timeout} s: {states}")
            time.sleep(0.02)

    def link(self, host: str) -> dict:
        """``ip -j -s link show`` of the host's veth end (operstate, stats64 rx/tx bytes)."""
        return json.loads(self._check("-j", "-s", "link", "show", "dev", VETH[host], host=host))[0]

    def tx_bytes(self, host: str) -> int:
        return int(self.link(host)["stats64"]["tx"]["bytes"])

    def interfaces(self, host: str) -> set:
        return {entry["ifname"] for entry in json.loads(self._check("-j", "link", "show", host=host))}

    def routes(self, host: str) -> list:
        """Every IPv4 route of the host (all tables)."""
        return json.loads(self._check("-j", "-4", "route", "show", "table", "all", host=host))

    def exec_argv(self, host: str, argv: list) -> list:
        """``argv`` run inside the host's namespace with the host's ``/dev/shm`` (``ip netns
        exec`` gives it a private mount namespace; it and ``sh`` exec: one process throughout)."""
        return [self.ip, "netns", "exec", self.netns[host], "sh", "-c", 'mount --bind "$0" /dev/shm && exec "$@"',
                str(self.shm[host])] + [str(a) for a in argv]

    def close(self) -> list:
        """Delete the namespaces (and with them the veth pair); return the errors, if any."""
        errors = []
        for name in reversed(self.created):
            done = _run([self.ip, "netns", "del", name])
            if done.returncode != 0:
                errors.append(f"ip netns del {name}: {done.stderr.strip()}")
            shutil.rmtree(SHM_ROOT / name, ignore_errors=True)
        self.created.clear()
        return errors


def remove_stale(ip: str) -> None:
    """Delete namespaces and /dev/shm directories left by an earlier run of these tests whose
    process is gone (killed before its teardown ran)."""
    listed = _run([ip, "netns", "list"]).stdout.split("\n")
    names = {line.split()[0] for line in listed if line.strip()} | {p.name for p in SHM_ROOT.glob(PREFIX + "-*")}
    for name in sorted(names):
        pid = name.rsplit("-", 1)[-1]
        if name.startswith(PREFIX + "-") and pid.isdigit() and not os.path.exists(f"/proc/{pid}"):
            _run([ip, "netns", "del", name])
            shutil.rmtree(SHM_ROOT / name, ignore_errors=True)
