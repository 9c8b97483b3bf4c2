"""A floor on the PyBullet plant (issue 37, item 4: the plant kinds in-class, mismatch and
bullet): `cps up --plant-kind bullet` starts every module on the in-class plant simulated in
another engine; an order's pick-up and delivery run there and end with a physical outcome
(not a fault); a floor that needs the depth camera is refused in one line before anything
is written (slow: a floor of 6 processes, ~40 s)."""

from __future__ import annotations

import json

import pytest

from tests.integration.cps._cli import call_tms, plant_floor, tt, two_module_floor

pytestmark = pytest.mark.slow

FLOOR = two_module_floor("bullet", {"o3": "TU_A"}) + """
[operation]
policy = "nearest-idle"
"""


@pytest.fixture(scope="module")
def floor(tmp_path_factory):
    yield from plant_floor(tmp_path_factory.mktemp("bullet"), FLOOR, "--plant-kind", "bullet")


def test_an_order_runs_both_legs_on_the_bullet_plant(floor):
    assert (floor / "plant.secret").read_text() == "7 bullet\n"  # the engine beside the seed
    out = tt("cps", "order", "--workdir", str(floor), "--object", "o3", "--to", "TU_B",
             timeout=300)  # fmt: skip
    assert out.returncode in (0, 3), out.stderr
    result = json.loads(call_tms(floor, "OperationStatus", "op1"))["result"]
    assert result["status"] in ("delivered", "failed at pick-up", "failed at delivery"), result
    legs = result["legs"]
    assert legs[0]["leg"] == "pick-up" and legs[0]["scanning"]["source"] == "ground truth"
    if result["status"] == "delivered":  # picked up from TU_A's belts, handed to TU_B's
        assert [leg["leg"] for leg in legs] == ["pick-up", "delivery"]
        assert legs[1]["scanning"]["boxes"][0]["x"] < 0.0  # on the module, behind its tip


def test_a_bullet_floor_that_needs_the_camera_is_refused_in_one_line(tmp_path):
    wd = tmp_path / "w"
    out = tt("cps", "up", "--workdir", str(wd), "--detach", "--plant-seed", "7",
             "--plant-kind", "bullet", "--docking", "navigated")  # fmt: skip
    assert out.returncode == 2, out.stderr
    assert len(out.stderr.strip().splitlines()) == 1
    assert "'bullet' plant has no depth camera" in out.stderr
    assert not wd.exists()
