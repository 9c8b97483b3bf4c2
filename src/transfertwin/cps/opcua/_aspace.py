"""The OPC UA standard address space, built once per process and copied per server.

Every asyncua server starts from the standard address space (about 6,200 nodes, 74,000
attributes), and asyncua builds it node by node in Python: about 2 s per server here, most
of a CPS's 14-server start-up. The nodes are the same for every server, so this module
builds them once per process (a template) and gives each server a mapping that copies a
node from the template the first time that server touches it (asyncua's own shelf option
does the same from a file, and is slower than building). A server's writes go to its own
copies; the template is never written.
"""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Iterator, MutableMapping
from pathlib import Path

from asyncua import Server, ua
from asyncua.server.address_space import (
    AddressSpace,
    AttributeValue,
    NodeData,
    NodeManagementService,
)
from asyncua.server.standard_address_space.standard_address_space import fill_address_space

__all__ = ["build_standard_address_space", "share_standard_address_space"]

_template: dict[ua.NodeId, NodeData] | None = None
_lock = threading.Lock()


def _standard_nodes() -> dict[ua.NodeId, NodeData]:
    """The standard address space's nodes, built on the first call (thread-safe)."""
    global _template
    with _lock:
        if _template is None:
            aspace = AddressSpace()
            fill_address_space(NodeManagementService(aspace))
            _template = aspace._nodes
        return _template


def build_standard_address_space() -> int:
    """Build this process's template now (a process that forks asset processes builds it
    once, and they share its pages copy-on-write); the number of nodes."""
    return len(_standard_nodes())


def _copy_attribute(value: AttributeValue) -> AttributeValue:
    copy = AttributeValue(value.value)  # a DataValue is replaced on write, never changed
    copy.value_callback = value.value_callback
    copy.value_setter = value.value_setter
    copy.datachange_callbacks = dict(value.datachange_callbacks)
    return copy


def _copy_node(node: NodeData) -> NodeData:
    copy = NodeData(node.nodeid)
    copy.attributes = {a: _copy_attribute(v) for a, v in node.attributes.items()}
    copy.references = list(node.references)
    copy.call = node.call
    return copy


class CopyOnAccess(MutableMapping):
    """One server's nodes: its own, plus the template's, copied when first touched."""

    def __init__(self, template: dict[ua.NodeId, NodeData]) -> None:
        self._template = template
        self._own: dict[ua.NodeId, NodeData] = {}
        self._deleted: set[ua.NodeId] = set()

    def __getitem__(self, key: ua.NodeId) -> NodeData:
        try:
            return self._own[key]
        except KeyError:
            if key in self._deleted:
                raise
            node = self._own[key] = _copy_node(self._template[key])
            return node

    def get(self, key: ua.NodeId, default: NodeData | None = None) -> NodeData | None:
        try:
            return self[key]
        except KeyError:
            return default

    def __setitem__(self, key: ua.NodeId, value: NodeData) -> None:
        self._own[key] = value
        self._deleted.discard(key)

    def __delitem__(self, key: ua.NodeId) -> None:
        if key not in self:
            raise KeyError(key)
        self._own.pop(key, None)
        if key in self._template:
            self._deleted.add(key)

    def __contains__(self, key: object) -> bool:
        return key in self._own or (key in self._template and key not in self._deleted)

    def __iter__(self) -> Iterator[ua.NodeId]:
        yield from self._own
        for key in self._template:
            if key not in self._own and key not in self._deleted:
                yield key

    def __len__(self) -> int:
        shared = sum(1 for k in self._template if k not in self._own and k not in self._deleted)
        return len(self._own) + shared


def share_standard_address_space(server: Server) -> None:
    """Make `server.init()` start from the shared standard address space (call before it).

    The rest of asyncua's start-up (its address-space fixes, server nodes, history) runs as
    usual on the server's own copies.
    """
    iserver = server.iserver

    async def load(shelf_file: Path | None = None) -> None:
        template = await asyncio.to_thread(_standard_nodes)
        iserver.aspace._nodes = CopyOnAccess(template)

    iserver.load_standard_address_space = load
