"""The servers' role rules for method calls: a viewer may call the knowledge graph's
read-only Query (`VIEWER_METHODS`) and nothing else, alone or in one request with another
method; an operator may call anything; a peer asset's certificate (`ASSET_ROLE`) anything
but the `OPERATOR_METHODS` (Shutdown, steering studies and campaigns)."""

from __future__ import annotations

import pytest
from asyncua import ua
from asyncua.common.utils import Buffer
from asyncua.crypto.permission_rules import User, UserRole
from asyncua.ua.ua_binary import struct_to_binary

from transfertwin.cps.opcua._security import RoleRuleset

CALL = ua.NodeId(ua.ObjectIds.CallRequest_Encoding_DefaultBinary)


def _call(*methods: str) -> Buffer:
    """The binary body of a CallRequest calling `methods` (string node ids)."""
    params = ua.CallParameters(MethodsToCall=[
        ua.CallMethodRequest(ObjectId=ua.NodeId(m.rsplit(".", 1)[0], 2),
                             MethodId=ua.NodeId(m, 2)) for m in methods])  # fmt: skip
    return Buffer(struct_to_binary(params))


@pytest.mark.parametrize(
    ("role", "methods", "granted"),
    [
        ("viewer", ("KG.ControlInterface.Query",), True),
        ("viewer", ("TU_A.ControlInterface.SetBeltSpeed",), False),
        ("viewer", ("TMS.ControlInterface.Orders",), False),
        ("viewer", ("KG.ControlInterface.Query", "TMS.ControlInterface.Orders"), False),
        ("viewer", ("KG.Lifecycle.Shutdown",), False),
        ("viewer", ("KG.Other.Query",), False),  # only the ControlInterface's Query
        ("operator", ("TU_A.ControlInterface.SetBeltSpeed",), True),
        ("TMS", ("TU_A.ControlInterface.SetBeltSpeed",), False),  # a peer role, not operator
        # a peer asset's certificate (ASSET_ROLE): all but the OPERATOR_METHODS
        ("asset", ("TU_A.ControlInterface.SetBeltSpeed",), True),
        ("asset", ("KG.ControlInterface.Heartbeat",), True),
        ("asset", ("KG.Lifecycle.Shutdown",), False),
        ("asset", ("TU_A.ControlInterface.SetBeltSpeed", "TU_A.Lifecycle.Shutdown"), False),
        ("asset", ("EM.ControlInterface.StartStudy",), False),
        ("asset", ("EM.ControlInterface.StopCampaign",), False),
        ("operator", ("KG.Lifecycle.Shutdown",), True),
        ("operator", ("EM.ControlInterface.StartCampaign",), True),
    ],
)
def test_a_viewer_may_call_query_only(role: str, methods: tuple[str, ...], granted: bool) -> None:
    user = User(role=UserRole.User, name=role)
    assert RoleRuleset().check_validity(user, CALL, _call(*methods)) is granted


def test_the_call_body_is_read_from_a_copy_and_garbage_is_refused() -> None:
    body = _call("KG.ControlInterface.Query")
    viewer = User(role=UserRole.User, name="viewer")
    assert RoleRuleset().check_validity(viewer, CALL, body)
    assert body.read(4) == _call("KG.ControlInterface.Query").read(4)  # not consumed
    assert not RoleRuleset().check_validity(viewer, CALL, Buffer(b"\x05\x00"))
