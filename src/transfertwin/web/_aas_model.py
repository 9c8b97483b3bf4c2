"""The floor's shells and submodels as the AAS HTTP API reads them (IDTA-01002 Part 2, the
read profiles SSP-002 of the shell repository and the submodel repository): a pure answer
to a GET, from basyx objects.

`AasRepository.answer` takes the path under the API's prefix and the query parameters and
returns an `Answer` (status and JSON body): identifiers in paths and queries are base64url
encoded (with or without padding), an element is addressed by its idShort path
(``TransferRelations.Constraints.BeltWidth``), lists are paged (``limit``, ``cursor``,
``paging_metadata``), and the modifiers ``$metadata``, ``$value``, ``$reference`` and
``$path`` give the serialisations Part 2 defines. Every error is Part 2's ``Result``
(``{"messages": [...]}``) with a 4xx status. Serialisation of the model is basyx's.
"""

from __future__ import annotations

import base64
import binascii
import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

from basyx.aas import model
from basyx.aas.adapter.json import AASToJsonEncoder

__all__ = ["PROFILES", "AasApiError", "AasRepository", "Answer", "b64url", "decode_b64url"]

_SSP = "https://admin-shell.io/aas/API/3/0/"
#: The service profiles the API claims (``/description``), each checked in CI by the IDTA's
#: test engine.
PROFILES = (
    f"{_SSP}AssetAdministrationShellRepositoryServiceSpecification/SSP-002",
    f"{_SSP}SubmodelRepositoryServiceSpecification/SSP-002",
)
_LEVELS = ("deep", "core")
_EXTENTS = ("withoutBlobValue", "withBlobValue")
_MODIFIERS = ("$metadata", "$value", "$reference", "$path")
#: Elements whose value-only and metadata forms Part 2 does not define.
_NO_VALUE = (model.Operation, model.Capability)


class AasApiError(Exception):
    """A request the API answers with a 4xx status and Part 2's ``Result``."""

    def __init__(self, status: int, text: str) -> None:
        super().__init__(text)
        self.status = status
        self.text = text


@dataclass(frozen=True)
class Answer:
    """A JSON answer: HTTP status and body."""

    status: int
    body: Any


def b64url(text: str) -> str:
    """`text` base64url encoded without padding (an identifier in a path)."""
    return base64.urlsafe_b64encode(text.encode()).decode().rstrip("=")


def decode_b64url(value: str, what: str) -> str:
    """A base64url (RFC 4648 §5) encoded UTF-8 string, padded or not; 400 otherwise."""
    padded = value + "=" * (-len(value) % 4)
    try:
        return base64.b64decode(padded, altchars=b"-_", validate=True).decode("utf-8")
    except (binascii.Error, ValueError):
        raise AasApiError(400, f"{what} is not base64url-encoded UTF-8: {value[:60]!r}") from None


def error_body(status: int, text: str) -> dict[str, Any]:
    """Part 2's ``Result`` with one error message."""
    now = datetime.now(UTC).isoformat(timespec="seconds")
    return {"messages": [{"code": str(status), "messageType": "Error", "text": text,
                          "timestamp": now}]}  # fmt: skip


def _json(obj: object) -> Any:
    """A basyx object as Part 1's JSON (a dict), by basyx's encoder."""
    return json.loads(json.dumps(obj, cls=AASToJsonEncoder))


def _one(query: Mapping[str, Sequence[str]], name: str) -> str | None:
    values = query.get(name) or []
    return values[-1] if values else None


def _choice(query: Mapping[str, Sequence[str]], name: str, allowed: tuple[str, ...]) -> str:
    value = _one(query, name)
    if value is None:
        return allowed[0]
    if value not in allowed:
        raise AasApiError(400, f"{name} must be one of {', '.join(allowed)}, got {value[:40]!r}")
    return value


def _page(items: list[Any], query: Mapping[str, Sequence[str]]) -> dict[str, Any]:
    """``{"paging_metadata": {...}, "result": [...]}``: `limit` items from `cursor` on."""
    limit_text, cursor = _one(query, "limit"), _one(query, "cursor")
    try:
        limit = int(limit_text) if limit_text is not None else len(items)
        start = int(cursor) if cursor is not None else 0
    except ValueError:
        raise AasApiError(400, "limit and cursor must be integers") from None
    if limit_text is not None and limit < 1:
        raise AasApiError(400, f"limit must be a positive integer, got {limit}")
    if not 0 <= start <= len(items):
        raise AasApiError(400, f"cursor {cursor!r} is out of range")
    end = start + limit
    meta = {"cursor": str(end)} if end < len(items) else {}
    return {"paging_metadata": meta, "result": items[start:end]}


def _typed(value: object) -> object:
    """A Property's value as JSON (numbers and booleans as such, the rest as text)."""
    if value is None or isinstance(value, bool | int | float):
        return value
    return str(value)


def value_only(element: model.SubmodelElement) -> Any:
    """The value-only serialisation of an element (Part 2 §11.4.3); None for those that
    have none (operations, capabilities)."""
    if isinstance(element, model.Property):
        return _typed(element.value)
    if isinstance(element, model.SubmodelElementCollection):
        return _values_of(element.value)
    if isinstance(element, model.SubmodelElementList):
        return [value_only(e) for e in element.value]
    if isinstance(element, model.RelationshipElement):
        return {"first": _json(element.first), "second": _json(element.second)}
    if isinstance(element, model.ReferenceElement):
        return _json(element.value) if element.value is not None else None
    if isinstance(element, model.MultiLanguageProperty):
        return [{lang: text} for lang, text in (element.value or {}).items()]
    if isinstance(element, model.Range):
        return {"min": _typed(element.min), "max": _typed(element.max)}
    return None


def _values_of(elements: Iterable[model.SubmodelElement]) -> dict[str, Any]:
    return {e.id_short: value_only(e) for e in elements if not isinstance(e, _NO_VALUE)}


def _children(element: model.Referable) -> list[model.SubmodelElement]:
    if isinstance(element, model.Submodel):
        return list(element.submodel_element)
    if isinstance(element, model.SubmodelElementCollection | model.SubmodelElementList):
        return list(element.value)
    return []


def id_short_paths(element: model.Referable, prefix: str, deep: bool) -> list[str]:
    """The idShort paths of the elements below `element` (``A.B``; ``L[0]`` in a list)."""
    out: list[str] = []
    for i, child in enumerate(_children(element)):
        if isinstance(element, model.SubmodelElementList):
            path = f"{prefix}[{i}]"
        else:
            path = f"{prefix}.{child.id_short}" if prefix else str(child.id_short)
        out.append(path)
        if deep:
            out += id_short_paths(child, path, deep)
    return out


def _core(data: dict[str, Any]) -> dict[str, Any]:
    """``level=core``: the direct children only (a child collection without its value)."""
    key = "submodelElements" if "submodelElements" in data else "value"
    children = data.get(key)
    if isinstance(children, list):
        data[key] = [{k: v for k, v in c.items() if not (k == "value" and isinstance(v, list))}
                     for c in children]  # fmt: skip
    return data


def _metadata(data: dict[str, Any]) -> dict[str, Any]:
    """An element's or submodel's metadata: everything but its value or elements."""
    drop = {"value", "valueId", "submodelElements", "first", "second", "annotations",
            "min", "max", "statements", "inputVariables", "outputVariables",
            "inoutputVariables"}  # fmt: skip
    return {k: v for k, v in data.items() if k not in drop}


class AasRepository:
    """The shells and submodels served (basyx objects; their Property values are updated
    in place with live values by the API before it answers).

    Args:
        shells: The shells, served in id order.
        submodels: Every submodel a shell references.
    """

    def __init__(self, shells: Iterable[model.AssetAdministrationShell],
                 submodels: Iterable[model.Submodel]) -> None:  # fmt: skip
        self.shells = {s.id: s for s in sorted(shells, key=lambda s: s.id)}
        self.submodels = {s.id: s for s in sorted(submodels, key=lambda s: s.id)}

    # -- what a path touches (the API reads those assets' values first) --------------------
    def touched(self, path: str) -> list[model.Submodel]:
        """The submodels an answer to `path` shows (all of them where it lists)."""
        parts = [p for p in path.split("/") if p]
        try:
            if parts[:1] == ["shells"] and len(parts) >= 2 and not parts[1].startswith("$"):
                shell = self._shell(parts[1])
                if len(parts) >= 4 and parts[2] == "submodels":
                    return [self._submodel(parts[3], shell)]
                return [self.submodels[i] for i in self._refs(shell) if i in self.submodels]
            if parts[:1] == ["submodels"] and len(parts) >= 2 and not parts[1].startswith("$"):
                return [self._submodel(parts[1])]
        except AasApiError:
            return []
        return list(self.submodels.values())

    # -- the answer -------------------------------------------------------------------------
    def answer(self, path: str, query: Mapping[str, Sequence[str]]) -> Answer:
        """The answer to ``GET <prefix>/<path>?<query>`` (errors as Part 2's Result)."""
        try:
            return Answer(200, self._route([p for p in path.split("/") if p], query))
        except AasApiError as exc:
            return Answer(exc.status, error_body(exc.status, exc.text))

    def _route(self, parts: list[str], query: Mapping[str, Sequence[str]]) -> Any:
        head, rest = (parts[0], parts[1:]) if parts else ("", [])
        if head == "description" and not rest:
            return {"profiles": list(PROFILES)}
        if head == "serialization" and not rest:
            return self._serialization(query)
        if head == "shells":
            return self._shells(rest, query)
        if head == "submodels":
            return self._submodels(rest, query, None)
        raise AasApiError(404, f"no such resource: /{'/'.join(parts)[:80]}")

    def _shells(self, rest: list[str], query: Mapping[str, Sequence[str]]) -> Any:
        if not rest or rest == ["$reference"]:
            shells = self._filtered_shells(query)
            if rest:
                return _page([_json(model.ModelReference.from_referable(s)) for s in shells],
                             query)  # fmt: skip
            return _page([_json(s) for s in shells], query)
        shell = self._shell(rest[0])
        tail = rest[1:]
        if not tail:
            return _json(shell)
        if tail == ["$reference"]:
            return _json(model.ModelReference.from_referable(shell))
        if tail == ["asset-information"]:
            return _json(shell.asset_information)
        if tail == ["asset-information", "thumbnail"]:
            raise AasApiError(404, f"{shell.id_short} has no thumbnail")
        if tail == ["submodel-refs"]:
            refs = [r for r in shell.submodel if r.key[-1].value in self.submodels]
            refs.sort(key=lambda r: r.key[-1].value)
            return _page([_json(r) for r in refs], query)
        if tail[0] == "submodels":
            return self._submodels(tail[1:], query, shell)
        raise AasApiError(404, f"no such resource below shell {shell.id_short}")

    def _filtered_shells(
        self, query: Mapping[str, Sequence[str]]
    ) -> list[model.AssetAdministrationShell]:
        shells = list(self.shells.values())
        id_short = _one(query, "idShort")
        if id_short is not None:
            shells = [s for s in shells if s.id_short == id_short]
        for encoded in query.get("assetIds") or []:
            wanted = self._asset_id(encoded)
            shells = [s for s in shells if wanted in _asset_ids(s)]
        return shells

    @staticmethod
    def _asset_id(encoded: str) -> tuple[str, str]:
        text = decode_b64url(encoded, "assetIds")
        try:
            doc = json.loads(text)
            return str(doc["name"]), str(doc["value"])
        except (ValueError, KeyError, TypeError):
            raise AasApiError(400, "assetIds must encode a SpecificAssetId "
                                   '{"name": ..., "value": ...}') from None  # fmt: skip

    def _submodels(self, rest: list[str], query: Mapping[str, Sequence[str]],
                   shell: model.AssetAdministrationShell | None) -> Any:  # fmt: skip
        if shell is None and (not rest or rest[0] in _MODIFIERS):
            modifier = rest[0] if rest else None
            if len(rest) > 1:
                raise AasApiError(404, "no such resource below /submodels")
            subs = self._filtered_submodels(query)
            level = _choice(query, "level", _LEVELS)
            _choice(query, "extent", _EXTENTS)
            if modifier == "$path":  # one list of idShort paths, paged
                return _page([p for sm in subs for p in self._form(sm, modifier, level)], query)
            return _page([self._form(sm, modifier, level) for sm in subs], query)
        if not rest:
            raise AasApiError(404, "GET /shells/{id}/submodels is not a read operation here")
        sm = self._submodel(rest[0], shell)
        tail = rest[1:]
        if tail[:1] == ["submodel-elements"]:
            return self._elements(sm, tail[1:], query)
        if len(tail) > 1 or (tail and tail[0] not in _MODIFIERS):
            raise AasApiError(404, f"no such resource below submodel {sm.id_short}")
        level = _choice(query, "level", _LEVELS)
        _choice(query, "extent", _EXTENTS)
        return self._form(sm, tail[0] if tail else None, level)

    def _filtered_submodels(self, query: Mapping[str, Sequence[str]]) -> list[model.Submodel]:
        subs = list(self.submodels.values())
        id_short = _one(query, "idShort")
        if id_short is not None:
            subs = [s for s in subs if s.id_short == id_short]
        semantic = _one(query, "semanticId")
        if semantic is not None:
            wanted = decode_b64url(semantic, "semanticId")
            subs = [s for s in subs if s.semantic_id and s.semantic_id.key[0].value == wanted]
        return subs

    def _form(self, obj: model.Referable, modifier: str | None, level: str) -> Any:
        """`obj` (a submodel or an element) in the form `modifier` asks for."""
        if modifier == "$reference":
            return _json(model.ModelReference.from_referable(obj))
        if modifier == "$path":
            if isinstance(obj, model.Submodel):
                return id_short_paths(obj, "", level == "deep")
            if not isinstance(
                obj, model.SubmodelElementCollection | model.SubmodelElementList | model.Entity
            ):
                raise AasApiError(400, f"$path is defined for submodels and collections, not "
                                       f"a {type(obj).__name__}")  # fmt: skip
            own = _element_path(obj)
            return [own, *id_short_paths(obj, own, level == "deep")]
        if isinstance(obj, _NO_VALUE) and modifier in ("$value", "$metadata"):
            raise AasApiError(400, f"a {type(obj).__name__} has no {modifier[1:]} form")
        if modifier == "$value":
            if isinstance(obj, model.Submodel):
                return _values_of(obj.submodel_element)
            return {obj.id_short: value_only(obj)}
        data = _json(obj)
        if modifier == "$metadata":
            return _metadata(data)
        return _core(data) if level == "core" else data

    def _listed(self, element: model.SubmodelElement, modifier: str | None, level: str) -> Any:
        """An element as an entry of a list of `modifier`'s form."""
        if not isinstance(element, _NO_VALUE) or modifier not in ("$value", "$metadata"):
            return self._form(element, modifier, level)
        if modifier == "$value":
            return {element.id_short: None}
        return _metadata(_json(element))

    def _elements(self, sm: model.Submodel, rest: list[str],
                  query: Mapping[str, Sequence[str]]) -> Any:  # fmt: skip
        level = _choice(query, "level", _LEVELS)
        _choice(query, "extent", _EXTENTS)
        if not rest or rest[0] in _MODIFIERS:
            if len(rest) > 1:
                raise AasApiError(404, "no such resource below submodel-elements")
            modifier = rest[0] if rest else None
            if modifier == "$path":
                return _page(id_short_paths(sm, "", level == "deep"), query)
            # in a list every element has an entry: one without a value form (an operation,
            # a capability) is all metadata, and null as a value
            return _page([self._listed(e, modifier, level) for e in sm.submodel_element], query)
        element = _element(sm, rest[0])
        tail = rest[1:]
        if tail == ["attachment"]:
            raise AasApiError(404, f"{rest[0]} is no File or Blob with an attachment")
        if len(tail) > 1 or (tail and tail[0] not in _MODIFIERS):
            raise AasApiError(404, f"no such resource below element {rest[0][:60]}")
        return self._form(element, tail[0] if tail else None, level)

    def _serialization(self, query: Mapping[str, Sequence[str]]) -> dict[str, Any]:
        """An Environment of the shells and submodels asked for (all, where none are)."""
        cds = _one(query, "includeConceptDescriptions")
        if cds is not None and cds.lower() not in ("true", "false"):
            raise AasApiError(400, f"includeConceptDescriptions must be true or false, "
                                   f"got {cds[:20]!r}")  # fmt: skip
        aas_ids = [decode_b64url(v, "aasIds") for v in query.get("aasIds") or []]
        sm_ids = [decode_b64url(v, "submodelIds") for v in query.get("submodelIds") or []]
        for i in aas_ids:
            self._shell(b64url(i))
        for i in sm_ids:
            self._submodel(b64url(i))
        whole = not aas_ids and not sm_ids
        shells = list(self.shells) if whole else aas_ids
        subs = list(self.submodels) if whole else sm_ids
        env: dict[str, Any] = {}
        if shells:
            env["assetAdministrationShells"] = [_json(self.shells[i]) for i in shells]
        if subs:
            env["submodels"] = [_json(self.submodels[i]) for i in subs]
        return env

    # -- lookups --------------------------------------------------------------------------
    def _shell(self, encoded: str) -> model.AssetAdministrationShell:
        aas_id = decode_b64url(encoded, "the shell's identifier")
        if aas_id not in self.shells:
            raise AasApiError(404, f"no shell {aas_id[:100]!r}")
        return self.shells[aas_id]

    @staticmethod
    def _refs(shell: model.AssetAdministrationShell) -> list[str]:
        return sorted(r.key[-1].value for r in shell.submodel)

    def _submodel(
        self, encoded: str, shell: model.AssetAdministrationShell | None = None
    ) -> model.Submodel:
        sm_id = decode_b64url(encoded, "the submodel's identifier")
        if sm_id not in self.submodels or (shell is not None and sm_id not in self._refs(shell)):
            where = f" in shell {shell.id_short}" if shell is not None else ""
            raise AasApiError(404, f"no submodel {sm_id[:100]!r}{where}")
        return self.submodels[sm_id]


def _asset_ids(shell: model.AssetAdministrationShell) -> set[tuple[str, str]]:
    info = shell.asset_information
    ids = {(s.name, s.value) for s in info.specific_asset_id}
    if info.global_asset_id:
        ids.add(("globalAssetId", info.global_asset_id))
    return ids


def _element(sm: model.Submodel, path: str) -> model.SubmodelElement:
    """The element at idShort path `path` (``A.B``, ``L[2]``) of `sm`; 404 if none."""
    node: model.Referable = sm
    parts = path.replace("[", ".[").split(".")
    if not all(parts):
        raise AasApiError(400, f"malformed idShort path {path[:80]!r}")
    for part in parts:
        children = _children(node)
        if part.startswith("["):
            try:
                node = children[int(part[1:-1])] if part.endswith("]") else None
            except (ValueError, IndexError):
                node = None
        else:
            node = next((c for c in children if c.id_short == part), None)
        if node is None:
            raise AasApiError(404, f"no element {path[:80]!r} in submodel {sm.id_short}")
    return node  # type: ignore[return-value]


def _element_path(element: model.Referable) -> str:
    """The idShort path of an element inside its submodel."""
    parts: list[str] = []
    node: Any = element
    while node is not None and not isinstance(node, model.Submodel):
        parent = node.parent
        if isinstance(parent, model.SubmodelElementList):
            parts.append(f"[{list(parent.value).index(node)}]")
        else:
            parts.append(f".{node.id_short}")
        node = parent
    return "".join(reversed(parts)).lstrip(".")
