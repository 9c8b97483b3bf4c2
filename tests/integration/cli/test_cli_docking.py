"""`docking fit|sample|plot` (Sec. 6.4) through a parser built like `transfertwin.cli`'s.

The subcommands are registered on a local `_Parser` (one-line `InputError` instead of
argparse's exit), so these tests do not depend on `cli.py` wiring them in.
"""

from __future__ import annotations

import csv
import json
from importlib import resources
from pathlib import Path

import pytest

from transfertwin._errors import InputError
from transfertwin.cli._common import Parser as _Parser
from transfertwin.cli._docking import register
from transfertwin.study import measured_docking_errors

HEADER = ["dock_err_x_mm", "dock_err_y_mm", "dock_err_theta_deg"]
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def run(*argv: str | Path) -> int:
    parser = _Parser(prog="transfertwin")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    register(sub)
    args = parser.parse_args([str(a) for a in argv])
    return args.func(args)


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("docking")
    text = resources.files("transfertwin.data").joinpath("calibration_experiments.csv").read_text()
    (folder / "real.csv").write_text(text)
    rows = list(csv.DictReader(text.splitlines()))
    with (folder / "no_units.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(HEADER)
        w.writerows([r[c] for c in HEADER] for r in rows)
    with (folder / "nine.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(HEADER)
        w.writerows([r[c] for c in HEADER] for r in rows[:9])
    (folder / "no_theta.csv").write_text("dock_err_x_mm,dock_err_y_mm\n1,2\n")
    (folder / "bad.json").write_text("{not json")
    (folder / "fixed.json").write_text(json.dumps({"kind": "fixed", "x_mm": 0}))
    assert run("docking", "fit", folder / "real.csv", "--out", folder / "model.json") == 0
    return folder


def _read(path: Path) -> list[list[str]]:
    with path.open(newline="") as fh:
        return list(csv.reader(fh))


def test_sec_6_4_fit_then_sample_writes_n_rows_with_the_header(data_dir: Path, tmp_path) -> None:
    out = tmp_path / "samples.csv"
    assert run("docking", "sample", data_dir / "model.json", "-n", "250", "--seed", "3",
               "--out", out) == 0  # fmt: skip
    rows = _read(out)
    assert rows[0] == HEADER and len(rows) == 1 + 250
    assert measured_docking_errors(out).shape == (250, 3)  # readable by the study's loader
    again = tmp_path / "again.csv"
    run("docking", "sample", data_dir / "model.json", "-n", "250", "--seed", "3", "--out", again)
    assert again.read_bytes() == out.read_bytes()
    other = tmp_path / "other.csv"
    run("docking", "sample", data_dir / "model.json", "-n", "250", "--seed", "4", "--out", other)
    assert other.read_bytes() != out.read_bytes()


def test_sec_6_4_fit_reports_the_winning_family_per_component(data_dir, tmp_path, capsys) -> None:
    out = tmp_path / "m.json"
    assert run("docking", "fit", data_dir / "no_units.csv", "--out", out) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split(":")[0] for line in lines[:3]] == [f"all {c}" for c in HEADER]
    desc = json.loads(out.read_text())
    assert desc["kind"] == "copula" and desc["n_fit"] == 191
    assert out.read_text() == (data_dir / "model.json").read_text()  # deterministic fit


def test_sec_6_4_per_station_fit_and_sample_add_the_transfer_unit(data_dir, tmp_path) -> None:
    model = tmp_path / "ps.json"
    assert run("docking", "fit", data_dir / "real.csv", "--out", model, "--per-station") == 0
    assert json.loads(model.read_text())["kind"] == "copula-per-station"
    out = tmp_path / "ps.csv"
    assert run("docking", "sample", model, "-n", "400", "--out", out) == 0
    rows = _read(out)
    assert rows[0] == [*HEADER, "transfer_unit"] and len(rows) == 401
    assert {r[3] for r in rows[1:]} == {"TU_A", "TU_B", "TU_C", "TU_D"}


def test_fig_6_9_to_6_11_plot_writes_two_pngs(data_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "plots"
    assert run("docking", "plot", data_dir / "real.csv", data_dir / "model.json",
               "--out", out, "-n", "2000") == 0  # fmt: skip
    names = sorted(p.name for p in out.iterdir())
    assert names == ["docking_correlations.png", "docking_histograms.png"]
    assert all((out / n).read_bytes().startswith(PNG_MAGIC) for n in names)


BAD = [
    (("fit", "{d}/no_theta.csv", "--out", "{t}/m.json"), "missing column"),
    (("fit", "{d}/nine.csv", "--out", "{t}/m.json"), "at least 10 rows, got 9"),
    (("fit", "{d}/absent.csv", "--out", "{t}/m.json"), "cannot read"),
    (("fit", "{d}/real.csv", "--out", "{t}/m.txt"), "ending in .json"),
    (("fit", "{d}/real.csv", "--out", "{t}/missing/m.json"), "does not exist"),
    (("fit", "{d}/no_units.csv", "--out", "{t}/m.json", "--per-station"), "transfer_unit"),
    (("sample", "{d}/bad.json", "-n", "5", "--out", "{t}/s.csv"), "not valid JSON"),
    (("sample", "{d}/fixed.json", "-n", "5", "--out", "{t}/s.csv"), "expected kind 'copula'"),
    (("sample", "{d}/model.json", "-n", "0", "--out", "{t}/s.csv"), "at least 1"),
    (("sample", "{d}/model.json", "-n", "many", "--out", "{t}/s.csv"), "invalid int"),
    (("sample", "{d}/model.json", "-n", "5", "--out", "{t}/s.json"), "ending in .csv"),
    (("plot", "{d}/real.csv", "{d}/model.json", "--out", "{d}/real.csv"), "not a directory"),
    (("plot", "{d}/nine.csv", "{d}/model.json", "--out", "{t}/p"), "at least 10 rows"),
    ((), "required"),
]


@pytest.mark.parametrize(("argv", "match"), BAD, ids=[m for _, m in BAD])
def test_sec_6_4_bad_input_is_one_line_input_error_and_writes_nothing(
    data_dir: Path, tmp_path: Path, argv: tuple[str, ...], match: str
) -> None:
    args = [a.format(d=data_dir, t=tmp_path) for a in argv]
    with pytest.raises(InputError, match=match) as info:
        run("docking", *args)
    assert "\n" not in str(info.value)
    assert list(tmp_path.iterdir()) == []
