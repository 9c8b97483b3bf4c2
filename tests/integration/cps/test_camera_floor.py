"""The modules' depth cameras in the loop on the emulated plant (docs/architecture.md,
"Operation"): o10 on plant seed 7 stands about 115 mm high on its front face where its model
says 85 mm (measured by a scan of the plant's physics), beyond the 25 mm the scan is matched
with. The module takes the one box the ledger expects there as o10, learns the height (in
the order's history and its persisted state) and expects it from then on."""

from __future__ import annotations

import json

import pytest

from tests.integration.cps._cli import call_tms, tt, two_module_floor

#: A floor of 6 processes on the plant and one order (~60 s): slow, run by .ci/run.
pytestmark = pytest.mark.slow

FLOOR = two_module_floor("camera", {"o10": "TU_A"}) + """
[operation]
sensor = "camera"
"""


def _scans(node) -> list[dict]:
    """Every 'possessions' summary in an operation's result, in order."""
    if isinstance(node, dict):
        found = [node["possessions"]] if "possessions" in node else []
        return found + [s for k, v in node.items() if k != "possessions" for s in _scans(v)]
    if isinstance(node, list):
        return [s for v in node for s in _scans(v)]
    return []


def test_the_camera_learns_a_height_its_model_gets_wrong_and_expects_it(tmp_path):
    (tmp_path / "floor.toml").write_text(FLOOR)
    wd = tmp_path / "w"
    up = tt("cps", "up", "--policy", "nearest-idle",
            "--floor", str(tmp_path / "floor.toml"), "--workdir", str(wd),
            "--detach", "--time-scale", "0", "--plant-seed", "7", "--lease", "10",
            "--start-timeout", "150", timeout=200)  # fmt: skip
    assert up.returncode == 0, up.stderr
    try:
        order = tt("cps", "order", "--workdir", str(wd), "--object", "o10", "--to", "TU_B",
                   timeout=300)  # fmt: skip
        assert order.returncode in (0, 3), order.stderr
        op = json.loads(call_tms(wd, "OperationStatus", "op1"))
        scans = _scans(op["result"])
        assert scans, op["result"]
        # no scan stopped the order: it went on to the transfer
        assert "scanning" not in op["result"].get("status", ""), op["result"]
        first = scans[0]
        assert first["matched"] == ["o10"] and first["missing"] == [], first
        learnt = first["learnt"][0]
        assert learnt.startswith("o10 stands ") and "on its front face (its model 85 mm)" in learnt
        seen_mm = int(learnt.split()[2])
        assert seen_mm >= 85 + 26, learnt  # beyond the scan's 25 mm: only learning matched it
        # every later scan of o10 matched the learnt height without learning again
        assert all("learnt" not in s and s["matched"] == ["o10"] for s in scans[1:]), scans
        state = json.loads(next((wd / "assets").rglob("TM_1.json")).read_text())
        assert state["heights"]["o10/front"] == pytest.approx(seen_mm / 1000, abs=0.0006)
    finally:
        down = tt("cps", "down", "--workdir", str(wd))
    assert down.returncode == 0 and "killed" not in down.stdout, down.stdout + down.stderr
