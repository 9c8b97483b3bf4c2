"""A calibration campaign (`CampaignJob`) over physical units backed by an emulated plant:
stopped mid-way, resumed from its journal without running an E^P twice, finished with the
rehearsal's outputs and each object's predictions of both legs."""

from __future__ import annotations

import json
import threading

import pytest

from transfertwin._errors import InputError
from transfertwin.cps.apps import CampaignJob, CampaignRequest
from transfertwin.cps.dispatch import campaign_advice, campaign_predictions
from transfertwin.plant import EmulatedPlant, PlantRequest
from transfertwin.rehearsal import REHEARSAL_KEYS, calibration_design

UNITS = ("TU_A_P", "TU_B_P")
REQUEST = json.dumps({"objects": ["o1", "o23"], "experiments": 6, "runs": 1,
                      "validation_runs": 1, "theta_step": 180, "depths_mm": [16],
                      "seed": 3})  # fmt: skip


class Units:
    """`run_one` of the campaign: each E^P one cycle of an emulated plant at the unit's
    station (what a physical unit's ``RunTransfer`` runs); counts what it ran."""

    def __init__(self, plant: EmulatedPlant) -> None:
        self.plant = plant
        self.ran: list[tuple[str, str, str, str, int]] = []
        self.lock = threading.Lock()
        self.after: tuple[int, object] | None = None  # (n, callback): called after the nth

    def __call__(self, unit: str, obj: str, face: str, conveyor: str, theta: int) -> dict:
        station = unit.removesuffix("_P")
        with self.lock:  # one plant, one simulation at a time (as `PhysicalPlant.cycle`)
            (row,) = self.plant.operate([PlantRequest(obj, face, conveyor, theta, station)])
            self.ran.append((unit, obj, face, conveyor, theta))
            if self.after is not None and len(self.ran) == self.after[0]:
                self.after[1]()
        return row


def test_a_campaign_stops_resumes_from_its_journal_and_publishes_predictions(tmp_path) -> None:
    request = CampaignRequest.parse(REQUEST, ["o1", "o2", "o23"])
    folder = tmp_path / request.campaign_id
    first = Units(EmulatedPlant(5))
    job = CampaignJob(request, folder, first, UNITS, campaign_predictions)
    first.after = (3, job.stop)
    assert job.run()["state"] == "stopped"
    journal = (folder / "plant_journal.jsonl").read_text().splitlines()
    assert len(journal) == len(first.ran) >= 3
    assert {json.loads(line)["unit"] for line in journal} <= set(UNITS)

    second = Units(EmulatedPlant(5))
    job = CampaignJob(request, folder, second, UNITS, campaign_predictions)
    assert job.status()["plant_experiments"] == len(journal)
    final = job.run()
    assert final["state"] == "finished", final["error"]
    entries = [json.loads(line) for line in (folder / "plant_journal.jsonl").read_text()
               .splitlines()]  # fmt: skip
    keys = [e["key"] for e in entries]
    assert len(keys) == len(set(keys)) == len(journal) + len(second.ran)  # none run twice
    assert final["plant_experiments"] == len(entries)
    assert final["floor_s"] > 0

    doc = json.loads((folder / "rehearsal.json").read_text())
    assert set(REHEARSAL_KEYS) <= set(doc)
    assert doc["fullstate_leg"] == "operation"
    assert doc["counter_measures"] == ["stability", "compliance"]
    assert doc["training"] + doc["held_out"] == 6
    assert "plant_seed" not in doc["config"]
    assert doc["config"]["object_prior"] == "shipped"  # the defaults
    assert doc["config"]["fullstate_sampling"] == "adaptive"  # rows under the objects' ids:
    from transfertwin.objects import builtin_features

    for obj, entry in doc["objects"].items():  # a face no training row tried keeps its feature
        cal = entry["calibration"]
        if not cal["calibrated"]:
            continue
        shipped = {p.face: round(p.depth_m * 1000, 3) for p in builtin_features(obj)}
        assert set(cal["depth_mm"]) == set(shipped), (obj, cal)
        for face in set(shipped) - set(cal["faces_searched"]):
            assert cal["depth_mm"][face] == shipped[face], (obj, face, cal)
    assert not (folder / "plant.secret").exists()  # the floor's plant is not the rehearsal's
    preds = json.loads((folder / "predictions.json").read_text())
    assert preds["campaign"] == request.campaign_id and preds["leg"] == "operation"
    for obj in ("o1", "o23"):
        states = preds["predictions"][obj]
        assert states, obj
        shares = [s["share"] for s in states]
        assert shares == sorted(shares, reverse=True)
        for s in states:
            assert s["leg"] == "operation" and 0 <= s["k"] <= s["k_pickup"] <= s["n"]
            assert s["ci_low"] <= s["share"] <= s["ci_high"]
            assert s["source"] == f"campaign {request.campaign_id}"
    assert final["summary"]["f05_before"] == doc["f05_before"]
    advice = campaign_advice(folder, ["o1", "o23", "o2"])
    assert advice["o1"].startswith("Put it ") and advice["o23"].startswith("Put it ")
    assert advice["o2"] == ""  # not in the campaign


def test_a_journal_of_another_campaign_is_refused(tmp_path) -> None:
    request = CampaignRequest.parse(REQUEST, ["o1", "o23"])
    entry = {"key": "0:0", "unit": "TU_A_P", "request": ["o1", "back", "left", 90],
             "row": {}}  # fmt: skip
    (tmp_path / "plant_journal.jsonl").write_text(json.dumps(entry) + "\n")
    job = CampaignJob(request, tmp_path, Units(EmulatedPlant(5)), UNITS, campaign_predictions)
    final = job.run()
    assert final["state"] == "failed"
    assert "belongs to another campaign" in final["error"]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[1]", "a JSON object"),
        ('{"objects": ["o9"]}', "not objects of this floor"),
        ('{"experiments": 2}', "'experiments' must be an integer in 3..10000"),
        ('{"workers": 1}', "'workers' must be an integer in 2..256"),
        ('{"theta_step": 7}', "--theta-step must divide 360"),
        ('{"budget": 3}', "unknown key(s) budget"),
        ('{"object_prior": "scan"}', "--object-prior must be one of plain, shipped"),
        ('{"min_face_rows": 0}', "'min_face_rows' must be an integer in 1..10000"),
        ('{"sampling": "greedy"}', "fullstate sampling must be one of exhaustive, adaptive"),
    ],
)
def test_bad_requests_say_what_is_wrong(text: str, message: str) -> None:
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        CampaignRequest.parse(text, ["o1", "o23"])


def test_the_same_request_is_the_same_campaign() -> None:
    a = CampaignRequest.parse(REQUEST, ["o1", "o23"])
    b = CampaignRequest.parse(json.dumps(json.loads(REQUEST), indent=3), ["o1", "o23"])
    c = CampaignRequest.parse(REQUEST.replace('"seed": 3', '"seed": 4'), ["o1", "o23"])
    assert a.campaign_id == b.campaign_id != c.campaign_id
    # the object prior: the shipped features by default
    d = CampaignRequest.parse(REQUEST[:-1] + ', "object_prior": "shipped"}', ["o1", "o23"])
    e = CampaignRequest.parse(REQUEST[:-1] + ', "object_prior": "plain", "min_face_rows": 3}',
                              ["o1", "o23"])  # fmt: skip
    assert d.campaign_id == a.campaign_id != e.campaign_id
    assert (a.config().object_prior, a.config().min_face_rows) == ("shipped", 1)
    assert (e.config().object_prior, e.config().min_face_rows) == ("plain", 3)


def test_a_unit_that_cannot_run_e_p_is_left_out_and_the_others_run_its_share(tmp_path) -> None:
    from transfertwin.cps.apps import FloorPlant, UnitUnavailableError

    units = Units(EmulatedPlant(5))

    def run_one(unit: str, *args) -> dict:
        if unit == "TU_E_P":  # a unit of a station the plant does not have
            raise UnitUnavailableError(unit, "the plant has no station for TU_E_P")
        return units(unit, *args)

    plant = FloorPlant(run_one, ("TU_E_P", "TU_A_P", "TU_B_P"), tmp_path / "j.jsonl")
    requests = calibration_design(["o1"], 5, seed=0)
    rows = plant.run(requests)
    assert [r["theta_deg"] for r in rows] == [r.theta_deg for r in requests]
    assert plant.units == ("TU_A_P", "TU_B_P") and "TU_E_P" in plant.left_out
    assert {u for u, *_ in units.ran} == {"TU_A_P", "TU_B_P"} and len(units.ran) == 5
    dead = FloorPlant(run_one, ("TU_E_P",), tmp_path / "k.jsonl")
    with pytest.raises(InputError, match="no physical unit of the floor can run E\\^P"):
        dead.run(requests[:1])
