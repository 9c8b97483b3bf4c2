"""`transfertwin validate` against the real calibration experiments (Sec. 6.7).

The physical side is the shipped real table (191 experiments, one per state);
the virtual side is a small CSV made here: 20 made-up runs for two real states of
each of the four objects, all contradicting the real outcome for o1 and agreeing
with it elsewhere, plus one state that was never run physically. Hand-derived:
20/20 vs 0/1 (or 0/20 vs 1/1) has a Newcombe interval that excludes 0, 20/20 vs
1/1 and 0/20 vs 0/1 do not, so exactly o1 differs: "1/4 objects differ".
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import pytest

from transfertwin._errors import InputError
from transfertwin.cli._common import Parser as _Parser
from transfertwin.cli._validate import register
from transfertwin.store import export_results, read_results

REAL = Path(__file__).resolve().parents[3] / "src" / "transfertwin" / "data"
REAL_CSV = REAL / "calibration_experiments.csv"
RUNS = 20
HEADER = "object_id,face,conveyor,theta_deg,n_v,k_v,p_v,n_p,k_p,p_p,diff_low,diff_high,significant"


def parser() -> argparse.ArgumentParser:
    p = _Parser(prog="transfertwin")
    register(p.add_subparsers(dest="command", required=True, parser_class=_Parser))
    return p


def run(*argv: str) -> int:
    args = parser().parse_args(list(argv))
    return args.func(args)


def real_rows() -> list[dict[str, str]]:
    with REAL_CSV.open(newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def chosen_states() -> list[dict[str, str]]:
    """The first two real experiments of each object, in file order."""
    picked: dict[str, list[dict[str, str]]] = {}
    for r in real_rows():
        if len(picked.setdefault(r["object_id"], [])) < 2:
            picked[r["object_id"]].append(r)
    return [r for rows in picked.values() for r in rows]


def write_virtual(path: Path) -> None:
    keys = ("object_id", "face", "conveyor", "theta_deg")
    real_states = {tuple(r[k] for k in keys) for r in real_rows()}
    assert ("o1", "front", "both", "100") not in real_states  # the virtual-only state
    with path.open("w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow([*keys, "run", "success", "status"])
        for r in chosen_states():
            real = int(r["success"])
            outcome = 1 - real if r["object_id"] == "o1" else real
            for run_ in range(RUNS):
                writer.writerow([*(r[k] for k in keys), run_, outcome, "ok"])
            writer.writerow([*(r[k] for k in keys), RUNS, 1 - outcome, "unstable"])  # ignored
        for run_ in range(RUNS):
            writer.writerow(["o1", "front", "both", 100, run_, 1, "ok"])


def test_validate_against_the_real_calibration_csv(tmp_path: Path, capsys) -> None:
    virtual = tmp_path / "virtual.csv"
    write_virtual(virtual)
    out = tmp_path / "out"
    assert run("validate", "--virtual", str(virtual), "--physical", str(REAL_CSV),
               "--out", str(out)) == 0  # fmt: skip
    line = capsys.readouterr().out.strip()
    assert line.startswith("1/4 objects differ (8 states compared, 2 significant")
    assert "1 virtual-only, 183 physical-only" in line

    text = (out / "validation.csv").read_text(encoding="utf-8")
    assert text.splitlines()[0] == HEADER
    records = list(csv.DictReader(text.splitlines()))
    assert len(records) == 8
    assert {(r["n_v"], r["n_p"]) for r in records} == {(str(RUNS), "1")}
    assert {r["object_id"] for r in records if r["significant"] == "1"} == {"o1"}
    for r in records:
        assert abs(float(r["p_v"]) - float(r["p_p"])) == (1.0 if r["object_id"] == "o1" else 0.0)

    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["summary"] == "1/4 objects differ"
    assert summary["differing_objects"] == ["o1"]
    assert (summary["states_virtual_only"], summary["states_physical_only"]) == (1, 183)
    assert summary["objects"]["o1"]["states_virtual_only"] == 1
    assert (out / "validation.png").read_bytes().startswith(b"\x89PNG")


def test_validate_reads_parquet_results(tmp_path: Path, capsys) -> None:
    virtual = tmp_path / "virtual.csv"
    write_virtual(virtual)
    parquet = export_results(read_results(virtual), tmp_path / "virtual.parquet")
    assert run("validate", "--virtual", str(parquet), "--physical", str(REAL_CSV),
               "--out", str(tmp_path / "pq"), "--alpha", "0.1") == 0  # fmt: skip
    assert capsys.readouterr().out.startswith("1/4 objects differ")
    assert json.loads((tmp_path / "pq" / "summary.json").read_text())["alpha"] == 0.1


def test_no_common_state_is_an_input_error_without_output(tmp_path: Path) -> None:
    virtual = tmp_path / "virtual.csv"
    virtual.write_text("object_id,face,conveyor,theta_deg,success\no1,front,both,100,1\n")
    out = tmp_path / "out"
    with pytest.raises(InputError, match="no pre-transfer state was run on both sides"):
        run("validate", "--virtual", str(virtual), "--physical", str(REAL_CSV), "--out", str(out))
    assert not out.exists()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--virtual", "missing.csv", "--physical", str(REAL_CSV), "--out", "o"], "no such file"),
        (["--virtual", str(REAL_CSV), "--physical", "x.txt", "--out", "o"], "unknown result"),
        (["--virtual", str(REAL_CSV), "--physical", str(REAL_CSV)], "--out"),
        (["--virtual", str(REAL_CSV), "--physical", str(REAL_CSV), "--out", "o",
          "--alpha", "2"], "alpha"),
    ],
)  # fmt: skip
def test_bad_input_is_one_input_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, argv: list[str], message: str
) -> None:
    monkeypatch.chdir(tmp_path)
    with pytest.raises(InputError, match=message) as info:
        run("validate", *argv)
    assert "\n" not in str(info.value)
    assert not (tmp_path / "o").exists()


def test_out_must_not_be_a_file(tmp_path: Path) -> None:
    file = tmp_path / "file"
    file.write_text("x")
    with pytest.raises(InputError, match="not a directory"):
        run("validate", "--virtual", str(REAL_CSV), "--physical", str(REAL_CSV),
            "--out", str(file))  # fmt: skip


def test_states_with_one_physical_run_are_reported_without_power(tmp_path: Path, capsys) -> None:
    """n_p = 1 everywhere (the README's case). Hand-derived: the 6 states that agree
    (20/20 vs 1/1, 0/20 vs 0/1) are not significant and 1 run cannot show a difference
    of 0.2; o1's 2 contradicting states are significant and have the power."""
    virtual = tmp_path / "virtual.csv"
    write_virtual(virtual)
    out = tmp_path / "out"
    assert run("validate", "--virtual", str(virtual), "--physical", str(REAL_CSV),
               "--out", str(out)) == 0  # fmt: skip
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 3
    assert lines[1].startswith("183 physical states have no virtual results")  # no WARNING line
    note = lines[2]
    assert note.startswith("6/8 compared states have too few runs to see a difference: "
                           "physical n = 1 per state, virtual n = 20")  # fmt: skip
    assert "does not mean 'no difference'" in note
    assert "Newcombe interval would exclude 0 for a difference of 0.2 with n = " in note
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["power_note"] == note
    assert summary["power"]["states_underpowered"] == 6
