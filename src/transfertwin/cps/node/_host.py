"""The seam between a transport module's role and its skills (`ModuleHost`): what the
operation flow's steps (`transfertwin.cps.apps.TransportSkills`) and the hand-over policy
(`transfertwin.cps.apps.HandOverRetries`) may use of the module they run on. A module's
role implements it (`transfertwin.cps.roles.ModuleRole`, and the one on real hardware);
the skills reach the module through nothing else."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol, TypeVar

if TYPE_CHECKING:
    from transfertwin.control import TransferRecord
    from transfertwin.cps.apps import FloorRobot
    from transfertwin.cps.node._state import NodeState
    from transfertwin.ots import TransferDirection
    from transfertwin.sim import DockingError

__all__ = ["ModuleHost"]

T = TypeVar("T")


class ModuleHost(Protocol):
    """A transport module as its skills see it.

    Attributes:
        aid: The module's asset id.
        robot: Its drive on the shop floor (pose, navigation, docking).
        env: The world it simulates or drives (``scene``, ``system``, ``lock``,
            ``object_ref``, ``undock()``): an `Environment`, the plant's, or a
            `GatewayWorld` on real hardware.
        docking: How it gets to a station: 'sampled' or 'navigated'.
        seed: The seed of its docking errors.
        state: Its persisted state (the faces of the objects on board: ``faces``).
        op: The operation it runs (its ``load`` state), None between operations.
        face: The face the carried object lies on.
        attempt: The hand-over try of the running leg (0: the first).
        lost_in_gap: Set when the hand-over policy gives up with the object in the gap.
    """

    aid: str
    robot: FloorRobot
    env: Any
    docking: str
    seed: int
    state: NodeState
    op: dict[str, Any] | None
    face: str
    attempt: int
    lost_in_gap: bool

    def station_of(self, unit: str) -> str:
        """The station of transfer unit `unit`."""

    def carried(self) -> list[str]:
        """The objects on the module's belts."""

    def docking_error(self, source: str, target: str, obj: str, leg: int) -> DockingError:
        """The docking error drawn for this try of leg `leg` (sampled docking)."""

    async def docking_estimate(
        self, unit: str, error: DockingError, seed: int
    ) -> tuple[DockingError, dict[str, Any] | None]:
        """The docking error the transfer uses, and what PropS said of it (None: none)."""

    def locked(self, fn: Callable[..., T], *args: object) -> T:
        """`fn(*args)` with the world's lock held."""

    async def publish_pose(self) -> None:
        """Publish the module's floor pose."""

    async def dock(self, unit: str) -> bool:
        """Publish the docking at `unit`, on both sides."""

    async def undock(self) -> bool:
        """Leave the unit docked at."""

    async def transfer(self, unit: str, direction: TransferDirection) -> TransferRecord:
        """One OTS between the module and `unit`."""

    async def take_back(self, unit: str, to_unit: bool = False) -> bool:
        """Reverse both belt pairs until the object is back (on the unit with `to_unit`)."""

    async def moved(self, obj: str, holder: str) -> None:
        """A transfer put `obj` onto `holder`."""
