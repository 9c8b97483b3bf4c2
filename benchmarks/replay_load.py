"""How long a replay takes: recording against the plain experiment, and the 3-D page's load.

1. Recording: `record_experiment` against `run_experiment` of the same spec (both in this
   process, best of `--repeat`): the recording clock's overhead as a ratio.
2. Loading: `transfertwin replay --no-browser` serves the replay of a 30 s transfer (the
   early timeout off, so the time line covers all of t_max) and, as the baseline, of a 3 s
   one; Debian's chromium (Playwright, WebGL through SwiftShader) opens each `--loads`
   times; printed: navigation to the first rendered frame (the page's own clock), best and
   median, and the ratio 30 s / 3 s (the load hardly grows with the replay's length: three.js,
   the WebGL context and the first frame dominate).

    PYTHONPATH=src .venv/bin/python benchmarks/replay_load.py [--loads 5] [--repeat 3]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from transfertwin.replay import record_experiment, transfer_spec
from transfertwin.sim import SceneConfig
from transfertwin.study.experiment import run_experiment, save_profile

GL_ARGS = ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
           "--ignore-gpu-blocklist"]  # fmt: skip
READY = "() => { const r = window.__replay; return Boolean(r && (r.ready || r.error)); }"


def _best(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def _loads(browser, args: list[str], n: int) -> tuple[list[float], float]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "transfertwin", "replay", "--no-browser", "--port", "0", *args],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )  # fmt: skip
    try:
        proc.stdout.readline()
        url = proc.stdout.readline().split(" ", 1)[1].strip()
        out, duration = [], 0.0
        for _ in range(n):
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.goto(url)
            page.wait_for_function(READY, timeout=120_000)
            load_ms, duration, error = page.evaluate(
                "[window.__replay.loadMs, window.__replay.duration, window.__replay.error]")
            if error:
                raise RuntimeError(error)
            out.append(load_ms)
            page.close()
        return out, duration
    finally:
        proc.terminate()
        proc.wait(30)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--loads", type=int, default=5, help="page loads per replay")
    parser.add_argument("--repeat", type=int, default=3, help="recordings per figure")
    parser.add_argument("--chromium", default="/usr/bin/chromium")
    args = parser.parse_args()
    state = ("o1", "front", "both", 0)
    with tempfile.TemporaryDirectory() as tmp:
        profile = save_profile(Path(tmp) / "nostall.toml", "nostall",
                               SceneConfig().with_overrides(stall_time_s=None))  # fmt: skip
        from transfertwin.study.experiment import load_profile

        spec = transfer_spec(*state, seed=3, profile=str(profile))
        assert load_profile(str(profile))[1].stall_time_s is None
        plain = _best(lambda: run_experiment(spec), args.repeat)
        recorded = _best(lambda: record_experiment(spec), args.repeat)
        replay = record_experiment(spec)
        print(f"recording: {replay.duration_s:.2f} s simulated, {len(replay.t_s)} samples; "
              f"run_experiment {plain:.3f} s, record_experiment {recorded:.3f} s "
              f"(best of {args.repeat}): ratio {recorded / plain:.2f}")  # fmt: skip
        from playwright.sync_api import sync_playwright

        long_args = ["--object", "o1", "--face", "front", "--conveyor", "both", "--theta", "0",
                     "--seed", "3", "--profile", str(profile)]  # fmt: skip
        short_args = ["--object", "o1", "--face", "front", "--conveyor", "both", "--theta",
                      "90", "--seed", "3", "--gap-mm", "80"]  # fmt: skip
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=args.chromium, args=GL_ARGS)
            try:
                long_ms, long_s = _loads(browser, long_args, args.loads)
                short_ms, short_s = _loads(browser, short_args, args.loads)
            finally:
                browser.close()
    for name, ms, dur in (("30 s transfer", long_ms, long_s), ("baseline", short_ms, short_s)):
        print(f"page load, {name} ({dur:.2f} s replay): best {min(ms):.0f} ms, median "
              f"{statistics.median(ms):.0f} ms over {len(ms)} loads (navigation to first frame)")
    print(f"ratio 30 s / baseline (best): {min(long_ms) / min(short_ms):.2f}")


if __name__ == "__main__":
    main()
