"""Hosts on one machine for a test: Linux network namespaces joined by a bridge
(`NamespaceNet`), each with one interface and an address from 198.18.0.0/15 (the
benchmarking range, RFC 2544: never any other range), its loopback left down.

The bridge lives in a namespace of its own and every veth pair is made with its ends
already in their namespaces, so nothing is added to the machine's own network; deleting
the namespaces (`NamespaceNet.remove`) removes every interface with them.
"""

from __future__ import annotations

import ipaddress
import os
import shutil
import subprocess

__all__ = ["NETWORK", "NamespaceNet", "netns_unavailable"]

#: The only addresses these hosts get (a /24 of the benchmarking range 198.18.0.0/15).
NETWORK = ipaddress.ip_network("198.18.0.0/24")


def _ip(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    return subprocess.run(["ip", *args], capture_output=True, text=True, check=check, timeout=30)


def netns_unavailable() -> str | None:
    """Why this machine cannot make network namespaces (None: it can)."""
    if shutil.which("ip") is None:
        return "no 'ip' command (iproute2)"
    if os.geteuid() != 0:
        return "network namespaces need root"
    probe = f"ttprobe{os.getpid()}"
    made = _ip("netns", "add", probe, check=False)
    if made.returncode != 0:
        return f"'ip netns add' failed: {made.stderr.strip()}"
    _ip("netns", "del", probe, check=False)
    return None


class NamespaceNet:
    """Network namespaces on one bridge: `add(name)` makes a host with the next address.

    Args:
        prefix: Unique start of the namespaces' names (this test run's).
    """

    def __init__(self, prefix: str) -> None:
        self.prefix = prefix
        self.switch = f"{prefix}-sw"
        self.hosts: dict[str, str] = {}  # name -> address
        self._made: list[str] = []
        self._next = 10
        self._netns("add", self.switch)
        _ip("-n", self.switch, "link", "add", "br0", "type", "bridge")
        _ip("-n", self.switch, "link", "set", "br0", "up")

    def _netns(self, *args: str) -> None:
        _ip("netns", *args)
        if args[0] == "add":
            self._made.append(args[1])

    def namespace(self, name: str) -> str:
        return f"{self.prefix}-{name}"

    def add(self, name: str, address: str | None = None) -> str:
        """A host `name`: a namespace with ``eth0`` on the bridge at the next free address
        of `NETWORK` (or `address`, which must be in it), loopback down; its address."""
        if address is None:
            address = str(NETWORK[self._next])
            self._next += 1
        if ipaddress.ip_address(address) not in NETWORK:
            raise ValueError(f"{address} is not in {NETWORK}")
        ns = self.namespace(name)
        self._netns("add", ns)
        port = f"v{len(self.hosts)}"
        _ip("link", "add", "eth0", "netns", ns, "type", "veth", "peer", "name", port,
            "netns", self.switch)  # fmt: skip
        _ip("-n", self.switch, "link", "set", port, "master", "br0", "up")
        _ip("-n", ns, "addr", "add", f"{address}/{NETWORK.prefixlen}", "dev", "eth0")
        _ip("-n", ns, "link", "set", "eth0", "up")
        self.hosts[name] = address
        return address

    def command(self, name: str, argv: list[str]) -> list[str]:
        """`argv` run inside host `name`'s namespace."""
        return ["ip", "netns", "exec", self.namespace(name), *argv]

    def bring_loopback_up(self, name: str) -> None:
        """Bring host `name`'s loopback up (a host that serves itself, e.g. a console)."""
        _ip("-n", self.namespace(name), "link", "set", "lo", "up")

    def loopback_up(self, name: str) -> bool:
        """Whether host `name`'s loopback is up."""
        out = _ip("-n", self.namespace(name), "-o", "link", "show", "lo").stdout
        return "state UP" in out or ",UP" in out

    def left(self) -> list[str]:
        """The namespaces of this net that still exist."""
        listed = _ip("netns", "list", check=False).stdout.split()
        return [n for n in listed if n.startswith(f"{self.prefix}-")]

    def remove(self) -> None:
        """Delete every namespace made (their interfaces, the bridge with them)."""
        for ns in reversed(self._made):
            _ip("netns", "del", ns, check=False)
        self._made.clear()
