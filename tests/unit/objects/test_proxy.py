"""Calibrated proxies: protrusion hulls below a face's resting plane, saved and loaded."""

from __future__ import annotations

import json

import numpy as np
import pytest
from tests.conftest import plain_body_proxy

from transfertwin._errors import InputError
from transfertwin.objects import (
    Protrusion,
    ProxySpec,
    axial_mass_split,
    load_builtin,
    load_object,
    mass_split,
    read_proxy,
    write_proxy,
)


def test_front_protrusion_reaches_depth_below_the_lowest_point(tmp_path) -> None:
    spec = ProxySpec("o1x", "o1", (Protrusion("front", 0.02), Protrusion("back", 0.0)))
    path = write_proxy(spec, tmp_path / "o1x.proxy.json")
    base, proxy = load_builtin("o1", features=False), load_object(str(path))
    assert proxy.object_id == "o1x" and len(proxy.hulls) == len(base.hulls) + 1
    low = np.vstack(base.hulls)[:, 2].min()
    assert np.vstack(proxy.hulls)[:, 2].min() == pytest.approx(low - 0.02)
    assert np.vstack(proxy.hulls)[:, 2].max() == pytest.approx(np.vstack(base.hulls)[:, 2].max())
    assert proxy.mass == base.mass
    assert read_proxy(path) == spec


def test_back_protrusion_lies_above_the_highest_point() -> None:
    base = load_object("o18")
    top = np.vstack(base.hulls)[:, 2].max()
    box = Protrusion("back", 0.01, size_x_m=0.01, size_y_m=0.02).hull(base)
    assert box.shape == (8, 3)
    assert box[:, 2].max() == pytest.approx(top + 0.01)
    assert np.ptp(box[:, 0]) == pytest.approx(0.01) and np.ptp(box[:, 1]) == pytest.approx(0.02)


def test_bad_proxy_files_are_input_errors(tmp_path) -> None:
    with pytest.raises(InputError, match="face"):
        Protrusion("side", 0.01)
    with pytest.raises(InputError, match="depth"):
        Protrusion("front", -0.01)
    bad = tmp_path / "x.proxy.json"
    bad.write_text("{}")
    with pytest.raises(InputError, match="not a proxy"):
        load_object(str(bad))
    with pytest.raises(InputError, match=r"\.proxy\.json"):
        write_proxy(ProxySpec("a", "o1", ()), tmp_path / "a.json")


def test_com_shift_moves_the_centre_of_mass_along_x_and_keeps_the_mass(tmp_path) -> None:
    base = load_builtin("o1", features=False)
    for shift in (0.012, -0.02):
        spec = ProxySpec("o1m", "o1", (Protrusion("front", 0.01),), com_shift_m=shift)
        proxy = load_object(str(write_proxy(spec, tmp_path / "o1m.proxy.json")))
        assert proxy.mass.mass_kg == pytest.approx(base.mass.mass_kg, rel=1e-12)
        assert proxy.mass.com_m[0] == pytest.approx(base.mass.com_m[0] + shift, abs=1e-6)
        inertia = proxy.mass.inertia_kg_m2
        assert np.allclose(inertia, inertia.T) and np.linalg.eigvalsh(inertia).min() > 0
        assert not np.allclose(inertia, base.mass.inertia_kg_m2, rtol=1e-3)
        split = mass_split(base, spec)
        # the end the centre of mass moves towards carries more than its uniform share
        more = split.front_fraction > split.uniform_front_fraction
        assert more == (shift > 0) and 0 < split.front_fraction < 1
        assert read_proxy(tmp_path / "o1m.proxy.json") == spec
    # zero is the uniform body, bit for bit; the uniform split has the volume shares
    assert load_object(str(plain_body_proxy(tmp_path))).mass == base.mass
    uniform = axial_mass_split(base.mesh, base.mass.mass_kg, 0.0)
    assert uniform.mass.com_m == pytest.approx(base.mass.com_m, abs=1e-6)
    assert uniform.mass.inertia_kg_m2 == pytest.approx(base.mass.inertia_kg_m2, rel=1e-5)
    assert uniform.front_fraction == pytest.approx(uniform.uniform_front_fraction)


def test_shifted_centre_of_mass_reaches_the_mujoco_body(tmp_path) -> None:
    from transfertwin.sim import SceneConfig, VirtualTransferSystem

    spec = ProxySpec("o1m", "o1", (), com_shift_m=0.015)
    obj = load_object(str(write_proxy(spec, tmp_path / "o1m.proxy.json")))
    system = VirtualTransferSystem(obj.hulls, obj.mass.mass_kg, obj.mass.com_m,
                                   obj.mass.inertia_kg_m2, SceneConfig())  # fmt: skip
    body = system.model.body("object")
    assert body.ipos[0] == pytest.approx(0.015, abs=1e-6)
    assert body.mass[0] == pytest.approx(obj.mass.mass_kg)


def test_old_proxy_files_without_a_mass_distribution_load_as_uniform(tmp_path) -> None:
    old = tmp_path / "old.proxy.json"
    old.write_text(json.dumps({
        "object_id": "o1", "base": "o1", "note": "calibrated proxy, not a scan",
        "protrusions": [{"face": "back", "depth_m": 0.026, "x_frac": 0.5, "y_frac": 0.5,
                         "size_x_m": 0.006, "size_y_m": 0.03, "height_m": None}],
    }))  # fmt: skip
    spec = read_proxy(old)
    assert spec.com_shift_m == 0.0
    assert load_object(str(old)).mass == load_builtin("o1", features=False).mass


def test_impossible_mass_distributions_are_input_errors() -> None:
    with pytest.raises(InputError, match="com_shift_m"):
        ProxySpec("a", "o1", (), com_shift_m=0.2)
    base = load_builtin("o1", features=False)
    with pytest.raises(InputError, match="two positive densities"):
        mass_split(base, ProxySpec("a", "o1", (), com_shift_m=0.05))


def test_the_default_position_is_the_centred_geometry_bit_for_bit(tmp_path) -> None:
    base = load_builtin("o1", features=False)
    verts = np.vstack(base.hulls)
    lo, hi = verts.min(axis=0), verts.max(axis=0)
    box = Protrusion("front", 0.02).hull(base)
    assert np.array_equal(box, Protrusion("front", 0.02, x_frac=0.5).hull(base))
    assert np.array_equal(box[:, 0].reshape(2, 4).mean(axis=1),
                          [lo[0] + 0.5 * (hi[0] - lo[0]) - 0.003,
                           lo[0] + 0.5 * (hi[0] - lo[0]) + 0.003])  # fmt: skip
    # a proxy file written before positions were fitted (no x_frac) loads as centred
    old = tmp_path / "old.proxy.json"
    old.write_text(json.dumps({
        "object_id": "o1", "base": "o1",
        "protrusions": [{"face": "front", "depth_m": 0.02}],
    }))  # fmt: skip
    new = write_proxy(ProxySpec("o1", "o1", (Protrusion("front", 0.02, x_frac=0.5),)),
                      tmp_path / "new.proxy.json")  # fmt: skip
    assert read_proxy(old).protrusions[0].x_frac == 0.5
    a, b = load_object(str(old)), load_object(str(new))
    assert all(np.array_equal(u, v) for u, v in zip(a.hulls, b.hulls, strict=True))


def test_a_position_off_centre_moves_the_feature_along_x_only() -> None:
    base = load_builtin("o1", features=False)
    verts = np.vstack(base.hulls)
    length = np.ptp(verts[:, 0])
    centre = Protrusion("back", 0.015).hull(base)
    for x in (0.25, 0.7):
        moved = Protrusion("back", 0.015, x_frac=x).hull(base)
        assert np.allclose(moved[:, 0] - centre[:, 0], (x - 0.5) * length)
        assert np.array_equal(moved[:, 1:], centre[:, 1:])
    with pytest.raises(InputError, match="x_frac"):
        Protrusion("back", 0.015, x_frac=1.2)
