"""The lease's arithmetic and an asset's side of it (`cps.node._lease`): the default lease by floor
size, the renewal sent when nothing changed, the directory sent only when it changed, the
jitter, and the gossip period stretched with the number of peers."""

from __future__ import annotations

import json

import pytest

from transfertwin.cps import default_lease
from transfertwin.cps.node._lease import (
    DEFAULT_LEASE_S,
    HEARTBEATS_PER_S,
    Renewal,
    directory_reply,
    heartbeat_period,
    instance_id,
)
from transfertwin.cps.opcua._discovery import Discovery, Peer


@pytest.mark.parametrize(("assets", "lease"), [(0, 5.0), (10, 5.0), (50, 5.0), (66, 5.0),
                                               (67, 6.0), (200, 15.0), (2000, 150.0)])  # fmt: skip
def test_the_default_lease_keeps_the_graphs_heartbeat_rate_within_its_budget(assets, lease):
    assert default_lease(assets) == lease
    assert default_lease(assets) >= DEFAULT_LEASE_S
    if assets > 66:  # a floor beyond the small ones: the graph's rate is at the budget
        assert assets / heartbeat_period(lease) <= HEARTBEATS_PER_S


def test_a_renewal_goes_out_once_the_full_heartbeat_was_acknowledged():
    lease = Renewal("o7", "5e1f")
    payload = json.dumps({"id": "o7", "instance": "5e1f", "pid": 4242, "state": "idle",
                          "location": "TU_A"})  # fmt: skip
    first = json.loads(lease.request(payload))
    assert first["location"] == "TU_A" and first["directory"] == ""  # full, no directory held
    # not acknowledged (e.g. the call timed out): full again
    assert "location" in json.loads(lease.request(payload))
    endpoints = lease.answered(directory_reply("b.3", {"KG": "opc.tcp://kg", "o7": "x"}, ""))
    assert endpoints == {"KG": "opc.tcp://kg", "o7": "x"} and lease.directory == "b.3"
    renew = json.loads(lease.request(payload))
    assert renew == {"id": "o7", "instance": "5e1f", "renew": True, "directory": "b.3"}
    assert lease.answered(directory_reply("b.3", {"KG": "opc.tcp://kg"}, "b.3")) is None
    assert lease.directory == "b.3"
    # the live state changed: the full heartbeat again, then renewals
    moved = payload.replace("TU_A", "TM_1")
    assert json.loads(lease.request(moved))["location"] == "TM_1"
    lease.answered(directory_reply("b.4", {"KG": "opc.tcp://kg"}, "b.3"))
    assert lease.directory == "b.4"
    assert json.loads(lease.request(moved)).get("renew") is True
    # the graph holds no lease (restarted): the next one is full
    lease.refused()
    assert json.loads(lease.request(moved))["location"] == "TM_1"
    assert (lease.full_sent, lease.renewals_sent) == (4, 2)


def test_the_directory_is_sent_only_to_a_sender_holding_another_version():
    eps = {"KG": "opc.tcp://127.0.0.2:4840/transfertwin/KG"}
    assert json.loads(directory_reply("a.1", eps, None)) == {"directory": "a.1", "endpoints": eps}
    assert json.loads(directory_reply("a.1", eps, "a.0"))["endpoints"] == eps
    assert json.loads(directory_reply("a.1", eps, "a.1")) == {"directory": "a.1"}


def test_heartbeats_are_jittered_within_the_period_and_the_same_for_the_same_asset():
    a, b, again = Renewal("TU_A", "1"), Renewal("TU_B", "1"), Renewal("TU_A", "2")
    pauses = [a.pause(3.0) for _ in range(200)]
    assert all(2.4 <= p <= 3.0 for p in pauses) and max(pauses) - min(pauses) > 0.4
    assert [again.pause(3.0) for _ in range(200)] == pauses  # seeded by the asset's id
    assert [b.pause(3.0) for _ in range(200)] != pauses


def test_each_start_of_a_process_has_an_instance_id_of_its_own():
    ids = {instance_id() for _ in range(100)}  # pids repeat across hosts; these do not
    assert len(ids) == 100 and all(len(i) == 16 and int(i, 16) >= 0 for i in ids)


def test_the_gossip_period_stretches_with_the_number_of_peers():
    agent = Discovery(server=None, period_s=1.0, entries_per_s=10.0)  # type: ignore[arg-type]
    assert agent.pause() == 1.0
    for i in range(199):
        agent.peers[f"urn:transfertwin:o{i}"] = Peer(f"urn:transfertwin:o{i}", f"opc.tcp://h{i}")
    assert agent.pause() == pytest.approx(19.9)
    assert Discovery(server=None, period_s=0.5).pause() == 0.5  # type: ignore[arg-type]
