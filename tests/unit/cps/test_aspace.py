"""The shared standard address space: each server sees asyncua's standard nodes, its own
writes stay its own, and the mapping behaves like the dict it replaces."""

from __future__ import annotations

import asyncio

import pytest
from asyncua import Server, ua
from asyncua.server.address_space import NodeData

from transfertwin.cps.opcua._aspace import CopyOnAccess, share_standard_address_space


def _node(i: int) -> NodeData:
    return NodeData(ua.NodeId(i, 7))


def test_copy_on_access_behaves_like_a_dict_and_never_writes_the_template():
    template = {n.nodeid: n for n in (_node(1), _node(2), _node(3))}
    nodes = CopyOnAccess(template)
    a, b, c, d = (ua.NodeId(i, 7) for i in (1, 2, 3, 4))
    assert len(nodes) == 3 and set(nodes) == {a, b, c} and a in nodes and d not in nodes
    got = nodes[a]
    assert got is not template[a] and got.nodeid == a and nodes[a] is got  # copied once
    got.references.append("ref")
    assert template[a].references == []
    nodes[d] = _node(4)
    del nodes[b]
    assert b not in nodes and nodes.get(b) is None and set(nodes) == {a, c, d} and len(nodes) == 3
    assert b in template  # the template keeps it for other servers
    nodes[b] = _node(2)
    assert b in nodes and len(nodes) == 4
    with pytest.raises(KeyError):
        del nodes[ua.NodeId(99, 7)]


@pytest.mark.slow  # ~13 s alone (CI: the CPS slow group)
def test_servers_from_the_shared_space_match_asyncua_and_keep_their_writes_apart():
    async def scenario():
        plain = Server()
        await plain.init()
        first, second = Server(), Server()
        for server in (first, second):
            share_standard_address_space(server)
            await server.init()
        assert isinstance(first.iserver.aspace._nodes, CopyOnAccess)
        assert set(first.iserver.aspace.keys()) == set(plain.iserver.aspace.keys())
        # standard nodes read the same (a type, a reference, the namespace array)
        for nid in (ua.ObjectIds.BaseObjectType, ua.ObjectIds.HasComponent,
                    ua.ObjectIds.Server_NamespaceArray):  # fmt: skip
            for attr in (ua.AttributeIds.BrowseName, ua.AttributeIds.NodeClass):
                want = plain.iserver.aspace.read_attribute_value(ua.NodeId(nid), attr).Value
                got = first.iserver.aspace.read_attribute_value(ua.NodeId(nid), attr).Value
                assert got == want
        # a server's own nodes and writes do not reach the other server
        ns = await first.register_namespace("urn:test:first")
        var = await first.nodes.objects.add_variable(ns, "Speed", 1.0)
        await var.write_value(2.5)
        assert await var.read_value() == 2.5
        assert var.nodeid not in second.iserver.aspace
        names = await first.get_namespace_array()
        assert "urn:test:first" in names
        assert "urn:test:first" not in await second.get_namespace_array()
        children = {c.nodeid for c in await second.nodes.objects.get_children()}
        assert var.nodeid not in children

    asyncio.run(scenario())
