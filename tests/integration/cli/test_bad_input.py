"""Every command refuses bad input the same way: exit code 2, one line on stderr, no
traceback, and no file left behind (issue: reliability, item 8)."""

from __future__ import annotations

import os
import socket
from pathlib import Path

import pytest

from transfertwin.cli import main
from transfertwin.data import calibration_csv_path

HEADER = (
    "experiment_id,transfer_unit,object_id,theta_deg,face,conveyor,success,"
    "dock_err_x_mm,dock_err_y_mm,dock_err_theta_deg\n"
)
T = ["transfer", "--object", "o1", "--face", "front", "--conveyor", "both", "--theta", "0"]
TUNE = ["calibrate", "tune", "--out", "t", "--limit", "6"]
SENS = ["calibrate", "sensitivity", "--limit", "2", "--out", "sens"]
REH = ["rehearse", "--plant-seed", "1", "--objects", "o3", "--calibration-experiments", "20",
       "--out", "reh"]  # fmt: skip
PER = ["perceive", "--object", "o1", "--face", "front", "--conveyor", "both", "--theta", "0"]
EXP = ["cps", "experiment", "--workdir", "nowhere", "--unit", "TU_A", "--object", "o2", "--face",
       "front", "--conveyor", "both", "--theta", "30"]  # fmt: skip
STUDY = ["study", "run", "--db", "s.sqlite", "--objects", "o1", "--theta-step", "180"]

BAD: list[tuple[str, list[str]]] = [
    ("negative seed", [*T, "--seed", "-3", "--image", "neg.png"]),
    ("theta out of range", [*T[:-1], "999"]),
    ("unknown face", [*T[:4], "up", *T[5:]]),
    ("unknown conveyor", [*T[:6], "middle", *T[7:]]),
    ("unknown object", ["transfer", "--object", "o99", *T[3:]]),
    ("missing mesh", ["transfer", "--object", "missing.stl", *T[3:]]),
    ("short docking error", [*T, "--dock-error", "1,2"]),
    ("image not png", [*T, "--image", "x.jpg"]),
    ("image in /sys", [*T, "--image", "/sys/x.png"]),
    ("image under a file", [*T, "--image", "real.csv/x.png"]),
    ("mesh in mm read as m", ["study", "run", "--db", "s.sqlite", "--objects", "box_mm.stl"]),
    ("corrupt mesh", ["study", "run", "--db", "s.sqlite", "--objects", "corrupt.stl"]),
    ("zero max experiments", [*STUDY, "--max-experiments", "0"]),
    ("zero workers", [*STUDY, "--workers", "0"]),
    ("negative workers", [*STUDY, "--workers", "-1"]),
    ("negative study seed", [*STUDY, "--seed", "-1"]),
    ("adaptive option without adaptive", [*STUDY, "--adaptive-epsilon", "0.1"]),
    ("unknown sampling", [*STUDY, "--sampling", "lucky"]),
    ("unknown adaptive interval", [*STUDY, "--sampling", "adaptive", "--adaptive-interval", "x"]),
    ("adaptive confidence of 1", [*STUDY, "--sampling", "adaptive", "--adaptive-confidence", "1"]),
    ("adaptive first runs of 0", [*STUDY, "--sampling", "adaptive", "--adaptive-first-runs", "0"]),
    ("address without ray executor", [*STUDY, "--address", "auto"]),
    ("chunk size without ray executor", [*STUDY, "--chunk-size", "4"]),
    ("unknown executor", [*STUDY, "--executor", "dask"]),
    ("zero ray chunk size", [*STUDY, "--executor", "ray", "--chunk-size", "0"]),
    ("ray address without port", [*STUDY, "--executor", "ray", "--address", "headnode"]),
    ("unreachable ray cluster", [*STUDY, "--executor", "ray", "--address", "127.0.0.1:1"]),
    ("address with warp executor", [*STUDY, "--executor", "warp", "--address", "auto"]),
    ("zero warp worlds", [*STUDY, "--executor", "warp", "--chunk-size", "0"]),
    ("zero runs", [*STUDY, "--runs", "0"]),
    ("study theta step not dividing 360", [*STUDY[:-1], "7"]),
    ("states theta step not dividing 360", ["states", "--theta-step", "7"]),
    ("demo theta step not dividing 360", ["demo", "--out", "d", "--theta-step", "7"]),
    ("unknown docking model", [*STUDY, "--docking", "bogus"]),
    ("missing profile", [*STUDY, "--profile", "missing.toml"]),
    ("db without a db suffix", ["study", "run", "--db", "s.txt", "--objects", "o1"]),
    ("status of a missing db", ["study", "status", "--db", "missing.sqlite"]),
    ("export of a missing db", ["study", "export", "--db", "missing.sqlite", "--out", "x.csv"]),
    ("analyze a missing table", ["analyze", "missing.csv", "--out", "rep"]),
    ("analyze into /sys", ["analyze", "real.csv", "--out", "/sys/rep"]),
    ("calibrate header-only table", ["calibrate", "run", "--real", "header.csv", "--out", "c"]),
    ("calibrate bad theta", ["calibrate", "run", "--real", "bad_theta.csv", "--out", "c"]),
    ("calibrate zero runs", ["calibrate", "run", "--runs", "0", "--out", "c"]),
    ("calibrate zero workers", ["calibrate", "run", "--workers", "0", "--out", "c"]),
    ("calibrate address without ray", ["calibrate", "tune", "--address", "auto", "--out", "c"]),
    (
        "calibrate unreachable ray",
        ["calibrate", "run", "--executor", "ray", "--address", "127.0.0.1:1", "--out", "c"],
    ),
    ("evaluate one fold", ["calibrate", "evaluate", "--folds", "1", "--out", "e"]),
    ("docking fit missing csv", ["docking", "fit", "missing.csv", "--out", "m.json"]),
    ("docking sample zero", ["docking", "sample", "missing.json", "-n", "0", "--out", "s.csv"]),
    ("dock unknown station", ["dock", "--station", "E", "--out", "d.csv"]),
    ("dock empty station list", ["dock", "--station", ",", "--out", "d.csv"]),
    ("dock zero runs", ["dock", "--runs", "0", "--out", "d.csv"]),
    ("dock negative seed", ["dock", "--seed", "-1", "--out", "d.csv"]),
    ("dock out not csv", ["dock", "--out", "d.txt"]),
    ("dock image not png", ["dock", "--out", "d.csv", "--image", "d.jpg"]),
    ("dock missing real table", ["dock", "--out", "d.csv", "--real", "missing.csv"]),
    ("dock real table without units", ["dock", "--out", "d.csv", "--real", "no_units.csv"]),
    (
        "validate missing tables",
        ["validate", "--virtual", "a.csv", "--physical", "b.csv", "--out", "v"],
    ),
    ("export unknown core", ["objects", "export", "o99", "--out", "x.stl"]),
    ("export as obj", ["objects", "export", "o1", "--out", "x.obj"]),
    ("cps status without a cps", ["cps", "status", "--workdir", "nowhere"]),
    ("cps supervise without a floor", ["cps", "supervise", "--workdir", "nowhere"]),
    ("cps supervise no restarts", ["cps", "supervise", "--workdir", ".", "--max-restarts", "0"]),
    ("cps up unknown docking", ["cps", "up", "--workdir", "w", "--docking", "teleport"]),
    (
        "cps order without a cps",
        [
            "cps",
            "order",
            "--workdir",
            "nowhere",
            "--from",
            "TU_A",
            "--to",
            "TU_C",
            "--object",
            "o5",
        ],
    ),
    (
        "cps order zero timeout",
        [
            "cps",
            "order",
            "--workdir",
            "w",
            "--from",
            "TU_A",
            "--to",
            "TU_C",
            "--object",
            "o5",
            "--timeout",
            "0",
        ],
    ),
    ("cps trust without a cps", ["cps", "trust", "real.csv", "--workdir", "nowhere"]),
    ("cps trust missing cert", ["cps", "trust", "missing.der", "--workdir", "cpswd"]),
    ("cps trust not a certificate", ["cps", "trust", "real.csv", "--workdir", "cpswd"]),
    ("cps up negative plant seed", ["cps", "up", "--workdir", "w", "--plant-seed", "-1"]),
    ("cps up plant seed not a number", ["cps", "up", "--workdir", "w", "--plant-seed", "x"]),
    (
        "cps up plant seed with insecure",
        ["cps", "up", "--workdir", "w", "--plant-seed", "1", "--insecure"],
    ),
    ("cps experiment without a cps", [*EXP, "--physical"]),
    ("cps experiment not a state", [*EXP[:11], "left", "--theta", "45"]),
    ("cps experiment unknown object", [*EXP[:7], "o99", *EXP[8:]]),
    ("cps experiment zero runs", [*EXP, "--runs", "0"]),
    ("cps experiment negative seed", [*EXP, "--seed", "-2"]),
    ("demo into /sys", ["demo", "--out", "/sys/demo"]),
    ("data export not csv", ["data", "calibration", "--out", "real.txt"]),
    (
        "calibrate object unknown family",
        ["calibrate", "object", "--object", "o1", "--family", "x", "--out", "o"],
    ),
    ("calibrate object unknown id", ["calibrate", "object", "--object", "o99", "--out", "o"]),
    (
        "calibrate object shift beyond 50 mm",
        ["calibrate", "object", "--object", "o1", "--com-shifts-mm", "-80,10", "--out", "o"],
    ),
    (
        "calibrate object shift the body cannot carry",
        ["calibrate", "object", "--object", "o1", "--com-shifts-mm", "48", "--out", "o"],
    ),
    (
        "calibrate object negative mass penalty",
        ["calibrate", "object", "--object", "o1", "--mass-penalty", "-1", "--out", "o"],
    ),
    (
        "calibrate evaluate negative mass penalty",
        ["calibrate", "evaluate", "--mass-penalty", "-0.1", "--out", "o"],
    ),
    (
        "calibrate object position beyond the length",
        ["calibrate", "object", "--object", "o1", "--positions", "0.3,1.5", "--out", "o"],
    ),
    (
        "calibrate object positions not numbers",
        ["calibrate", "object", "--object", "o1", "--positions", "rear", "--out", "o"],
    ),
    (
        "calibrate object negative position penalty",
        ["calibrate", "object", "--object", "o1", "--position-penalty", "-1", "--out", "o"],
    ),
    (
        "calibrate evaluate negative position penalty",
        ["calibrate", "evaluate", "--position-penalty", "-0.1", "--out", "o"],
    ),
    ("tune unknown space setting", [*TUNE, "--space", "friction=0:1"]),
    ("tune space low above high", [*TUNE, "--space", "mu=0.8:0.3"]),
    ("tune space not a range", [*TUNE, "--space", "mu=0.3"]),
    ("tune log space from zero", [*TUNE, "--space", "mu=0:0.8:log"]),
    ("tune space string setting", [*TUNE, "--space", "physics.solver=1:2"]),
    ("tune space whole tuple", [*TUNE, "--space", "physics.solref=0.002:0.02"]),
    ("tune space value refused", [*TUNE, "--space", "layout.pulley_radius_m=0.01:0.4"]),
    ("tune unknown object face", [*TUNE, "--space", "object.o1.side_depth_mm=0:30"]),
    ("tune object without rows", [*TUNE, "--space", "object.o99.front_depth_mm=0:30"]),
    ("tune depth beyond 100 mm", [*TUNE, "--space", "object.o1.front_depth_mm=0:300"]),
    ("tune mu twice", [*TUNE, "--space", "mu=0.3:0.5", "--mu-min", "0.2"]),
    ("tune shorthand low above high", [*TUNE, "--mu-min", "0.9"]),
    ("tune unknown metric", [*TUNE, "--metric", "auc"]),
    ("tune zero trials", [*TUNE, "--trials", "0"]),
    ("tune negative penalty", [*TUNE, "--penalty", "-1"]),
    ("tune storage not a url", [*TUNE, "--storage", "t.sqlite"]),
    ("tune storage unreachable", [*TUNE, "--storage", "sqlite:////nonexistent/dir/t.db"]),
    ("tune lhs with storage", [*TUNE, "--method", "lhs", "--storage", "sqlite:///t.sqlite"]),
    ("tune profile not toml", [*TUNE, "--save-profile", "p.txt"]),
    ("transfer missing profile", [*T, "--profile", "missing.toml"]),
    ("transfer unknown sensor", [*T, "--sensor", "sonar"]),
    ("sensitivity one level", [*SENS, "--levels", "1"]),
    ("sensitivity zero runs", [*SENS, "--runs", "0"]),
    ("sensitivity on ray", [*SENS, "--executor", "ray"]),
    ("sensitivity unknown factor", [*SENS, "--params", "wobble=0:1"]),
    ("sensitivity reversed range", [*SENS, "--params", "mu=0.8:0.3"]),
    ("sensitivity range not numbers", [*SENS, "--params", "mu=a:b"]),
    ("sensitivity pitch out of range", [*SENS, "--params", "tu_pitch_deg=-20:20"]),
    ("sensitivity string setting", [*SENS, "--params", "physics.solver=0:1"]),
    ("sensitivity factor twice", [*SENS, "--params", "mu,mu=0.2:0.4"]),
    ("sensitivity unknown method", [*SENS, "--method", "sobol"]),
    ("sensitivity morris odd levels", [*SENS, "--method", "morris", "--levels", "3"]),
    (
        "sensitivity morris one factor",
        [*SENS, "--method", "morris", "--params", "mu", "--levels", "4"],
    ),
    ("sensitivity missing proxy", [*SENS, "--object-map", "o1=missing.proxy.json"]),
    ("sensitivity into /sys", ["calibrate", "sensitivity", "--out", "/sys/sens"]),
    ("rehearse unknown object", [*REH[:3], "o99", *REH[4:]]),
    ("rehearse negative plant seed", ["rehearse", "--plant-seed", "-1", *REH[3:]]),
    ("rehearse zero experiments", [*REH[:5], "0", *REH[6:]]),
    ("rehearse bad experiment list", [*REH[:5], "25,x", *REH[6:]]),
    ("rehearse too few to hold out", [*REH[:5], "2", *REH[6:]]),
    ("rehearse zero validation runs", [*REH, "--validation-runs", "0"]),
    ("rehearse theta step not dividing 360", [*REH, "--theta-step", "7"]),
    ("rehearse holdout of 1", [*REH, "--holdout", "1"]),
    ("rehearse into /sys", [*REH[:-1], "/sys/reh"]),
    ("rehearse unknown ablation", [*REH, "--ablate", "mass,gravity"]),
    ("rehearse negative operations", [*REH, "--operations", "-1"]),
    ("rehearse negative test experiments", [*REH, "--test-experiments", "-1"]),
    ("rehearse proxy position below 0", [*REH, "--proxy-positions", "-0.1,0.5"]),
    ("rehearse proxy positions not numbers", [*REH, "--proxy-positions", "front"]),
    ("rehearse empty proxy positions", [*REH, "--proxy-positions", ","]),
    (
        "rehearse one experiment with a test set",
        [*REH[:5], "1", *REH[6:], "--test-experiments", "4"],
    ),
    ("web off loopback without token", ["web", "--host", "0.0.0.0"]),
    ("web short token", ["web", "--token", "abc"]),
    ("web port out of range", ["web", "--port", "70000"]),
    ("web missing db", ["web", "--db", "missing.sqlite"]),
    ("web db not a store", ["web", "--db", "real.csv"]),
    ("web cps not running", ["web", "--cps", "nowhere"]),
    ("web port busy", ["web", "--port", "BUSY"]),
    ("perceive unknown object", ["perceive", "--object", "o99", *PER[3:]]),
    ("perceive unknown face", [*PER[:4], "up", *PER[5:]]),
    ("perceive unknown conveyor", [*PER[:6], "middle", *PER[7:]]),
    ("perceive theta out of range", [*PER[:-1], "999"]),
    ("perceive short docking error", [*PER, "--dock-error", "1,2"]),
    ("perceive negative seed", [*PER, "--seed", "-1", "--image", "p.png"]),
    ("perceive size not WxH", [*PER, "--size", "big"]),
    ("perceive size too small", [*PER, "--size", "4x4"]),
    ("perceive image not png", [*PER, "--image", "p.jpg"]),
    ("perceive image in /sys", [*PER, "--image", "/sys/x.png"]),
    ("web calibration missing", ["web", "--calibration", "nowhere"]),
    ("web calibration not an output folder", ["web", "--calibration", "."]),
    ("unknown command", ["frobnicate"]),
]


@pytest.fixture
def workdir(tmp_path: Path, box_stl: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    (tmp_path / "box_mm.stl").write_bytes(box_stl.read_bytes())
    (tmp_path / "corrupt.stl").write_bytes(b"solid nothing\nendsolid\n")
    (tmp_path / "real.csv").write_text(calibration_csv_path().read_text())
    (tmp_path / "header.csv").write_text(HEADER)
    real = calibration_csv_path().read_text().splitlines()
    (tmp_path / "no_units.csv").write_text(
        "\n".join(",".join(c for i, c in enumerate(line.split(",")) if i != 1) for line in real)
    )
    (tmp_path / "cpswd" / "certs").mkdir(parents=True)  # a CPS workdir (cps trust)
    first = calibration_csv_path().read_text().splitlines()[1].split(",")
    first[3] = "999"
    (tmp_path / "bad_theta.csv").write_text(HEADER + ",".join(first[:10]) + "\n")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _tree(root: Path) -> set[str]:
    return {str(p.relative_to(root)) for p in root.rglob("*")}


@pytest.mark.parametrize(("case", "argv"), BAD, ids=[c for c, _ in BAD])
def test_bad_input_exits_2_with_one_line_and_leaves_nothing(case, argv, workdir, capfd) -> None:
    before = _tree(workdir)
    with socket.socket() as busy:  # a port another program listens on
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = str(busy.getsockname()[1])
        code = main([port if a == "BUSY" else a for a in argv])
    out, err = capfd.readouterr()
    assert code == 2, (case, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("transfertwin: error: "), err
    assert "Traceback" not in out + err
    assert _tree(workdir) == before, f"{case} left files behind"
    assert not os.path.exists("/sys/x.png")
