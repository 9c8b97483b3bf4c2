"""Calibrated proxies: protrusion hulls below a face's resting plane, saved and loaded."""

from __future__ import annotations

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.objects import (
    Protrusion,
    ProxySpec,
    load_builtin,
    load_object,
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
