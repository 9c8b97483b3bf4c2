"""Partners found by meaning (issue 39, item 5): a role asks the knowledge graph which assets
realise a capability, with which constraints, and whether they are online; never for an id
or an asset class. The graph itself is found through the floor's seeds (``KG``).

The question is one SPARQL query (`partners_query`) sent to the graph's ``Query``; the answer
(`partners_from_rows`) is one `Partner` per asset, with the constraint values its AAS gives
that capability (``<capability>Relations/Constraints``, entered into the graph as
``tt:hasConstraint`` nodes). `Partner.admits` says whether an asset's constraints admit what
a task needs, e.g. ``{"ObjectMass": 3.5}`` against ``ObjectMassMin``/``ObjectMassMax``.
"""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING

from transfertwin.cps.aas import Capability

if TYPE_CHECKING:
    from transfertwin.cps.node._node import AssetNode

__all__ = [
    "Partner",
    "capability_name",
    "find_partner_ids",
    "find_partners",
    "partners_from_rows",
    "partners_query",
]

log = logging.getLogger(__name__)

_TT = "https://transfertwin.dev/ontology#"


def capability_name(cap: Capability) -> str:
    """Local name of a capability's individual in the ontology, e.g. ``FusePoses``."""
    return "".join(word.title() for word in cap.value.split("_"))


def partners_query(cap: Capability) -> str:
    """The question "which assets realise `cap`, with which constraints, online or not?"
    (SPARQL SELECT of ``?id ?status ?name ?value``: one row per asset and constraint, one
    row without ``?name`` for an asset whose capability has none). The capability is an
    enum member, never caller text."""
    name = capability_name(Capability(cap))
    return f"""\
PREFIX tt: <{_TT}>
SELECT ?id ?status ?name ?value WHERE {{
  ?asset tt:hasCapability tt:{name} ;
         tt:assetId ?id ;
         tt:status ?status .
  OPTIONAL {{
    ?asset tt:hasConstraint ?c .
    ?c tt:ofCapability tt:{name} ;
       tt:constraint ?k ;
       tt:value ?value .
    BIND(STRAFTER(STR(?k), "#") AS ?name)
  }}
}}
ORDER BY ?id ?name
"""


def _value(text: str) -> float | str:
    try:
        return float(text)
    except ValueError:
        return text


@dataclass(frozen=True)
class Partner:
    """An asset that realises a capability.

    Attributes:
        asset_id: Its id.
        online: Whether its lease is held (``tt:status "online"``).
        constraints: Constraint idShort -> value (numbers as float), e.g.
            ``{"ObjectMassMax": 4.9, "BeltWidth": 0.195}``.
    """

    asset_id: str
    online: bool
    constraints: Mapping[str, float | str] = field(default_factory=lambda: MappingProxyType({}))

    def admits(self, needs: Mapping[str, float]) -> bool:
        """Whether its constraints admit `needs` (name -> value): for each, ``<name>Min`` <=
        value <= ``<name>Max`` where it has these bounds (a bound it lacks does not bind).

        Example: ``{"ObjectMass": 3.5}`` against ``ObjectMassMin = 2.2``,
        ``ObjectMassMax = 3.0`` is not admitted.
        """
        for name, value in needs.items():
            low, high = self.constraints.get(f"{name}Min"), self.constraints.get(f"{name}Max")
            if isinstance(low, float) and value < low:
                return False
            if isinstance(high, float) and value > high:
                return False
        return True


def partners_from_rows(rows: Iterable[Mapping[str, str]]) -> tuple[Partner, ...]:
    """The answer of `partners_query` (rows of variable -> lexical value), one `Partner`
    per asset, sorted by id."""
    found: dict[str, tuple[bool, dict[str, float | str]]] = {}
    for row in rows:
        _, bounds = found.setdefault(row["id"], (row.get("status") == "online", {}))
        if row.get("name"):
            bounds[row["name"]] = _value(row.get("value", ""))
    return tuple(Partner(aid, online, MappingProxyType(bounds))
                 for aid, (online, bounds) in sorted(found.items()))  # fmt: skip


async def find_partners(node: AssetNode, cap: Capability,
                        needs: Mapping[str, float] | None = None, *, online: bool = True,
                        timeout_s: float = 5.0) -> list[Partner] | None:  # fmt: skip
    """The assets that realise `cap` as the knowledge graph knows them (`partners_query`).

    Args:
        node: The asking asset's node (it reaches the graph through its seeds).
        cap: The capability.
        needs: What the task needs of the capability's constraints (`Partner.admits`).
        online: Only the online ones (False: those offline too, with ``online`` False).
        timeout_s: How long the graph may take.

    Returns:
        The partners, sorted by id; None when the graph does not answer.
    """
    try:
        answer = await asyncio.wait_for(node.peers.call("KG", "Query", partners_query(cap)),
                                        timeout_s)  # fmt: skip
    except Exception as exc:
        log.debug("%s: no answer from the knowledge graph (%s): %s", node.desc.asset_id,
                  cap.value, exc)  # fmt: skip
        return None
    return [p for p in partners_from_rows(json.loads(answer))
            if (p.online or not online) and p.admits(needs or {})]  # fmt: skip


async def find_partner_ids(node: AssetNode, cap: Capability, *,
                           online: bool = True) -> list[str]:  # fmt: skip
    """Ids of the assets that realise `cap` (`find_partners`: the online ones, or with
    ``online=False`` all, the online first); while the graph does not answer, those of the
    floor file that offer it (the node's descriptors: what they offer, never their class),
    so that a report or a pose is not held up by the graph."""
    found = await find_partners(node, cap, online=online)
    if found is not None:
        return [p.asset_id for p in sorted(found, key=lambda p: not p.online)]
    return sorted(aid for aid, d in node.descriptors.items()
                  if cap in d.capabilities and aid != node.desc.asset_id)  # fmt: skip
