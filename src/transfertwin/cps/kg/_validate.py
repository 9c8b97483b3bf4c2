"""Validation of asset descriptions before they enter the knowledge graph (Sec. 3.3).

Shape rules (``data/ontology/shapes.ttl``; messages carry the id):

* KG-1 an asset has exactly one ``tt:assetId`` literal and one ``tt:status``;
* KG-2 an asset is typed ``tt:PhysicalAsset``, ``tt:LogicalAsset`` or ``tt:VirtualModel``;
* KG-3 a physical asset or virtual model has exactly one ``tt:assetType``;
* KG-4 a virtual model has exactly one ``tt:virtualModelOf``;
* KG-5 a transfer unit is at exactly one ``tt:Station``;
* KG-6 a transport module is docked at no more than one ``tt:TransferUnit``;
* KG-7 an interface has exactly one ``tt:endpointUrl`` matching ``^opc\\.tcp://``;
* KG-8 an object is located at (``tt:locatedAt``) no more than one asset;
* KG-9 every concept an AAS names (``tt:AasConcept``) has a label and a ``skos:definition``
  (a rule of the ontology itself: `tests/unit/cps/test_ontology.py` checks it);
* KG-10 an asset's ``tt:hasCapability`` values are ``tt:Capability`` individuals;
* KG-11 a capability constraint's value (``tt:ConstraintValue``) binds one
  ``tt:Capability`` (``tt:ofCapability``), names one ``tt:CapabilityConstraint``
  (``tt:constraint``) and has one literal ``tt:value``.

Beyond the shapes, a description must be about one asset whose IRI matches its id, be
online, and state nothing about nodes other than the asset, its own interfaces and its
capabilities' constraints (IRIs under the asset's IRI) and the ``rdf:type`` of its
stations; so no asset can rewrite another.
"""

from __future__ import annotations

import functools
from importlib import resources

import pyshacl
from rdflib import RDF, Graph, Literal, URIRef
from rdflib.namespace import SH

from transfertwin._errors import InputError
from transfertwin.cps.kg._describe import ASSET_CLASSES, TT, asset_iri

__all__ = ["asset_node", "first_violation", "validate_description"]


@functools.cache
def _shapes() -> Graph:
    text = resources.files("transfertwin.data").joinpath("ontology", "shapes.ttl").read_text()
    return Graph().parse(data=text, format="turtle")


def first_violation(data: Graph, focus: set[URIRef] | None = None) -> str | None:
    """Validate ``data`` against the shapes KG-1 … KG-11.

    Args:
        data: The data graph.
        focus: Report only violations about these nodes (default: all). Context nodes
            (e.g. a docking partner, present only with its types) are not checked.

    Returns:
        None if it conforms, else the first violation (sorted, so deterministic) as
        '<focus node> <path>: <message>'.
    """
    conforms, results, _ = pyshacl.validate(data, shacl_graph=_shapes(), inference="none")
    if conforms:
        return None
    results.namespace_manager.bind("tt", TT)
    found: list[str] = []
    for result in results.subjects(RDF.type, SH.ValidationResult):
        node = results.value(result, SH.focusNode)
        if focus is not None and node not in focus:
            continue
        path = results.value(result, SH.resultPath)
        message = results.value(result, SH.resultMessage)
        shown = path.n3(results.namespace_manager) if path is not None else ""
        found.append(f"<{node}> {shown}: {message}")
    return min(found, default=None)


def asset_node(description: Graph) -> tuple[URIRef, str]:
    """The single asset a description is about, and its id (or IRI tail) for messages.

    Raises:
        InputError: No asset node, several, or a blank node.
    """
    nodes = set(description.subjects(TT.assetId, None))
    nodes |= {s for s, c in description.subject_objects(RDF.type) if c in ASSET_CLASSES}
    if len(nodes) != 1 or not isinstance(next(iter(nodes)), URIRef):
        raise InputError(f"a description must be about exactly one asset IRI, found {len(nodes)}")
    node = next(iter(nodes))
    ids = list(description.objects(node, TT.assetId))
    name = str(ids[0]) if len(ids) == 1 else str(node).rsplit("/", 1)[-1]
    return node, name


def validate_description(description: Graph, graph: Graph) -> tuple[URIRef, str]:
    """Check a description against the shapes and the scope rules.

    The shapes check the description's nodes, seeing also the ``rdf:type`` triples that
    ``graph`` holds for the nodes it refers to (so KG-6 can tell that a docking partner is
    a transfer unit).

    Args:
        description: The asset's description.
        graph: The current knowledge graph (read only; the caller holds its lock).

    Returns:
        The asset's IRI and id.

    Raises:
        InputError: Naming the asset and the first violation.
    """
    node, name = asset_node(description)
    _check_subjects(description, graph, node, name)
    data = Graph() + description
    for obj in set(description.objects()):
        if isinstance(obj, URIRef) and obj != node:
            for cls in graph.objects(obj, RDF.type):
                data.add((obj, RDF.type, cls))
    violation = first_violation(data, set(description.subjects()))
    if violation is not None:
        raise InputError(f"asset {name}: description rejected: {violation}")
    if node != asset_iri(name):
        raise InputError(f"asset {name}: its IRI must be {asset_iri(name)}, got {node}")
    if description.value(node, TT.status) != Literal("online"):
        raise InputError(f"asset {name}: a joining asset must be online")
    return node, name


def _check_subjects(description: Graph, graph: Graph, node: URIRef, name: str) -> None:
    own = set(description.objects(node, TT.hasInterface))
    own |= set(description.objects(node, TT.hasConstraint))
    stations = set(description.objects(node, TT.atStation))
    for subject in set(description.subjects()) - {node}:
        own_interface = subject in own and str(subject).startswith(f"{node}/")
        station_type_only = subject in stations and set(description.predicate_objects(subject)) <= {
            (RDF.type, TT.Station)
        }
        is_asset = (subject, TT.assetId, None) in graph
        if is_asset or not (own_interface or station_type_only):
            raise InputError(
                f"asset {name}: a description may state only the asset, its interfaces "
                f"and the type of its stations, not <{subject}>"
            )
