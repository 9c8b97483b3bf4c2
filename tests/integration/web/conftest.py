"""Fixtures of the console tests: a small real study store, a CPS, the console served by
`transfertwin web`, and Debian's chromium driven by Playwright."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

CHROMIUM = os.environ.get("TRANSFERTWIN_CHROMIUM", "/usr/bin/chromium")


@pytest.fixture(scope="session")
def tiny_study(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """6 of the 12 experiments of o1 at θ step 90 (one run), run for real into SQLite."""
    from transfertwin.store import SQLiteResultStore
    from transfertwin.study.docking import docking_model
    from transfertwin.study.experiment import StudyPlan, run_study

    db = tmp_path_factory.mktemp("study") / "tiny.sqlite"
    plan = StudyPlan(objects=("o1",), theta_step=90, runs=1, seed=3,
                     docking=docking_model("copula", None))  # fmt: skip
    with SQLiteResultStore(db) as store:
        run_study(plan, store, workers=1, max_experiments=6)
    return db


def _stop(proc: subprocess.Popen, timeout: float = 60) -> str:
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
    try:
        out, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, _ = proc.communicate()
    return out or ""


@pytest.fixture(scope="module")
def cps_workdir(tmp_path_factory: pytest.TempPathFactory):
    """`transfertwin cps up` in a temporary work folder (as in tests/integration/cps)."""
    wd = tmp_path_factory.mktemp("cps") / "wd"
    up = subprocess.Popen(
        [sys.executable, "-m", "transfertwin", "cps", "up", "--single-process",
         "--policy", "nearest-idle", "--workdir",
         str(wd),
         "--time-scale", "0"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
    )  # fmt: skip
    try:
        line = up.stdout.readline()  # blocks until the CPS reports it is up
        assert line.startswith("CPS up"), line
        yield wd
    finally:
        _stop(up)


class Console:
    """`transfertwin web` running in a subprocess."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "transfertwin", "web", "--port", "0", *args],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        )  # fmt: skip
        line = self.proc.stdout.readline()
        assert line.startswith("console: http://"), line
        self.url = line.split(" ", 1)[1].strip()
        self.base, _, self.token = self.url.partition("/?token=")

    def stop(self) -> str:
        return _stop(self.proc)


@pytest.fixture
def console_factory():
    consoles: list[Console] = []

    def start(*args: str) -> Console:
        consoles.append(Console(*args))
        return consoles[-1]

    yield start
    for c in consoles:
        c.stop()


def credential_strings(wd: Path) -> list[str]:
    """Every user name and password in a CPS's credentials file."""
    creds = json.loads((wd / "credentials.json").read_text())
    return [v for d in creds.values() for v in (d["username"], d["password"])]


@pytest.fixture(scope="session")
def chromium_path() -> str:
    """Debian's chromium; missing: skipped locally, a failure in CI."""
    path = shutil.which(CHROMIUM) or (CHROMIUM if Path(CHROMIUM).is_file() else None)
    try:
        import playwright  # noqa: F401
    except ImportError:
        path = None
    if path is None:
        reason = (f"no chromium at {CHROMIUM} or no playwright package "
                  "(./dev.sh installs both: apt package 'chromium', pip 'playwright')")  # fmt: skip
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(f"browser tests must run in CI: {reason}")
        pytest.skip(reason)
    return path


@pytest.fixture
def page(chromium_path: str):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium_path,
                                    args=["--no-sandbox", "--disable-gpu"])  # fmt: skip
        context = browser.new_context(viewport={"width": 1400, "height": 900})
        page = context.new_page()
        page.set_default_timeout(60_000)
        yield page
        browser.close()


def save_screenshot(page, tmp_path: Path, name: str) -> Path:
    """Screenshot into the test's folder (and into TRANSFERTWIN_SCREENSHOTS if set)."""
    path = tmp_path / f"{name}.png"
    page.screenshot(path=str(path), full_page=True)
    extra = os.environ.get("TRANSFERTWIN_SCREENSHOTS")
    if extra:
        Path(extra).mkdir(parents=True, exist_ok=True)
        shutil.copy(path, Path(extra) / path.name)
    return path


def wait_for(predicate, timeout: float, what: str, period: float = 0.5):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(period)
    raise AssertionError(f"timed out after {timeout:g} s waiting for {what}")
