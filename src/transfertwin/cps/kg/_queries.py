"""Named SPARQL queries of the knowledge graph (Sec. 3.3).

Parameters are bound with ``initBindings`` (never spliced into the text); every query
counts only assets whose ``tt:status`` is "online".
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Iterable, Mapping
from typing import Any

from rdflib import RDF, RDFS
from rdflib.plugins.sparql import prepareQuery
from rdflib.plugins.sparql.parserutils import CompValue
from rdflib.plugins.sparql.sparql import Query

from transfertwin._errors import InputError
from transfertwin.cps.kg._describe import TT

__all__ = [
    "IDLE_TRANSPORT_MODULES",
    "OBJECT_LOCATIONS",
    "PREFIXES",
    "RECEIVERS_AT",
    "VIRTUAL_MODELS_OF",
    "prepared",
    "read_only_select",
]

_NS = {"tt": TT, "rdf": RDF, "rdfs": RDFS}
# rdflib's SPARQL parser (pyparsing) is not thread-safe: parse one query at a time.
_PARSER_LOCK = threading.Lock()

PREFIXES = """\
PREFIX tt: <https://transfertwin.dev/ontology#>
PREFIX rdf: <http://www.w3.org/1999/02/22-rdf-syntax-ns#>
"""

# "Which assets can receive an object at station ?station?": online assets able to
# transfer that stand at the station (its transfer units) or are docked at an online
# transfer unit of it (transport modules).
RECEIVERS_AT = (
    PREFIXES
    + """\
SELECT DISTINCT ?id WHERE {
  { ?asset tt:atStation ?station . }
  UNION
  { ?asset tt:dockedAt ?unit .
    ?unit tt:atStation ?station ;
          tt:status "online" . }
  ?asset tt:hasCapability tt:Transfer ;
         tt:status "online" ;
         tt:assetId ?id .
}
ORDER BY ?id
"""
)

# "Where is every object?": the asset each online object is located at (tt:locatedAt).
OBJECT_LOCATIONS = (
    PREFIXES
    + """\
SELECT ?object ?holder WHERE {
  ?o a tt:Object ;
     tt:status "online" ;
     tt:assetId ?object ;
     tt:locatedAt ?h .
  ?h tt:assetId ?holder .
}
ORDER BY ?object
"""
)

# "Which virtual model mirrors ?target?": online virtual models of the asset.
VIRTUAL_MODELS_OF = (
    PREFIXES
    + """\
SELECT DISTINCT ?id WHERE {
  ?model a tt:VirtualModel ;
         tt:virtualModelOf ?target ;
         tt:status "online" ;
         tt:assetId ?id .
}
ORDER BY ?id
"""
)

# Online transport modules whose operational state is "idle".
IDLE_TRANSPORT_MODULES = (
    PREFIXES
    + """\
SELECT DISTINCT ?id WHERE {
  ?tm a tt:TransportModule ;
      tt:status "online" ;
      tt:operationalState "idle" ;
      tt:assetId ?id .
}
ORDER BY ?id
"""
)


@functools.cache
def prepared(text: str) -> Query:
    """Parse one of the named queries once."""
    with _PARSER_LOCK:
        return prepareQuery(text, initNs=_NS)


def _walk(node: Any) -> Iterable[CompValue]:
    if isinstance(node, CompValue):
        yield node
    if isinstance(node, Mapping):
        for value in node.values():
            yield from _walk(value)
    elif isinstance(node, list | tuple):
        for value in node:
            yield from _walk(value)


def read_only_select(sparql: str) -> Query:
    """Parse a SELECT query; anything else (updates, CONSTRUCT, SERVICE) is refused.

    The last `QUERY_CACHE` texts are parsed once (rdflib's parser takes ~60 ms a query):
    the roles ask the same capability queries again and again
    (`transfertwin.cps.node.partners_query`).
    """
    if not isinstance(sparql, str):
        raise InputError(f"a SPARQL query must be a string, got {type(sparql).__name__}")
    return _parse_select(sparql)


#: How many distinct query texts `read_only_select` keeps parsed.
QUERY_CACHE = 128


@functools.lru_cache(maxsize=QUERY_CACHE)
def _parse_select(sparql: str) -> Query:
    try:
        with _PARSER_LOCK:
            query = prepareQuery(sparql, initNs=_NS)
    except Exception as exc:  # the parser raises several unrelated types
        raise InputError(f"not a SPARQL SELECT query (the graph is read-only): {exc}") from exc
    if query.algebra.name != "SelectQuery":
        raise InputError(f"only SELECT queries are answered, got {query.algebra.name}")
    if any(part.name == "ServiceGraphPattern" for part in _walk(query.algebra)):
        raise InputError("SERVICE (federated) queries are refused")
    return query
