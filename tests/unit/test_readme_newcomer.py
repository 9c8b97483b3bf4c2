"""What a newcomer reads beside the commands (docs/how-to/commands.md) and in the README.

- Each slow example says how long it took on a 2-core machine and names the faster way.
- The mesh convention ('front', 'back', θ = 0 for any mesh) is stated beside the commands,
  with the picture that ``scripts/make_mesh_convention.py`` draws from a built-in core; the
  study report repeats it for a user mesh.
- The README fits on one page and leads with the two commands.
"""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

from transfertwin.report import write_report
from transfertwin.report._mesh_convention import MESH_CONVENTION, mesh_convention_html
from transfertwin.study.fullstate import analyze

ROOT = Path(__file__).parents[2]
README = (ROOT / "README.md").read_text(encoding="utf-8")
COMMANDS = (ROOT / "docs" / "how-to" / "commands.md").read_text(encoding="utf-8")
TIME = re.compile(r"~\s?\d+(\.\d+)?\s?(s|min|h)\b.*2 cores|2 cores.*~\s?\d+(\.\d+)?\s?(s|min|h)\b")


def block_lines() -> list[str]:
    section = COMMANDS.split("## Commands", 1)[1]
    return section.split("```bash", 1)[1].split("```", 1)[0].splitlines()


def comment_near(pattern: str, before: int = 1, after: int = 3) -> str:
    lines = block_lines()
    hits = [i for i, line in enumerate(lines) if pattern in line]
    assert hits, f"commands.md's command block has no line with {pattern!r}"
    i = hits[0]
    return "\n".join(lines[max(0, i - before) : i + after + 1])


@pytest.mark.parametrize(
    ("pattern", "faster"),
    [
        ("--runs 50 --theta-step 5", "--sampling adaptive"),
        ("--preset full", "--executor ray"),
        ("calibrate object --object $o", "--executor ray"),
        ("--trials 60 --runs 3 --metric brier", "--executor ray"),
    ],
)
def test_slow_examples_give_their_time_on_2_cores_and_the_faster_way(
    pattern: str, faster: str
) -> None:
    near = comment_near(pattern)
    assert TIME.search(near), f"no '~N min ... 2 cores' beside {pattern!r}:\n{near}"
    assert faster in near, f"no {faster!r} beside {pattern!r}:\n{near}"


def test_the_mesh_convention_and_its_picture_are_beside_the_commands() -> None:
    usage = COMMANDS.split("## Commands", 1)[1].split("## What the outputs hold", 1)[0]
    assert "as modelled" in usage and "+x" in usage and "θ = 0" in usage
    assert "'back' is it turned over by 180° about x" in usage
    assert "(../img/mesh-convention.png)" in usage
    png = ROOT / "docs" / "img" / "mesh-convention.png"
    assert png.read_bytes()[:4] == b"\x89PNG" and png.stat().st_size < 120_000


def test_the_picture_script_draws_three_panels_from_a_core() -> None:
    path = ROOT / "scripts" / "make_mesh_convention.py"
    spec = importlib.util.spec_from_file_location("make_mesh_convention", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert len(module.draw("o1").axes) == 3


def rows() -> list[dict]:
    return [
        dict(object_id=obj, face=face, conveyor="both", theta_deg=t, success=int(t > 105))
        for obj in ("part",)
        for face in ("front", "back")
        for t in (100, 105, 110, 115)
    ]


def test_the_report_states_the_convention_for_a_user_mesh(tmp_path: Path) -> None:
    params = {"plan.objects": ["o1", "meshes/part.stl"]}
    page = write_report(tmp_path, analyze(rows()), params).read_text(encoding="utf-8")
    assert "Orientation of <code>part.stl</code>: a mesh is used as modelled" in page
    assert "turned over by 180° about x" in page
    assert mesh_convention_html({"plan.objects": ["o1", "o18"]}) == ""
    assert MESH_CONVENTION.startswith("the file's +x axis is the object's x axis")


def test_the_readme_fits_on_a_page_and_leads_with_the_two_commands() -> None:
    assert len(README.splitlines()) < 120
    first_block = README.split("```bash\n", 1)[1].split("```", 1)[0].splitlines()
    assert [line.split()[:2] for line in first_block] == [
        ["./dev.sh", "run"],
        ["./dev.sh", "test"],
    ]
    assert "./dev.sh exec .venv/bin/mkdocs serve" in README
