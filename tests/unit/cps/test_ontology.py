"""Every semanticId an asset's AAS carries is defined by the ontology (Sec. 3.3): a label,
a definition and its place in the class hierarchy (a subclass of ``tt:AasConcept``); the
SHACL shapes check the ontology's concepts (KG-9) and the capabilities an asset claims
(KG-10)."""

from __future__ import annotations

import pytest
from basyx.aas import model
from rdflib import OWL, RDF, RDFS, SKOS, Graph, Literal, URIRef

from tests.unit.cps._served import FLOORS, served
from transfertwin._errors import InputError
from transfertwin.cps.aas import demo_descriptors
from transfertwin.cps.kg import TT, KnowledgeGraph, describe, first_violation, load_ontology


def semantic_ids(element: object) -> set[str]:
    """The semanticIds of an element and of everything below it (submodels, collections,
    operation variables)."""
    found = set()
    if isinstance(element, model.HasSemantics) and element.semantic_id is not None:
        found |= {k.value for k in element.semantic_id.key}
    children = []
    if isinstance(element, model.Submodel):
        children = list(element.submodel_element)
    elif isinstance(element, model.SubmodelElementCollection):
        children = list(element.value)
    elif isinstance(element, model.Operation):
        children = [*element.input_variable, *element.output_variable,
                    *element.in_output_variable]  # fmt: skip
    for child in children:
        found |= semantic_ids(child)
    return found


@pytest.fixture(scope="module")
def used() -> set[str]:
    """Every semanticId of every AAS the demo floor (on the plant) and the large floor serve."""
    return {
        sid
        for make in FLOORS.values()
        for rep in served(make())
        for sm in rep.submodels
        for sid in semantic_ids(sm)
    }


@pytest.fixture(scope="module")
def ontology() -> Graph:
    return load_ontology()


def concept_classes(ontology: Graph) -> set[URIRef]:
    return set(ontology.transitive_subjects(RDFS.subClassOf, TT.AasConcept))


def test_the_walk_reaches_every_kind_of_element(used: set[str]) -> None:
    for name in ("Identification", "AssetId", "Transfer", "realizedBy", "BeltWidth",
                 "PossessedBy", "TransferHistoryJson", "SetBeltSpeed", "RunTransfer"):  # fmt: skip
        assert f"{TT}{name}" in used, name


def test_every_semantic_id_is_a_defined_concept(used: set[str], ontology: Graph) -> None:
    classes = concept_classes(ontology)
    undefined = []
    for sid in sorted(used):
        node = URIRef(sid)
        labelled = ontology.value(node, RDFS.label) is not None
        defined = (node, SKOS.definition, None) in ontology
        placed = any(c in classes for c in ontology.objects(node, RDF.type))
        if not (labelled and defined and placed):
            undefined.append(sid)
    assert undefined == []


def test_the_concept_classes_form_one_hierarchy(ontology: Graph) -> None:
    classes = concept_classes(ontology)
    assert {TT.SubmodelConcept, TT.IdentificationProperty, TT.StateVariable,
            TT.OperationConcept, TT.Capability, TT.CapabilityConstraint,
            TT.CapabilityPatternConcept} <= classes  # fmt: skip
    for cls in classes:
        assert (cls, RDF.type, OWL.Class) in ontology, cls
        assert ontology.value(cls, RDFS.label) is not None, cls


def test_the_ontology_meets_its_own_shapes(ontology: Graph) -> None:
    assert first_violation(ontology) is None


def test_a_concept_without_definition_breaks_kg9(ontology: Graph) -> None:
    broken = Graph() + ontology
    broken.remove((TT.BeltWidth, SKOS.definition, None))
    violation = first_violation(broken)
    assert violation is not None and "KG-9" in violation and "BeltWidth" in violation


def test_kg9_reaches_concepts_through_the_subclasses() -> None:
    g = Graph()
    g.add((TT.StateVariable, RDFS.subClassOf, TT.AasConcept))
    g.add((TT.Bogus, RDF.type, TT.StateVariable))
    g.add((TT.Bogus, RDFS.label, Literal("bogus")))
    assert "KG-9" in (first_violation(g) or "")


def test_kg10_an_asset_claims_only_capabilities_of_the_ontology() -> None:
    kg = KnowledgeGraph()
    desc = next(d for d in demo_descriptors() if d.asset_id == "TU_A")
    kg.join(desc)  # its own capabilities are the ontology's
    description = describe(desc)
    description.add((URIRef("https://transfertwin.dev/ids/asset/TU_A"), TT.hasCapability,
                     TT.Teleport))  # fmt: skip
    before = kg.triples()
    with pytest.raises(InputError, match="KG-10"):
        kg.join_graph(description)
    assert kg.triples() == before
