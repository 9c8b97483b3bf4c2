"""The MuJoCo Warp executor: a study's experiments as batched worlds of one model (GPU).

Experiments of the same object and scene run as lanes of one `mujoco_warp` batch: every
lane is one E^V, driven by the unchanged experiment code (`_run`: settle, P_pre check, OTS
controller, there and back) in its own thread, which sees a `_World`, a
`VirtualTransferSystem` whose `step` hands the physics to the batch. The threads take
turns (exactly one runs at a time, the others are parked in `step` or finished), so the
controller logic, belt commands and light barriers are those of the CPU path; only the
physics steps run batched on the device. The scheduler steps all lanes by the smallest
number of steps any lane asked for, hands the new state back (qpos, qvel, time, warm start,
body poses, sensors) to the lanes whose wait is over and resumes them one by one. A lane
whose experiment ends takes the next experiment of the group at once, so lanes of
experiments that end early do not idle until the slowest one is done.

Differences from the CPU path (docs/scaling.md, "GPU"): MuJoCo Warp computes in float32,
so trajectories agree with MuJoCo's float64 ones statistically, not bit for bit (success
shares within each other's Clopper–Pearson intervals); the implicit-event guard
(`PhysicsConfig.guard`) and the perception sensor are not available (the guard reads
contacts on the host); a non-finite state still makes a run 'unstable'.

Warp and MuJoCo Warp are the optional extra ``gpu`` and are imported here only, when the
executor starts. Without a CUDA device the executor refuses to start (one line, exit 2
from the CLI): Warp's CPU device runs the same kernels for tests, far slower than MuJoCo.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import os
import sys
import threading
import time
import warnings
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from transfertwin._errors import InputError
from transfertwin.sim import SimulationUnstable, VirtualTransferSystem
from transfertwin.study.experiment._experiment import (
    ExperimentResult,
    ExperimentSpec,
    _object,
    _run,
    _Seeing,
    _stamp,
    _system_for,
)

__all__ = ["WarpExecutor", "warp_available"]

Row = dict[str, object]

_INSTALL = "pip install 'transfertwin[gpu]' (mujoco-warp, warp-lang)"
NO_CUDA = (
    "--executor warp: no CUDA device (MuJoCo Warp on Warp's CPU device is for tests only); "
    "use --executor local"
)


def _import_warp() -> tuple[Any, Any]:
    """(warp, mujoco_warp), Warp initialised quietly; InputError if they are missing."""
    try:
        import mujoco_warp as mjw
        import warp as wp
    except ImportError:
        raise InputError(f"--executor warp needs MuJoCo Warp: {_INSTALL}") from None
    # No banner, no per-kernel compile lines; Warp's native CUDA probe writes a warning
    # straight to fd 2 when no driver is found, which `NO_CUDA` says in one line instead.
    wp.config.log_level = wp.LOG_WARNING
    with _stderr_silenced():
        wp.init()
    return wp, mjw


@contextlib.contextmanager
def _stderr_silenced() -> Iterator[None]:
    """Send file descriptor 2 to the null device for the duration (native writes too)."""
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def warp_available() -> str | None:
    """None when the warp executor can run here (CUDA device present), else why not."""
    try:
        wp, _ = _import_warp()
    except InputError as exc:
        return str(exc)
    return None if wp.is_cuda_available() else NO_CUDA


class _Cancelled(BaseException):
    """Raised in a parked lane's thread when the batch stops early (not an Exception, so
    the experiment code does not turn it into a result)."""


class _World(VirtualTransferSystem):
    """One lane's view of the batch: the group's compiled model and its own `MjData`.

    Everything but `step` is the CPU system's: placement, docking and readout work on the
    host `data`, which the batch fills with the lane's device state before it resumes the
    lane's thread. Not constructed through `VirtualTransferSystem.__init__`: it copies the
    template's attributes (model, hull vertices, ids) and attaches its own `MjData`.
    """

    def __init__(self, template: VirtualTransferSystem, lanes: _Lanes, lane: int) -> None:
        self.__dict__.update(template.__dict__)
        self._attach_data(mujoco.MjData(template.model))
        self._lanes = lanes
        self._lane = lane

    def step(self, n: int) -> None:
        """Park until the batch has advanced this lane by `n` steps."""
        self._lanes.park(self._lane, n)
        self.engine_steps += n
        self.steps_taken += n
        if not math.isfinite(float(self.data.qpos[self._qadr : self._qadr + 7].sum())):
            raise SimulationUnstable(f"physics diverged at t={self.data.time:.3f} s")


@dataclass
class _Lane:
    world: _World
    go: threading.Semaphore
    spec: ExperimentSpec | None = None
    want: int = 0  # steps asked for and not yet taken
    stepped: bool = False  # the device advanced it since it last ran
    result: ExperimentResult | None = None
    spec_done: bool = False
    thread: threading.Thread | None = None


class _Lanes:
    """A `mujoco_warp` batch of `n` worlds of one model, each lane running experiments."""

    def __init__(self, template: VirtualTransferSystem, n: int, device: str, sizes: tuple[int, int],
                 wp: Any, mjw: Any) -> None:  # fmt: skip
        self.wp, self.mjw, self.device = wp, mjw, device
        self.model = template.model
        nconmax, njmax = sizes
        with wp.ScopedDevice(device), warnings.catch_warnings():
            # The object's hulls carry friction 0 on purpose (the belts' priority governs).
            warnings.simplefilter("ignore", UserWarning)
            self.m = mjw.put_model(self.model)
            # MuJoCo caps solver and line-search iterations silently; MuJoCo Warp prints a
            # line per capped step from its kernels. Buffer overflows still print (and
            # `_advance` raises on them).
            capped = mjw.OverflowType.ITERATIONS | mjw.OverflowType.LS_ITERATIONS
            self.m.opt.warn_overflow &= ~capped
            self.d = mjw.put_data(self.model, template.data, nworld=n, nconmax=nconmax,
                                  njmax=njmax)  # fmt: skip
            self.sv = np.tile(self.model.geom_surfacevel, (n, 1, 1))
            self.m.geom_surfacevel = wp.array(self.sv, dtype=self.m.geom_surfacevel.dtype)
        self.nconmax, self.njmax = nconmax, njmax
        self.lanes = [_Lane(_World(template, self, i), threading.Semaphore(0)) for i in range(n)]
        self._parked = threading.Semaphore(0)
        self._cancelled = False
        # Host staging: the device state of every lane (uploaded before, read after a step).
        self.up = {k: np.array(getattr(self.d, k).numpy()) for k in _UPLOAD}
        self.down = {k: np.array(getattr(self.d, k).numpy()) for k in _DOWNLOAD}
        self.batch_steps = 0  # calls of mjw.step (each advances every lane by one step)
        self.resumes = 0  # lane turns on the host (controller, placement, readout)
        self.device_seconds = 0.0  # in `_advance`: upload, steps, download

    # -- lane side (runs in a lane's thread) ----------------------------------------------
    def park(self, i: int, n: int) -> None:
        lane = self.lanes[i]
        lane.want = n
        self._parked.release()
        lane.go.acquire()
        if self._cancelled:
            raise _Cancelled

    def _body(self, i: int, object_id: str, seeing: _Seeing) -> None:
        lane = self.lanes[i]
        try:
            lane.result = _run(lane.spec, lane.world, object_id, None, seeing)
        except _Cancelled:
            return
        finally:
            lane.want = 0
            lane.spec_done = True
            self._parked.release()

    # -- scheduler side ---------------------------------------------------------------------
    def _resume(self, i: int) -> None:
        """Let lane i run until it parks again or finishes (the only thread running)."""
        lane = self.lanes[i]
        world = lane.world
        self.resumes += 1
        if lane.stepped:
            _to_host(self.down, self.up, i, world.data)
            lane.stepped = False
        self.model.geom_surfacevel[:] = self.sv[i]
        lane.go.release()
        self._parked.acquire()
        self.sv[i] = self.model.geom_surfacevel
        _from_host(world.data, self.up, i)

    def _start(self, i: int, spec: ExperimentSpec, object_id: str, seeing: _Seeing) -> None:
        lane = self.lanes[i]
        lane.spec, lane.result, lane.spec_done = spec, None, False
        self.resumes += 1
        lane.thread = threading.Thread(target=self._body, args=(i, object_id, seeing),
                                       name=f"warp-lane-{i}", daemon=True)  # fmt: skip
        lane.thread.start()
        self._parked.acquire()  # runs until its first step (or its end)
        self.sv[i] = self.model.geom_surfacevel
        _from_host(lane.world.data, self.up, i)

    def run(self, specs: Iterable[ExperimentSpec], object_id: str) -> Iterator[list[Row]]:
        """Run `specs` on the lanes; yield the rows of experiments as they finish."""
        seeing = _Seeing("truth", None, None)
        todo = iter(specs)
        active: set[int] = set()
        done: list[Row] = []

        def fill(i: int) -> None:
            """Start experiments on lane i until one asks for steps or none are left."""
            while True:
                lane = self.lanes[i]
                if lane.spec is not None and not lane.spec_done:
                    return
                if lane.spec is not None:
                    lane.thread.join()
                    done.append(lane.result.row())
                    lane.spec = None
                    active.discard(i)
                spec = next(todo, None)
                if spec is None:
                    return
                active.add(i)
                self._start(i, spec, object_id, seeing)

        try:
            for i in range(len(self.lanes)):
                fill(i)
            if done:
                yield done
                done = []
            while active:
                k = min(self.lanes[i].want for i in active)
                self._advance(k)
                for i in sorted(active):
                    lane = self.lanes[i]
                    lane.want -= k
                    lane.stepped = True
                    if lane.want == 0:
                        self._resume(i)
                        fill(i)
                if done:
                    yield done
                    done = []
        finally:
            self._cancel()

    def _advance(self, k: int) -> None:
        """Upload the staged state, step every world `k` times, read the state back."""
        wp, d = self.wp, self.d
        t0 = time.perf_counter()
        with wp.ScopedDevice(self.device):
            for name, host in self.up.items():
                getattr(d, name).assign(host)
            self.m.geom_surfacevel.assign(self.sv)
            for _ in range(k):
                self.mjw.step(self.m, d)
            self.batch_steps += k
            for name in _DOWNLOAD:
                self.down[name] = np.array(getattr(d, name).numpy())  # a copy, also on CPU
            for name in _UPLOAD:
                self.up[name] = self.down[name] if name in self.down else self.up[name]
            nacon, nefc = int(d.nacon.numpy()[0]), int(d.nefc.numpy().max())
        self.device_seconds += time.perf_counter() - t0
        if nacon > d.naconmax or nefc > self.njmax:
            raise RuntimeError(
                f"MuJoCo Warp buffers overflowed ({nacon} contacts for {d.naconmax}, "
                f"{nefc} constraint rows for {self.njmax}): raise WarpExecutor's nconmax/njmax"
            )

    def _cancel(self) -> None:
        """Release every parked lane (they end with `_Cancelled`) and wait for them."""
        self._cancelled = True
        for lane in self.lanes:
            if lane.thread is not None and lane.thread.is_alive():
                lane.go.release()
                lane.thread.join()


# State the host writes (placement, docking, reset) and the device integrates.
_UPLOAD = ("qpos", "qvel", "time", "qacc_warmstart", "mocap_pos", "mocap_quat")
# State the lanes read after a step: the integrated state and the kinematics/sensors of the
# step's forward pass (as `mj_step` leaves them on the host).
_DOWNLOAD = ("qpos", "qvel", "time", "qacc_warmstart", "xpos", "xmat", "sensordata")


def _to_host(down: dict[str, np.ndarray], up: dict[str, np.ndarray], i: int,
             data: mujoco.MjData) -> None:  # fmt: skip
    """Lane i's device state (as read after the last step) into its host `data`."""
    data.qpos[:] = down["qpos"][i]
    data.qvel[:] = down["qvel"][i]
    data.time = float(down["time"][i])
    data.qacc_warmstart[:] = down["qacc_warmstart"][i]
    data.xpos[:] = down["xpos"][i]
    data.xmat[:] = down["xmat"][i].reshape(-1, 9)
    data.sensordata[:] = down["sensordata"][i]
    data.mocap_pos[:] = up["mocap_pos"][i]
    data.mocap_quat[:] = up["mocap_quat"][i]


def _from_host(data: mujoco.MjData, up: dict[str, np.ndarray], i: int) -> None:
    """Lane i's host state (after it ran: reset, placed, docked) into the upload staging."""
    up["qpos"][i] = data.qpos
    up["qvel"][i] = data.qvel
    up["time"][i] = data.time
    up["qacc_warmstart"][i] = data.qacc_warmstart
    up["mocap_pos"][i] = data.mocap_pos
    up["mocap_quat"][i] = data.mocap_quat


class WarpExecutor:
    """Runs experiments as batched MuJoCo Warp worlds; use as a context manager.

    Consecutive experiments of the same object, units and scene share one batch (a study
    plan lists each object's experiments together). Rows come back as experiments finish.
    Counters over the executor's life: `batch_steps` (device steps of the whole batch),
    `resumes` (lane turns on the host), `device_seconds` (uploads, steps and downloads) and
    `seconds` (all time spent producing rows, set-up included; the rest is host time).

    Args:
        worlds: Lanes per batch (worlds stepped together); a group with fewer experiments
            uses fewer.
        device: Warp device; None (default) needs CUDA ("cuda" or "cuda:N" pick one).
            ``"cpu"`` runs Warp's CPU kernels: correct, slow, meant for tests.
        nconmax: Contacts allocated per world (the default scene peaks near 50).
        njmax: Constraint rows allocated per world (the default scene peaks near 150).

    Raises:
        InputError: MuJoCo Warp is not installed, no CUDA device (device None or cuda*), or
            a bad argument.
    """

    def __init__(self, *, worlds: int = 1024, device: str | None = None, nconmax: int = 128,
                 njmax: int = 512) -> None:  # fmt: skip
        if worlds < 1:
            raise InputError(f"worlds must be at least 1, got {worlds}")
        if nconmax < 1 or njmax < 1:
            raise InputError("nconmax and njmax must be at least 1")
        self.worlds = worlds
        self.device = device
        self.nconmax, self.njmax = nconmax, njmax
        self.chunk_size = worlds
        self.cpus = 1
        self.batch_steps = 0
        self.resumes = 0
        self.device_seconds = 0.0
        self.seconds = 0.0
        self._wp: Any = None
        self._mjw: Any = None

    def __repr__(self) -> str:
        return f"WarpExecutor(worlds={self.worlds}, device={self.device or 'cuda'})"

    def start(self) -> WarpExecutor:
        """Import MuJoCo Warp and check the device (fails fast, before any output exists)."""
        wp, mjw = _import_warp()
        device = self.device or "cuda"
        if device.startswith("cuda") and not wp.is_cuda_available():
            raise InputError(NO_CUDA)
        try:
            wp.get_device(device)
        except (RuntimeError, ValueError) as exc:
            raise InputError(f"--executor warp: no Warp device {device!r}: {exc}") from None
        self.device = device
        self._wp, self._mjw = wp, mjw
        return self

    def batches(self, specs: Iterable[ExperimentSpec]) -> Iterator[list[Row]]:
        """Yield result rows as experiments finish, group by group."""
        if self._wp is None:
            raise RuntimeError("WarpExecutor.start() first (or use it as a context manager)")
        key = _group_key
        for (ref, units, scene), group in itertools.groupby(specs, key=key):
            if scene.physics.guard:
                raise InputError("--executor warp does not run the implausible-event guard "
                                 "(physics.guard); use --executor local")  # fmt: skip
            stamp = _stamp(ref)
            object_id = _object(ref, units, stamp).object_id
            # A fresh system, not the process's cached one: the lanes write its surfacevel.
            template = _fresh_system(ref, units, scene, stamp)
            group = list(group)
            lanes = _Lanes(template, min(self.worlds, len(group)), self.device,
                           (self.nconmax, self.njmax), self._wp, self._mjw)  # fmt: skip
            t0 = time.perf_counter()
            try:
                for rows in lanes.run(group, object_id):
                    self.seconds += time.perf_counter() - t0
                    yield rows
                    t0 = time.perf_counter()
            finally:
                self.seconds += time.perf_counter() - t0
                self.batch_steps += lanes.batch_steps
                self.resumes += lanes.resumes
                self.device_seconds += lanes.device_seconds

    def close(self) -> None:
        """Nothing to release (kept for the executor protocol of the CLI)."""

    def __enter__(self) -> WarpExecutor:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()


def _group_key(spec: ExperimentSpec) -> tuple[str, str, Any]:
    return (spec.object_ref, spec.units, spec.scene)


def _fresh_system(ref: str, units: str, scene: Any, stamp: Any) -> VirtualTransferSystem:
    return _system_for.__wrapped__(ref, units, scene, stamp)
