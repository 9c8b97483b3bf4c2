"""The per-process cache of compiled twins follows the object's file: a proxy or mesh
rewritten in place (a user editing it while the web console or a CPS keeps one process
running) is loaded again, never answered from the stale model."""

from __future__ import annotations

import os

from transfertwin.objects import Protrusion, ProxySpec, write_proxy
from transfertwin.sim import SceneConfig
from transfertwin.study.experiment import system_for


def _geoms(system) -> int:
    return sum(system.model.geom(i).name.startswith("object_") for i in range(system.model.ngeom))


def test_a_proxy_rewritten_in_place_is_loaded_again(tmp_path):
    path = tmp_path / "o1.proxy.json"
    write_proxy(ProxySpec("o1", "o1", ()), path)
    plain = system_for(str(path), "m", SceneConfig())
    assert system_for(str(path), "m", SceneConfig()) is plain  # cached while unchanged
    write_proxy(ProxySpec("o1", "o1", (Protrusion("back", 0.018),)), path)
    st = os.stat(path)
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 1_000_000))  # a later write
    featured = system_for(str(path), "m", SceneConfig())
    assert featured is not plain
    assert _geoms(featured) == _geoms(plain) + 1  # the protrusion's hull
