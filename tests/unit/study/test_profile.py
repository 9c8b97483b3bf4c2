"""Physics profiles: TOML round trip and clear errors."""

from __future__ import annotations

import pytest

from transfertwin import InputError
from transfertwin.sim import SceneConfig
from transfertwin.study import load_profile, save_profile


def test_profile_round_trips_every_setting(tmp_path):
    cfg = SceneConfig(mu=0.41, gap_m=0.015).with_overrides(
        **{"physics.solver": "CG", "physics.solimp": (0.8, 0.9, 0.002, 0.5, 2.0)}
    )
    path = save_profile(tmp_path / "p.toml", "tuned", cfg)
    name, again = load_profile(path)
    assert (name, again) == ("tuned", cfg)


def test_profile_accepts_gap_in_mm(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text('name = "x"\n[scene]\nmu = 0.5\ngap_mm = 20.0\n[physics]\nimpratio = 2.0\n')
    _, cfg = load_profile(path)
    assert (cfg.mu, cfg.gap_m, cfg.physics.impratio) == (0.5, 0.02, 2.0)


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("[scene\n", "TOML"),
        ("[scene]\nfriction = 1\n", "friction"),
        ("[physics]\nsolver = 'magic'\n", "solver"),
        ("[other]\nx = 1\n", "other"),
    ],
)
def test_bad_profiles_are_input_errors(tmp_path, text, needle):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(InputError, match=needle):
        load_profile(path)


def test_missing_profile_file(tmp_path):
    with pytest.raises(InputError, match="cannot read"):
        load_profile(tmp_path / "none.toml")


def test_profile_round_trips_the_unmeasured_mechanisms(tmp_path):
    cfg = SceneConfig(feature_mu=0.9, com_offset_m=-0.02).with_overrides(
        **{"layout.tu_height_offset_m": 0.004, "layout.tu_pitch_deg": -1.5,
           "layout.tu_roll_deg": 2.0, "physics.solref": (0.03, 1.0), "physics.condim": 4}
    )  # fmt: skip
    path = save_profile(tmp_path / "p.toml", "mech", cfg)
    text = path.read_text()
    assert "tu_pitch_deg = -1.5" in text and "feature_mu = 0.9" in text
    assert load_profile(path) == ("mech", cfg)
    # Off (None) is written as "none" and read back as today's behaviour.
    assert load_profile(save_profile(tmp_path / "d.toml", "d", SceneConfig()))[1] == SceneConfig()


def test_the_lean_profile_loads_by_name_with_its_cheaper_contacts():
    name, cfg = load_profile("lean")
    assert name == "lean" and cfg.physics.max_hulls == 8 and cfg.physics.multiccd is None
    assert (
        cfg.with_overrides(**{"physics.max_hulls": None, "physics.multiccd": True})
        == (load_profile("fast")[1])
    )
