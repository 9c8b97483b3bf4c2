"""Measured mass properties in a proxy (the rehearsal's mass counter-measure)."""

from __future__ import annotations

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.objects import ProxySpec, load_builtin, load_object, read_proxy, write_proxy


def test_measured_mass_replaces_the_uniform_density_one(tmp_path) -> None:
    base = load_builtin("o3", features=False)
    spec = ProxySpec("o3", "o3", (), mass_kg=3.5, com_m=(0.004, -0.001, 0.002))
    path = write_proxy(spec, tmp_path / "o3.proxy.json")
    assert read_proxy(path) == spec
    model = load_object(str(path))
    assert model.mass.mass_kg == 3.5
    assert np.allclose(model.mass.com_m, (0.004, -0.001, 0.002))
    ratio = 3.5 / base.mass.mass_kg
    assert np.allclose(model.mass.inertia_kg_m2, base.mass.inertia_kg_m2 * ratio)
    plain = write_proxy(ProxySpec("o3", "o3", ()), tmp_path / "p.proxy.json")
    assert "mass_kg" not in plain.read_text()  # files without a measurement stay as they were
    assert load_object(str(plain)).mass.mass_kg == base.mass.mass_kg


def test_bad_measurements_are_refused() -> None:
    with pytest.raises(InputError):
        ProxySpec("o3", "o3", (), mass_kg=-1.0)
    with pytest.raises(InputError):
        ProxySpec("o3", "o3", (), com_m=(0.0, 0.0))
