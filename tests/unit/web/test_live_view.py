"""The live transfer view's pure parts: the schematic's geometry, the object's footprint and
the checks on a transfer request."""

from __future__ import annotations

import math

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.sim import LayoutConfig, SceneConfig
from transfertwin.web import TransferRequest, footprint, scene_outline

CUBE = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])


def _area(poly) -> float:
    x, y = np.asarray(poly).T
    return 0.5 * abs(float(np.dot(x, np.roll(y, 1)) - np.dot(y, np.roll(x, 1))))


def _rot_z(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def test_belts_and_barriers_of_the_nominal_layout():
    lay = LayoutConfig()
    g = scene_outline(lay, (0.012, 0.0, 0.0))
    belts = {(b["unit"], b["belt"]): np.array(b["polygon"]) for b in g["belts"]}
    tm_left = belts[("tm", "left")]
    assert tm_left[:, 0].min() == pytest.approx(-lay.tm_length_m)
    assert tm_left[:, 0].max() == pytest.approx(0.0)
    assert tm_left[:, 1].min() == pytest.approx(lay.belt_separation_m / 2)
    assert tm_left[:, 1].max() == pytest.approx(lay.belt_separation_m / 2 + lay.belt_width_m)
    tu_right = belts[("tu", "right")]
    assert tu_right[:, 0].min() == pytest.approx(0.012)
    assert tu_right[:, 0].max() == pytest.approx(0.012 + lay.tu_length_m)
    assert tu_right[:, 1].max() == pytest.approx(-lay.belt_separation_m / 2)
    bars = {(b["unit"], b["which"]): b["segment"] for b in g["barriers"]}
    assert bars[("tm", "near")][0][0] == pytest.approx(-lay.barrier_inset_m)
    assert bars[("tu", "far")][0][0] == pytest.approx(0.012 + lay.tu_length_m - lay.barrier_inset_m)
    assert _area(g["gap"]) == pytest.approx(0.012 * (2 * lay.belt_width_m + lay.belt_separation_m))


def test_a_turned_tu_keeps_its_belt_size():
    lay = LayoutConfig()
    g = scene_outline(lay, (0.02, 0.005, math.radians(3)))
    for b in g["belts"]:
        assert _area(b["polygon"]) == pytest.approx(
            lay.belt_width_m * (lay.tm_length_m if b["unit"] == "tm" else lay.tu_length_m),
            rel=1e-4,
        )
    tu_near = next(
        b["segment"] for b in g["barriers"] if b["unit"] == "tu" and b["which"] == "near"
    )
    (x0, y0), (x1, y1) = tu_near
    assert math.degrees(math.atan2(x0 - x1, y1 - y0)) == pytest.approx(3, abs=0.01)


def test_footprint_of_a_cube():
    flat = footprint(CUBE, np.array([0.2, -0.1, 0.5]), _rot_z(math.radians(45)))
    # (the outline is rounded to 10 µm)
    assert len(flat) == 4 and _area(flat) == pytest.approx(1.0, abs=1e-4)
    centre = np.mean(flat, axis=0)
    assert centre == pytest.approx([0.2, -0.1], abs=1e-5)
    assert max(abs(p[0] - 0.2) for p in flat) == pytest.approx(math.sqrt(0.5), abs=1e-5)
    tilt = np.array(
        [[1, 0, 0], [0, math.cos(0.5), -math.sin(0.5)], [0, math.sin(0.5), math.cos(0.5)]]
    )
    assert _area(footprint(CUBE, np.zeros(3), tilt)) == pytest.approx(
        math.cos(0.5) + math.sin(0.5), abs=1e-4
    )  # a cube tilted about x shows two faces from above


def test_a_request_is_parsed_and_checked():
    r = TransferRequest.parse({"object": "o5", "face": "Back", "conveyor": "left",
                               "theta_deg": "-15", "seed": 3, "speed": "2",
                               "dock_error": "1.5, -2, 0.5", "token": "x"})  # fmt: skip
    assert (r.object_ref, r.face, r.conveyor, r.theta_deg, r.seed) == ("o5", "back", "left", -15, 3)
    assert r.speed == 2.0 and r.dock_error == (1.5, -2.0, 0.5)
    spec = r.spec(SceneConfig())
    assert spec.docking_error.x_m == pytest.approx(0.0015)


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ({"object": "/etc/passwd"}, "built-in core"),
        ({"object": "o38"}, "built-in core"),
        ({"object": "o1", "face": "top"}, "face"),
        ({"object": "o1", "conveyor": "middle"}, "onveyor"),
        ({"object": "o1", "theta_deg": 200}, "theta"),
        ({"object": "o1", "speed": 0}, "speed"),
        ({"object": "o1", "speed": "nan"}, "speed"),
        ({"object": "o1", "speed": True}, "speed"),
        ({"object": "o1", "seed": 2.5}, "seed"),
        ({"object": "o1", "dock_error": [0, 0]}, "dock_error"),
        ({"object": "o1", "dock_error": [0, 0, 45]}, "dock_error"),
        ({"object": "o1", "dock_error": {"x": 1}}, "dock_error"),
        ({"object": "o1", "runs": 3}, "unknown field"),
    ],
)  # fmt: skip
def test_bad_requests_are_refused(body, message):
    with pytest.raises(InputError, match=message):
        TransferRequest.parse(body)
