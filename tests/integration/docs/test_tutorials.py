"""The tutorials run as written: every ``bash`` block of each page in docs/tutorials, top to
bottom in a fresh folder, at a reduced size (`SHRINK`, the substitutions listed below), with
the commands a test cannot run left out (`SKIP`). A tutorial that drifts from the CLI fails
here. Everything a tutorial writes must land in ``work/`` (git ignores it).

Marked slow (minutes: real studies, calibration and a floor of processes); CI runs it
(.ci/run)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

DOCS = Path(__file__).resolve().parents[3] / "docs" / "tutorials"
TT = str(Path(sys.executable).with_name("transfertwin"))

#: (pattern, replacement) applied in order to every command: fewer runs, a coarser θ grid,
#: fewer candidates and trials, the first rows of the real table only.
SHRINK: tuple[tuple[str, str], ...] = (
    (r"--runs \d+", "--runs 1"),
    (r"--theta-step \d+ --workers", "--theta-step 180 --workers"),
    (r"(study run .*--objects work/o7\.stl)", r"\1 --max-experiments 4"),
    (r"--trials \d+", "--trials 2"),
    (r"--levels \d+", "--levels 2"),
    (r"--limit \d+", "--limit 6"),
    (r"(calibrate (run|sweep|tune) )(?!.*--limit)", r"\1--limit 6 "),
    (r"(calibrate object [^;]*?)(;|$)", r"\1 --depths-mm 8 --com-shifts-mm 0\2"),
    (r"(calibrate evaluate .*)$", r"\1 --folds 2 --repeats 1"),
    (r"--values Newton,CG,PGS", "--values Newton,CG"),
    (r"(study run --db work/tuned\.sqlite .*)$", r"\1 --objects o1 --runs 1 --theta-step 180"),
)

#: Commands a test does not run: the set-up (the test already runs in the venv) and the web
#: console, which serves until stopped (its pages have browser tests of their own).
SKIP = (re.compile(r"^\./dev\.sh"), re.compile(r"^\$tt web "))


def commands(page: Path) -> list[str]:
    """The shell lines of a page's ``bash`` blocks: continuation lines joined, comments and
    blank lines dropped, `SKIP` left out, `SHRINK` applied."""
    text = page.read_text(encoding="utf-8")
    out: list[str] = []
    for block in re.findall(r"```bash\n(.*?)```", text, flags=re.S):
        joined = re.sub(r"\\\n\s*", "", block)
        for line in joined.splitlines():
            line = re.sub(r"\s+#.*$", "", line).strip()
            if not line or line.startswith("#") or any(p.search(line) for p in SKIP):
                continue
            for pattern, repl in SHRINK:
                line = re.sub(pattern, repl, line)
            out.append(line)
    return out


def test_the_shrinking_reaches_every_heavy_command() -> None:
    lines = commands(DOCS / "first-study.md") + commands(DOCS / "calibrate.md")
    assert not [x for x in lines if re.search(r"--runs (?!1\b)\d+", x)]
    assert "$tt study run --db work/s.sqlite --objects o1,o18 --runs 1 --theta-step 180 " \
           "--workers 2" in lines  # fmt: skip
    assert all("--limit 6" in x for x in lines if re.search(r"calibrate (run|tune) ", x))


def _run(name: str, tmp_path: Path) -> subprocess.CompletedProcess:
    script = "\n".join(["set -euo pipefail", *commands(DOCS / name)])
    script = script.replace("tt=.venv/bin/transfertwin", f"tt={TT}")
    env = {**os.environ, "MPLBACKEND": "Agg"}
    proc = subprocess.run(["bash", "-c", script], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=1500)  # fmt: skip
    assert proc.returncode == 0, f"{name}:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    outside = sorted(p.name for p in tmp_path.iterdir() if p.name != "work")
    assert outside == [], f"{name} wrote outside work/: {outside}"
    return proc


def test_first_study_runs_as_written(tmp_path: Path) -> None:
    proc = _run("first-study.md", tmp_path)
    assert "WARNING" not in proc.stderr, proc.stderr
    assert re.search(r"(delivered|failed)", proc.stdout)
    assert "moved to the nearest state on a 30° grid" in proc.stdout
    assert "states compared" in proc.stdout
    assert (tmp_path / "work" / "report" / "report.html").is_file()
    assert (tmp_path / "work" / "val" / "validation.csv").is_file()


def test_own_mesh_runs_as_written(tmp_path: Path) -> None:
    _run("own-mesh.md", tmp_path)
    assert (tmp_path / "work" / "mine-report" / "report.html").is_file()


def test_calibrate_runs_as_written(tmp_path: Path) -> None:
    _run("calibrate.md", tmp_path)
    assert (tmp_path / "work" / "objs" / "o1.proxy.json").is_file()
    assert (tmp_path / "work" / "tune" / "profile.toml").is_file()


def test_cps_and_console_runs_as_written(tmp_path: Path) -> None:
    try:
        proc = _run("cps-and-console.md", tmp_path)
    finally:
        for wd in ("cps", "plant"):
            if (tmp_path / "work" / wd / "cps.json").is_file():
                subprocess.run([TT, "cps", "down", "--workdir", str(tmp_path / "work" / wd)],
                               capture_output=True, timeout=120)  # fmt: skip
    assert "o5" in proc.stdout and "TU_C" in proc.stdout
    assert re.search(r"campaign \w{12}: finished; \d+ E\^P", proc.stdout), proc.stdout[-2000:]
