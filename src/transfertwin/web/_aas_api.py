"""The AAS HTTP API of the floor (IDTA-01002 Part 2, read profiles SSP-002 of the shell
repository and the submodel repository), served by the console under `AAS_API_PREFIX`.

The shells and submodels are the floor's own: each asset's AAS as its node builds it
(`transfertwin.cps.build_representation` over the floor file's descriptors, with the
endpoint the asset serves at), and every Property's value is the one the asset's OPC UA
server holds, read over the console's viewer session when a request shows it (at most once
per live period per asset). Where an asset is offline, its OperationalData values are null:
nothing stale is shown as current. Operations are invoked over OPC UA, not here: the API is
read-only (any other method: 405).
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

from basyx.aas import model

from transfertwin._errors import InputError
from transfertwin.cps import build_representation
from transfertwin.cps.floor import load_floor
from transfertwin.web._aas_model import AasApiError, AasRepository, Answer, b64url, error_body
from transfertwin.web._gateway import CpsGateway

__all__ = ["AAS_API_PREFIX", "AasApi", "repository_of"]

log = logging.getLogger("transfertwin.web")

#: Where the console serves the AAS HTTP API (Part 2's ``/api/v3.0`` under its own name).
AAS_API_PREFIX = "/aas-api/v3.0"


def repository_of(floor_file: Path, endpoints: Mapping[str, str]) -> AasRepository:
    """The shells and submodels of the assets in `endpoints` (asset id -> OPC UA endpoint),
    as the floor file `floor_file` describes them.

    Raises:
        InputError: The floor file is missing or invalid.
    """
    shells, submodels = [], []
    for desc in load_floor(floor_file, check_cores=False).descriptors():
        if desc.asset_id not in endpoints:
            continue
        try:
            rep = build_representation(desc, endpoint=endpoints[desc.asset_id])
        except InputError as exc:  # an asset without a representation (type A)
            log.debug("no AAS for %s: %s", desc.asset_id, exc)
            continue
        shells.append(rep.shell)
        submodels += rep.submodels
    return AasRepository(shells, submodels)


def _properties(element: model.Referable, prefix: str) -> list[tuple[str, model.Property]]:
    """(node key ``<submodel>.<path>``, Property) of every Property below `element`."""
    out: list[tuple[str, model.Property]] = []
    children = (element.submodel_element if isinstance(element, model.Submodel)
                else getattr(element, "value", ()))  # fmt: skip
    if isinstance(element, model.Property):
        return [(prefix, element)]
    if not isinstance(element, model.Submodel | model.SubmodelElementCollection):
        return out
    for child in children:
        out += _properties(child, f"{prefix}.{child.id_short}")
    return out


def _set(prop: model.Property, value: object) -> None:
    """Set a Property's value to what the server holds, in its value type (None if it does
    not fit)."""
    try:
        prop.value = None if value is None else prop.value_type(value)
    except (TypeError, ValueError):
        prop.value = None


class AasApi:
    """The API's answers for one console: the floor's repository with live values.

    Args:
        gateway: The console's view of the running floor (its sessions read the values).
    """

    def __init__(self, gateway: CpsGateway) -> None:
        self.gateway = gateway
        self._repo: AasRepository | None = None
        self._stamp: tuple[object, ...] | None = None
        self._asset_of: dict[str, str] = {}  # submodel id -> asset id
        self._read: dict[str, float] = {}  # asset id -> monotonic time of its last read

    def repository(self) -> AasRepository:
        """The repository of the floor now running (built again when cps.json changes or an
        asset joins, leaves the floor or moves)."""
        gw = self.gateway
        endpoints = {a["id"]: a["endpoint"] for a in gw.assets() if a.get("endpoint")}
        stamp = (gw.info.stamp, tuple(sorted(endpoints.items())))
        if self._repo is None or self._stamp != stamp:
            try:
                info = json.loads((gw.workdir / "cps.json").read_text())
            except (OSError, ValueError):
                raise AasApiError(404, "the CPS is not running (no cps.json)") from None
            if not info.get("floor"):
                raise AasApiError(404, "this console reaches a floor without its floor file "
                                       "(web --graph): it serves no AAS API")  # fmt: skip
            try:
                repo = repository_of(Path(info["floor"]), endpoints)
            except InputError as exc:
                raise AasApiError(404, f"the floor's AAS cannot be built: {exc}") from None
            self._asset_of = {sm_id: shell.id_short for shell in repo.shells.values()
                              for sm_id in (r.key[-1].value for r in shell.submodel)}  # fmt: skip
            self._repo, self._stamp, self._read = repo, stamp, {}
        return self._repo

    def shell_path(self, aid: str) -> str | None:
        """The API's path of asset `aid`'s shell (None where the API serves none)."""
        try:
            repo = self.repository()
        except AasApiError:
            return None
        shell = next((s for s in repo.shells.values() if s.id_short == aid), None)
        return None if shell is None else f"{AAS_API_PREFIX}/shells/{b64url(shell.id)}"

    async def answer(self, path: str, query: Mapping[str, Sequence[str]]) -> Answer:
        """The answer to ``GET <prefix>/<path>``, its Property values read live first."""
        try:
            repo = self.repository()
        except AasApiError as exc:
            return Answer(exc.status, error_body(exc.status, exc.text))
        assets = {self._asset_of[sm.id] for sm in repo.touched(path) if sm.id in self._asset_of}
        for aid in sorted(assets):
            await self._refresh(repo, aid)
        return repo.answer(path, query)

    async def _refresh(self, repo: AasRepository, aid: str) -> None:
        """Read the asset's Property values from its server (at most once per period)."""
        now = time.monotonic()
        if now - self._read.get(aid, -1e9) < self.gateway.period_s:
            return
        self._read[aid] = now
        props = [kp for sm_id, owner in self._asset_of.items() if owner == aid
                 for kp in _properties(repo.submodels[sm_id],
                                       str(repo.submodels[sm_id].id_short))]  # fmt: skip
        try:
            values = await self.gateway.read_variables(aid, [k for k, _ in props])
        except LookupError:  # offline: what it reports now is unknown
            for key, prop in props:
                if key.startswith("OperationalData."):
                    prop.value = None
            return
        except Exception as exc:  # a read that failed: the values stay as they were
            log.debug("AAS API: reading %s failed: %s", aid, exc)
            return
        for key, prop in props:
            if key in values:
                _set(prop, values[key])
