"""Learning alone (``[operation] twin = false``): the floor's own transfers rank every
state of the grid from a flat prior, the twin plays no part (`cps.dispatch.uninformed`,
`posterior` with n = 0), so the benchmark can tell what the twin adds to learning."""

from __future__ import annotations

import pytest

from transfertwin._errors import InputError
from transfertwin.cps.dispatch import fallback, posterior, rerank, uninformed
from transfertwin.cps.floor import default_floor_spec, floor_toml, parse_floor

GRID = [{"face": "front", "conveyor": "both", "theta_deg": 0},
        {"face": "back", "conveyor": "both", "theta_deg": 0},
        {"face": "front", "conveyor": "left", "theta_deg": 90}]  # fmt: skip


def test_a_state_without_the_twin_has_the_laplace_prior_on_both_legs():
    pred = uninformed(GRID)[0]
    assert (pred["k"], pred["n"], pred["source"]) == (0, 0, "none")
    assert posterior(pred, {}) == {"p_pickup": 0.5, "p_delivery": 0.5, "p": 0.25}
    # one delivered operation in the state: (w m + k) / (w + n) with m = 1/2, w = 2
    seen = {"pick-up": {"front/both/0": [1, 1]}, "delivery": {"front/both/0": [1, 1]}}
    assert posterior(pred, seen) == pytest.approx(
        {"p_pickup": 2 / 3, "p_delivery": 2 / 3, "p": 4 / 9})


def test_without_evidence_the_grids_order_decides_and_evidence_reorders_it():
    preds = uninformed(GRID)
    assert [p["face"] for p in rerank(preds, {})] == ["front", "back", "front"]
    # the front face failed its pick-up twice, the back was delivered once
    evidence = {"pick-up": {"front/both/0": [0, 2], "back/both/0": [1, 1]},
                "delivery": {"back/both/0": [1, 1]}}  # fmt: skip
    ranked = rerank(preds, evidence)
    assert (ranked[0]["face"], ranked[0]["conveyor"]) == ("back", "both")
    # front/left/90 shares the failed face at half weight: below the untried flat prior
    assert ranked[-1]["face"] == "front"
    assert fallback(preds, evidence, ranked[0]) == {"face": "front", "conveyor": "left",
                                                    "theta_deg": 90}  # fmt: skip


def test_a_floor_file_says_twin_false_and_it_needs_learning():
    floor = default_floor_spec()
    text = floor_toml(floor).replace("twin = true", "twin = false")
    import tomllib

    parsed = parse_floor(tomllib.loads(text), floor.name)
    assert parsed.operation.twin is False and parsed.operation.learn is True
    assert parse_floor(tomllib.loads(floor_toml(parsed)), floor.name) == parsed
    with pytest.raises(InputError, match="twin = false needs learn = true"):
        parse_floor(tomllib.loads(text.replace("learn = true", "learn = false")), floor.name)
    with pytest.raises(InputError, match="twin must be true or false"):
        parse_floor(tomllib.loads(text.replace("twin = false", 'twin = "no"')), floor.name)


def test_learning_alone_ranks_the_default_state_then_the_grid_without_a_twin() -> None:
    """What the TMS ranks with ``twin = false``: the default state first (loaded as
    nearest-idle loads it), then the other 27 states of the grid, none with a prediction, and the
    posterior of each is Laplace's on both legs (the TMS once passed the grid's state
    objects here and every order of the arm hung)."""
    from transfertwin.cps.dispatch import DEFAULT_STATE, learning_alone_states

    states = learning_alone_states()
    assert {k: states[0][k] for k in DEFAULT_STATE} == DEFAULT_STATE
    assert len(states) == 28 and {s["source"] for s in states} == {"none"}
    assert len({(s["face"], s["conveyor"], s["theta_deg"]) for s in states}) == 28
    best = rerank(states, {})[0]
    assert {k: best[k] for k in DEFAULT_STATE} == DEFAULT_STATE and best["p"] == 0.25
