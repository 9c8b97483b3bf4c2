"""`transfertwin cps up/status/order` as a user runs them, and a clean SIGTERM shutdown."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time


def _tt(*args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "transfertwin", *args], capture_output=True,
                          text=True, timeout=timeout)  # fmt: skip


def test_cps_up_order_status_and_sigterm(tmp_path):
    wd = tmp_path / "cps"
    up = subprocess.Popen(
        [sys.executable, "-m", "transfertwin", "cps", "up", "--workdir", str(wd),
         "--time-scale", "0"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
    )  # fmt: skip
    try:
        line = up.stdout.readline()  # blocks until the CPS reports it is up
        assert line.startswith("CPS up: 14 assets"), line
        info = json.loads((wd / "cps.json").read_text())
        assert len(info["assets"]) == 14
        creds = json.loads((wd / "credentials.json").read_text())
        assert set(creds) == {"operator", "observer"}

        order = _tt("cps", "order", "--workdir", str(wd), "--from", "TU_B", "--to", "TU_D",
                    "--object", "o3")  # fmt: skip
        assert order.returncode == 0, order.stderr
        assert "submitted op1" in order.stdout
        assert "TM_1: docked at TU_B" in order.stdout
        assert "TMS: op1 finished" in order.stdout

        status = _tt("cps", "status", "--workdir", str(wd))
        assert status.returncode == 0, status.stderr
        for asset in ("TU_A", "TM_1", "TMS", "KG"):
            assert asset in status.stdout
    finally:
        up.send_signal(signal.SIGTERM)
        t0 = time.monotonic()
        out, _ = up.communicate(timeout=60)
    assert up.returncode == 0
    assert "CPS down" in out
    assert time.monotonic() - t0 < 60


def test_cps_commands_need_a_running_cps(tmp_path):
    res = _tt("cps", "status", "--workdir", str(tmp_path))
    assert res.returncode == 2
    assert "cps up" in res.stderr and len(res.stderr.strip().splitlines()) == 1


def test_cps_export_writes_valid_aas_in_every_format(tmp_path):
    from transfertwin.cps import read_export

    for suffix in (".json", ".xml", ".aasx"):
        out = tmp_path / f"demo{suffix}"
        res = _tt("cps", "export", "--out", str(out), "--with-physical", timeout=120)
        assert res.returncode == 0, res.stderr
        assert "valid" in res.stdout
        ids = {obj.id for obj in read_export(out)}
        assert "https://transfertwin.dev/ids/aas/TU_A" in ids
        assert "https://transfertwin.dev/ids/aas/TU_A_P" in ids
    bad = _tt("cps", "export", "--out", str(tmp_path / "demo.txt"), timeout=120)
    assert bad.returncode == 2 and not (tmp_path / "demo.txt").exists()
