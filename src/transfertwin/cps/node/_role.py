"""The `Role` base: what an asset does on its node (Ch. 3, the asset's application layer).

Every role offers `handlers()` (the OPC UA operations), `writable()` (properties others
may write besides the externally synchronised ones), `live()` (its part of the heartbeat),
`start()` and `stop()`, and keeps what must survive a crash in its `NodeState`. The roles
of the asset classes are in `transfertwin.cps.roles`; the node is handed a factory that
makes one (`AssetNode(cfg, roles)`), so this layer names no role.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from transfertwin.cps.node._state import NodeState

if TYPE_CHECKING:
    from transfertwin.cps.aas import OperationSpec
    from transfertwin.cps.node._node import AssetNode

__all__ = ["Role"]


class Role:
    """The default role: serve the AAS, nothing else."""

    def __init__(self, node: AssetNode) -> None:
        self.node = node
        self.aid = node.desc.asset_id
        self.state = NodeState(node.cfg.state_dir / f"{self.aid}.json", self.initial())

    def initial(self) -> dict[str, Any]:
        """The persisted state before the first save."""
        return {}

    def handlers(self) -> dict[str, Any]:
        return {}

    def operations(self) -> tuple[OperationSpec, ...]:
        """Operations of the asset's ControlInterface beyond its class's (`RunTransfer` of a
        plant's physical unit)."""
        return ()

    def writable(self) -> set[str]:
        return set()

    async def start(self) -> None:
        pass

    async def stop(self) -> None:
        pass

    async def live(self) -> dict[str, Any]:
        """This asset's live state for the heartbeat."""
        return {"state": "idle"}

    async def set(self, prop: str, value: object) -> None:
        """Set one of this asset's OperationalData properties."""
        await self.node.server.set("OperationalData", prop, value)

    async def get(self, prop: str) -> Any:
        return await self.node.server.get("OperationalData", prop)


