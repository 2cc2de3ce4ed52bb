"""Emulated hosts for tests and benchmarks: Linux network namespaces joined by veth links.

* :class:`TwoHosts`: namespaces ``A`` and ``B`` joined by one veth pair (created directly
  inside them: nothing is ever added to the machine's own namespace), ``10.213.0.1/30`` and
  ``10.213.0.2/30``;
* :class:`LanHosts`: ``n`` namespaces ``H1`` ... ``Hn`` on one switched LAN: each host's veth
  ends in a bridge that lives in a namespace of its own (the switch), ``10.213.1.k/24``.

Each host gets its loopback and veth interface up and nothing else: no other interface, no
default route, so a process run inside (``exec_argv``) reaches only the other hosts and
itself. Each also gets a ``/dev/shm`` of its own (a directory of the machine's, bind-mounted
over ``/dev/shm`` in the process's private mount namespace), shared by the processes of that
host only, as on separate machines: Fast DDS's shared-memory transport and its port locks
live there, so they neither cross between hosts nor number one host's participants after
another's.

``close()`` deletes the namespaces (the veth links go with them) and the ``/dev/shm``
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
SHM_ROOT = pathlib.Path("/dev/shm")
PREFIX_LEN = 30  #: of the two hosts' link
VETH = {"A": "veth_a", "B": "veth_b"}  #: the two hosts' interface names
LAN_SUBNET, LAN_PREFIX_LEN = "10.213.1", 24


class Unavailable(RuntimeError):
    """Network namespaces cannot be created on this machine (the reason is the message)."""


def ip_command() -> str | None:
    for path in (shutil.which("ip"), "/usr/sbin/ip", "/sbin/ip"):
        if path and os.access(path, os.X_OK):
            return path
    return None


def _run(argv: list, timeout: float = 10.0) -> subprocess.CompletedProcess:
    return subprocess.run(argv, capture_output=True, text=True, timeout=timeout)


class Hosts:
    """Network namespaces, one per host name, with their veth interface and address (subclasses
    make the links: :meth:`create`)."""

    def __init__(self, names, addresses: dict, interfaces: dict, prefix_len: int):
        self.ip = ip_command()
        tag = os.getpid()
        self.names = tuple(names)
        self.netns = {host: f"{PREFIX}-{host.lower()}-{tag}" for host in self.names}
        self.shm = {host: SHM_ROOT / name for host, name in self.netns.items()}
        self.addresses, self.veth, self.prefix_len = dict(addresses), dict(interfaces), prefix_len
        self.created: list[str] = []

    def address(self, host: str) -> str:
        return self.addresses[host]

    def _ip(self, *args, host: str | None = None, netns: str | None = None) -> subprocess.CompletedProcess:
        name = self.netns[host] if host else netns
        return _run([self.ip] + (["-n", name] if name else []) + list(args))

    def _check(self, *args, host: str | None = None, netns: str | None = None) -> str:
        done = self._ip(*args, host=host, netns=netns)
        if done.returncode != 0:
            raise RuntimeError(f"`ip {' '.join(args)}` failed: {done.stderr.strip()}")
        return done.stdout

    def _add_namespace(self, name: str) -> None:
        """Create namespace ``name`` (Unavailable where the machine cannot)."""
        done = self._ip("netns", "add", name)
        if done.returncode != 0:
            raise Unavailable(f"`ip netns add` failed (e.g. an unprivileged container): {done.stderr.strip()}")
        self.created.append(name)

    def _add_hosts(self) -> None:
        """Check what is needed, clear stale namespaces, create every host's namespace and /dev/shm."""
        if self.ip is None:
            raise Unavailable("iproute2's `ip` command is not installed")
        if os.geteuid() != 0:
            raise Unavailable("creating network namespaces needs root")
        if shutil.which("mount") is None or not SHM_ROOT.is_dir():
            raise Unavailable("util-linux's `mount` or /dev/shm is missing")
        remove_stale(self.ip)
        for host in self.names:
            self._add_namespace(self.netns[host])
            self.shm[host].mkdir(mode=0o1777, exist_ok=True)

    def _bring_up(self) -> None:
        """Every host's address on its veth end; loopback and veth up."""
        for host in self.names:
            self._check("address", "add", f"{self.addresses[host]}/{self.prefix_len}", "dev", self.veth[host],
                        host=host)
            self._check("link", "set", "lo", "up", host=host)
            self._check("link", "set", self.veth[host], "up", host=host)

    def wait_link_running(self, timeout: float = 10.0) -> float:
        """Wait until every host's veth end is operationally up (carrier); return the seconds waited.

        Fast DDS lists the machine's interfaces once, when a participant is created, and skips
        those not running. Right after ``ip link set ... up`` a veth end can still be DOWN
        (NO-CARRIER): processes started at once announced only 127.0.0.1 (6 of 6 trials) and
        were never reached from the other host; started after both ends reported UP, they
        announced the veth address (6 of 6).
        """
        start = time.monotonic()
        while True:
            states = {host: self.link(host)["operstate"] for host in self.names}
            if all(state == "UP" for state in states.values()):
                return time.monotonic() - start
            if time.monotonic() - start > timeout:
                raise RuntimeError(f"veth links not up after {timeout} s: {states}")
            time.sleep(0.02)

    def link(self, host: str, interface: str | None = None) -> dict:
        """``ip -j -s link show`` of one of the host's interfaces (default its veth end)."""
        return json.loads(self._check("-j", "-s", "link", "show", "dev", interface or self.veth[host], host=host))[0]

    def tx_bytes(self, host: str, interface: str | None = None) -> int:
        return int(self.link(host, interface)["stats64"]["tx"]["bytes"])

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
        """Delete the namespaces (and with them the veth links); return the errors, if any."""
        errors = []
        for name in reversed(self.created):
            done = _run([self.ip, "netns", "del", name])
            if done.returncode != 0:
                errors.append(f"ip netns del {name}: {done.stderr.strip()}")
            shutil.rmtree(SHM_ROOT / name, ignore_errors=True)
        self.created.clear()
        return errors


class TwoHosts(Hosts):
    """Hosts ``"A"`` and ``"B"`` joined by one veth pair; see the module docstring."""

    def __init__(self):
        super().__init__(("A", "B"), {"A": "10.213.0.1", "B": "10.213.0.2"}, VETH, PREFIX_LEN)

    def other(self, host: str) -> str:
        return "B" if host == "A" else "A"

    def create(self) -> TwoHosts:
        """Create both namespaces and the link; Unavailable where this machine cannot."""
        self._add_hosts()
        done = self._ip("link", "add", VETH["A"], "netns", self.netns["A"], "type", "veth",
                        "peer", "name", VETH["B"], "netns", self.netns["B"])
        if done.returncode != 0:
            raise Unavailable(f"cannot create a veth pair between namespaces: {done.stderr.strip()}")
        self._bring_up()
        return self


class LanHosts(Hosts):
    """Hosts ``H1`` ... ``Hn`` on one switched LAN (a bridge in a namespace of its own); see the
    module docstring. The switch floods multicast (snooping off), as an unmanaged switch does."""

    def __init__(self, n: int):
        names = [f"H{k}" for k in range(1, n + 1)]
        super().__init__(names, {h: f"{LAN_SUBNET}.{k}" for k, h in enumerate(names, 1)},
                         dict.fromkeys(names, "eth0"), LAN_PREFIX_LEN)
        self.switch = f"{PREFIX}-sw-{os.getpid()}"

    def create(self) -> LanHosts:
        """Create the hosts, the switch and one link from each host to it."""
        self._add_hosts()
        self._add_namespace(self.switch)
        self._check("link", "add", "br0", "type", "bridge", "mcast_snooping", "0", netns=self.switch)
        for k, host in enumerate(self.names, 1):
            done = self._ip("link", "add", "eth0", "netns", self.netns[host], "type", "veth",
                            "peer", "name", f"port{k}", "netns", self.switch)
            if done.returncode != 0:
                raise Unavailable(f"cannot create a veth pair between namespaces: {done.stderr.strip()}")
            self._check("link", "set", f"port{k}", "master", "br0", "up", netns=self.switch)
        self._check("link", "set", "br0", "up", netns=self.switch)
        self._bring_up()
        return self

    def traffic(self) -> int:
        """Bytes every host has sent so far, on its LAN link and its loopback (all of DDS's UDP)."""
        return sum(self.tx_bytes(host) + self.tx_bytes(host, "lo") for host in self.names)


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
