"""The MuJoCo Warp executor (issue 11, item 4): its refusals, and its logic on Warp's CPU
device at tiny size against the CPU backend.

The CPU-device runs compile MuJoCo Warp's kernels on first use (minutes cold, cached in
~/.cache/warp afterwards) and step two worlds at a few dozen steps/s, so they are marked
slow; .ci/run runs them.
"""

from __future__ import annotations

import sys
import threading

import pytest

from transfertwin._errors import InputError
from transfertwin.cli import main
from transfertwin.sim import SceneConfig
from transfertwin.study.experiment import ExperimentSpec, WarpExecutor, run_experiment

# (face, conveyor, θ) of o1 with seed 1 in the default scene, as the CPU backend runs them:
# settled outside P_pre (ends after settling); a transfer that stalls (y1 = 0 after 2.2 s);
# there and back (y1 = y2 = 1, about 1,300 steps).
STATES = [("front", "left", 60), ("back", "right", -150), ("front", "left", 30)]
OUTCOME = ("status", "y1", "y2", "success")


def _specs(scene: SceneConfig | None = None) -> list[ExperimentSpec]:
    scene = scene or SceneConfig()
    return [ExperimentSpec("o1", f, c, t, seed=1, scene=scene) for f, c, t in STATES]


def test_missing_mujoco_warp_is_one_clear_error(monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "warp", None)  # import warp raises ImportError
    monkeypatch.setitem(sys.modules, "mujoco_warp", None)
    with pytest.raises(InputError, match=r"needs MuJoCo Warp: pip install 'transfertwin\[gpu\]'"):
        WarpExecutor().start()


def test_bad_arguments_and_use_before_start() -> None:
    with pytest.raises(InputError, match="worlds"):
        WarpExecutor(worlds=0)
    with pytest.raises(InputError, match="nconmax"):
        WarpExecutor(nconmax=0)
    with pytest.raises(RuntimeError, match="start"):
        next(WarpExecutor().batches(_specs()))


def test_without_cuda_the_cli_exits_2_with_one_line(tmp_path, capfd) -> None:
    wp = pytest.importorskip("warp")
    from transfertwin.study.experiment import warp_available

    if warp_available() is None:
        pytest.skip(f"a CUDA device is present ({wp.get_cuda_device_count()})")
    db = tmp_path / "s.sqlite"
    argv = ["study", "run", "--db", str(db), "--objects", "o1", "--executor", "warp"]
    assert main(argv) == 2
    out, err = capfd.readouterr()
    assert err.strip().splitlines() == [
        "transfertwin: error: --executor warp: no CUDA device (MuJoCo Warp on Warp's CPU "
        "device is for tests only); use --executor local"
    ]
    assert out == ""
    assert not db.exists()


def test_guard_is_refused_before_anything_runs() -> None:
    pytest.importorskip("mujoco_warp")
    scene = SceneConfig().with_overrides(**{"physics.guard": True})
    with WarpExecutor(worlds=2, device="cpu") as ex, pytest.raises(InputError, match="guard"):
        next(ex.batches(_specs(scene)))


@pytest.mark.slow
def test_cpu_device_agrees_with_the_cpu_backend() -> None:
    """Three experiments on two lanes (one lane takes a second experiment when its first
    ends): the same outcomes and end times (to one camera sample) as `run_experiment`."""
    pytest.importorskip("mujoco_warp")
    specs = _specs()
    with WarpExecutor(worlds=2, device="cpu") as ex:
        rows = [row for batch in ex.batches(specs) for row in batch]
        batch_steps = ex.batch_steps
    assert len(rows) == 3
    by_state = {(r["face"], r["conveyor"], r["theta_deg"]): r for r in rows}
    assert set(by_state) == set(STATES)
    sample_s = SceneConfig().steps_per_sample() * SceneConfig().physics.timestep_s
    for spec in specs:
        cpu = run_experiment(spec).row()
        warp = by_state[(spec.face, spec.conveyor, spec.theta_deg)]
        assert tuple(warp[k] for k in OUTCOME) == tuple(cpu[k] for k in OUTCOME), spec
        for key in ("t_end_1_s", "t_end_2_s"):
            if cpu[key] == cpu[key]:  # not NaN
                assert abs(warp[key] - cpu[key]) <= sample_s + 1e-9, (spec, key)
    # The lanes ran side by side: fewer batch steps than the experiments' steps together.
    assert by_state[STATES[2]]["status"] == "ok"
    assert 0 < batch_steps < 2000


@pytest.mark.slow
def test_abandoned_batch_leaves_no_lane_running() -> None:
    pytest.importorskip("mujoco_warp")
    with WarpExecutor(worlds=2, device="cpu") as ex:
        batches = ex.batches(_specs())
        first = next(batches)  # the state outside P_pre ends first, after settling
        batches.close()
    assert [r["status"] for r in first] == ["invalid"]
    assert not [t for t in threading.enumerate() if t.name.startswith("warp-lane-")]
