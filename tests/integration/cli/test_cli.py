"""The `transfertwin` command: contracts of output, exit codes and error lines."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from transfertwin.cli import main


def _run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "transfertwin", *args], capture_output=True, text=True, timeout=300
    )


def test_states_prints_924_rows_with_the_contract_header(capsys):
    assert main(["states"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "face,conveyor,theta_deg,x_m,y_m"
    assert len(lines) == 1 + 924


def test_theta_step_30_keeps_28_states(capsys):
    assert main(["states", "--theta-step", "30"]) == 0
    assert len(capsys.readouterr().out.splitlines()) == 1 + 28


def test_transfer_json_is_one_object_with_the_contract_keys(box_stl):
    proc = _run("transfer", "--object", str(box_stl), "--units", "mm", "--face", "front",
                "--conveyor", "both", "--theta", "0", "--json")  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    payload = json.loads(proc.stdout)
    assert {"y1", "y2", "success", "status", "t_end_s"} <= payload.keys()
    assert payload["status"] == "ok" and payload["success"] == 1


def test_transfer_image_writes_a_png_strip(box_stl, tmp_path):
    out = tmp_path / "strip.png"
    rc = main(["transfer", "--object", str(box_stl), "--units", "mm", "--face", "front",
               "--conveyor", "both", "--theta", "30", "--image", str(out)])  # fmt: skip
    assert rc == 0
    from PIL import Image

    with Image.open(out) as img:
        assert img.width == 4 * 480 and img.height > 260  # rows of four frames
        assert len(img.getcolors(maxcolors=1 << 20)) > 50  # not a blank image


def test_corrupt_stl_is_exit_2_with_one_line_and_no_traceback(tmp_path):
    bad = tmp_path / "broken.stl"
    bad.write_bytes(b"solid x\nfacet normal 0 0 1\n outer loop\n vertex 0 0 nan\n")
    out = tmp_path / "never.png"
    proc = _run("transfer", "--object", str(bad), "--face", "front", "--conveyor", "both",
                "--theta", "0", "--image", str(out))  # fmt: skip
    assert proc.returncode == 2
    assert proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "broken.stl" in lines[0]
    assert "Traceback" not in proc.stderr
    assert not out.exists()


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--face", "up", "--conveyor", "both", "--theta", "0"], "face"),
        (["--face", "front", "--conveyor", "middle", "--theta", "0"], "conveyor"),
        (["--face", "front", "--conveyor", "both", "--theta", "181"], "theta"),
        (["--face", "front", "--conveyor", "both", "--theta", "0", "--dock-error=1,2"], "dock"),
        (["--face", "front", "--conveyor", "both", "--theta", "0", "--gap-mm", "-3"], "gap"),
    ],
)
def test_bad_arguments_are_exit_2_with_one_line(args, needle, capsys):
    assert main(["transfer", "--object", "o1", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0].lower()


def test_unknown_object_is_exit_2(capsys):
    rc = main(["transfer", "--object", "o99", "--face", "front", "--conveyor", "both",
               "--theta", "0"])  # fmt: skip
    assert rc == 2
    assert "o99" in capsys.readouterr().err


def test_objects_export_writes_a_loadable_stl(tmp_path):
    import trimesh

    out = tmp_path / "o3.stl"
    assert main(["objects", "export", "o3", "--out", str(out)]) == 0
    mesh = trimesh.load_mesh(out)
    assert mesh.is_watertight
    assert 0.18 <= mesh.extents.max() <= 0.26


def test_python_dash_m_and_console_script_agree():
    proc = _run("states", "--theta-step", "90")
    exe = Path(sys.executable).with_name("transfertwin")
    proc2 = subprocess.run([str(exe), "states", "--theta-step", "90"], capture_output=True,
                           text=True, timeout=120)  # fmt: skip
    assert proc.returncode == proc2.returncode == 0
    assert proc.stdout == proc2.stdout


def test_strip_title_names_each_transfer_and_never_says_none():
    import math as _math

    from transfertwin.cli._transfer import strip_title
    from transfertwin.study.experiment import ExperimentResult

    base = dict(
        object_id="o1", face="front", conveyor="left", theta_deg=10, run=0, seed=0,
        dock_err_x_mm=-8.55, dock_err_y_mm=2.84, dock_err_theta_deg=1.44,
    )  # fmt: skip
    failed = ExperimentResult(
        **base, y1=0, y2=None, success=0, t_end_s=2.0, status="ok", t_end_1_s=2.0,
        t_end_2_s=_math.nan,
    )  # fmt: skip
    text = " | ".join(strip_title(failed))
    assert "None" not in text and "nan" not in text
    assert "TU → TM: not attempted (the transfer there failed)" in text
    assert "TM → TU: failed after 2.00 s" in text
    assert "conveyor left" in text and "θ = 10°" in text and "x = -8.55 mm" in text
    ok = ExperimentResult(
        **base, y1=1, y2=1, success=1, t_end_s=6.37, status="ok", t_end_1_s=3.575,
        t_end_2_s=2.795,
    )  # fmt: skip
    assert "delivered and brought back in 6.37 s" in " ".join(strip_title(ok))
    bad = ExperimentResult(
        **base, y1=None, y2=None, success=None, t_end_s=_math.nan, status="invalid",
        message="settled state is not a pre-transfer state (Eq. 6.1)",
    )  # fmt: skip
    text = " ".join(strip_title(bad))
    assert "None" not in text and "not run: the object did not settle" in text
