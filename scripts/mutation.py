"""Mutation testing of the modules the study rests on: score per module, and the survivors.

    ./dev.sh exec .venv/bin/python scripts/mutation.py                 # fresh run, then report
    ./dev.sh exec .venv/bin/python scripts/mutation.py --keep          # reuse mutants/ results
    ./dev.sh exec .venv/bin/python scripts/mutation.py --report-only --diffs
    ./dev.sh exec .venv/bin/python scripts/mutation.py --rerun-survivors  # after adding tests
    ./dev.sh exec .venv/bin/python scripts/mutation.py --out benchmarks/results/mutation.json

mutmut (configured in pyproject.toml, `[tool.mutmut]`) copies src/ to mutants/, changes one
operator, constant or call at a time in the scoped modules, and runs the unit tests that call
the changed function. A mutant the tests fail on is *killed*; one they pass *survives*.
Left out of the score, each in its own column: mutants listed as equivalent in
scripts/mutation_equivalent.toml (with the reason), mutants of functions listed there as
outside the scope, and mutants that change only what an exception's message, a log record or
a warning says (found here, `message_only`). The score of a module is

    (killed + timed out) / (mutants - equivalent - message - outside)

and the run exits 1 if a module scores below --min-score (95 %). How to read the output:
docs/how-to/mutation-testing.md.
"""

from __future__ import annotations

import argparse
import ast
import json
import os
import shutil
import subprocess
import sys
import time
import tomllib
from collections import Counter
from dataclasses import dataclass, field
from datetime import UTC, datetime
from fnmatch import fnmatch
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MUTANTS = ROOT / "mutants"
LISTED = ROOT / "scripts" / "mutation_equivalent.toml"
# The scoped modules, as the report groups them (path prefixes under src/transfertwin/).
MODULES = (
    "ots/",
    "study/fullstate/",
    "study/validation/",
    "study/docking/",
    "study/calibration/_metrics.py",
    "cps/dispatch/_learn.py",
    "cps/dispatch/_predict.py",
)
# mutmut's exit codes of a mutant's test run (mutmut/stats.py), folded to what the score needs.
KILLED_CODES = {1: "killed", 3: "killed", -11: "killed", -9: "killed", 37: "killed", 36: "timeout",
                24: "timeout", -24: "timeout", 152: "timeout", 255: "timeout"}  # fmt: skip
OTHER_CODES = {0: "survived", 5: "no tests", 33: "no tests", 34: "skipped", None: "not checked"}
EXCLUDED = ("equivalent", "message", "outside", "skipped")
COLUMNS = ("killed", "timeout", "survived", "no tests", "not checked", "equivalent", "message",
           "outside")  # fmt: skip


@dataclass(frozen=True)
class Mutant:
    """One mutant: its mutmut name, source file (relative to src/transfertwin/) and status
    (mutmut's, or after `classify` the kind the score counts it as)."""

    name: str
    file: str
    status: str

    @property
    def killed(self) -> bool:
        return self.status in ("killed", "timeout")

    @property
    def function(self) -> str:
        """mutmut's mangled name of the mutated function, e.g. '...._learn.x_fallback'."""
        return self.name.rpartition("__mutmut_")[0]


@dataclass
class ModuleScore:
    """Counts of one scoped module by kind (see `classify`)."""

    module: str
    counts: Counter = field(default_factory=Counter)

    @property
    def considered(self) -> int:
        return sum(self.counts.values()) - sum(self.counts[k] for k in EXCLUDED)

    @property
    def score(self) -> float:
        """(killed + timeout) / considered, in [0, 1]; 1 when nothing is considered."""
        killed = self.counts["killed"] + self.counts["timeout"]
        return killed / self.considered if self.considered else 1.0


@dataclass(frozen=True)
class Listed:
    """scripts/mutation_equivalent.toml: equivalent mutants (name -> entry with 'line', the
    mutated line, and 'why') and functions outside the scope (mangled name -> why)."""

    equivalent: dict[str, dict[str, str]]
    outside: dict[str, str]


def load_listed(path: Path = LISTED) -> Listed:
    """The listed equivalent mutants and out-of-scope functions (empty without the file)."""
    data = tomllib.loads(path.read_text()) if path.exists() else {}
    return Listed(
        {e["mutant"]: e for e in data.get("equivalent", [])},
        {e["function"]: e["why"] for e in data.get("outside", [])},
    )


def run_mutmut(workers: int, keep: bool, log: Path) -> float:
    """Run `mutmut run` with `workers` children; returns the wall time in seconds."""
    if not keep and MUTANTS.exists():
        shutil.rmtree(MUTANTS)
    MUTANTS.mkdir(exist_ok=True)
    mutmut = Path(sys.executable).with_name("mutmut")
    start = time.monotonic()
    with log.open("w") as fh:
        cmd = [str(mutmut), "run", "--max-children", str(workers)]
        rc = subprocess.call(cmd, cwd=ROOT, stdout=fh, stderr=subprocess.STDOUT)
    if rc != 0:
        sys.exit(f"mutmut run failed (exit {rc}); its output: {log}")
    return time.monotonic() - start


def in_scope(path: str) -> bool:
    """Whether `path` (e.g. 'src/transfertwin/ots/_sets.py') is mutated by the pyproject.toml
    configuration (`only_mutate`, `do_not_mutate`)."""
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["mutmut"]
    only, never = cfg.get("only_mutate", ["*"]), cfg.get("do_not_mutate", [])
    return any(fnmatch(path, p) for p in only) and not any(fnmatch(path, p) for p in never)


def rerun_survivors(listed: Listed, workers: int, log: Path) -> float:
    """Run the mutants of the last run that no test killed again (after adding tests), in
    the same mutants/ (mutmut copies the tests anew); returns the wall time in seconds."""
    names = [m.name for m in classify(read_mutants(), listed)
             if m.status in ("survived", "no tests", "not checked", "suspicious")]  # fmt: skip
    mutmut = Path(sys.executable).with_name("mutmut")
    start = time.monotonic()
    with log.open("a") as fh:
        for i in range(0, len(names), 300):  # mutmut takes the names as arguments
            cmd = [str(mutmut), "run", "--max-children", str(workers), *names[i : i + 300]]
            rc = subprocess.call(cmd, cwd=ROOT, stdout=fh, stderr=subprocess.STDOUT)
            if rc != 0:
                sys.exit(f"mutmut run failed (exit {rc}); its output: {log}")
    return time.monotonic() - start


def read_mutants() -> list[Mutant]:
    """Every mutant of the scoped modules with mutmut's status, from its .meta files (files a
    narrower configuration no longer mutates are left out)."""
    out = []
    base = MUTANTS / "src" / "transfertwin"
    for meta in sorted(base.rglob("*.py.meta")):
        rel = meta.relative_to(base).as_posix()[: -len(".meta")]
        if not in_scope(f"src/transfertwin/{rel}"):
            continue
        codes = json.loads(meta.read_text())["exit_code_by_key"]
        for name, code in sorted(codes.items(), key=lambda kv: _natural(kv[0])):
            status = KILLED_CODES.get(code) or OTHER_CODES.get(code, "suspicious")
            out.append(Mutant(name, rel, status))
    return out


def _natural(name: str) -> tuple[str, int]:
    stem, _, number = name.rpartition("__mutmut_")
    return stem, int(number) if number.isdigit() else 0


def diff_of(name: str) -> str:
    """mutmut's diff of one mutant (the original function against the mutated one)."""
    try:
        from mutmut.mutation.diff_apply import get_diff_for_mutant
    except ImportError:  # another mutmut layout: ask its CLI
        mutmut = Path(sys.executable).with_name("mutmut")
        cmd = [str(mutmut), "show", name]
        return subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True).stdout
    return get_diff_for_mutant(name)


def _changed_lines(diff: str, sign: str) -> list[str]:
    return [ln[1:] for ln in diff.splitlines() if ln.startswith(sign) and ln[:3] != sign * 3]


def mutated_line(diff: str) -> str:
    """The first added line of a diff, stripped: what the mutant changed a line to."""
    added = _changed_lines(diff, "+")
    return added[0].strip() if added else ""


_LOG_CALLS = {"debug", "info", "warning", "error", "exception", "critical", "warn"}


def message_only(mutant: Mutant, diff: str) -> bool:
    """Whether every line the mutant changes lies inside a raise statement or a logging or
    warning call: it changes what an exception or a log record says, not whether it is raised
    or written, and no result."""
    minus, plus = _changed_lines(diff, "-"), _changed_lines(diff, "+")
    if not minus or len(minus) != len(plus):
        return False
    node = _function_node(mutant)
    if node is None:
        return False
    source = (ast.get_source_segment(_source(mutant.file), node) or "").splitlines()
    for changed in minus:
        lines = [node.lineno + i for i, ln in enumerate(source) if ln.strip() == changed.strip()]
        if not lines or not all(_in_message(node, line) for line in lines):
            return False
    return True


def _in_message(func: ast.AST, line: int) -> bool:
    """Whether `line` of `func` lies in a raise statement or a logging/warning call."""
    for n in ast.walk(func):
        if not (getattr(n, "lineno", 0) <= line <= (getattr(n, "end_lineno", 0) or 0)):
            continue
        if isinstance(n, ast.Raise):
            return True
        if (
            isinstance(n, ast.Call)
            and isinstance(n.func, ast.Attribute)
            and n.func.attr in _LOG_CALLS
            and not isinstance(n.func.value, ast.Call)
        ):
            return True
    return False


def _source(file: str) -> str:
    return (ROOT / "src" / "transfertwin" / file).read_text()


def _function_node(mutant: Mutant) -> ast.FunctionDef | None:
    """The original function or method a mutant belongs to, from its mangled name
    ('x_name' for a function, 'xǁClassǁmethod' for a method)."""
    tail = mutant.function.rpartition(".")[2]
    parts = tail.split("ǁ")
    cls, func = (parts[1], parts[2]) if len(parts) == 3 else (None, tail[len("x_") :])
    tree = ast.parse(_source(mutant.file))
    scope = tree.body
    if cls is not None:
        found = [n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == cls]
        scope = found[0].body if found else []
    defs = (ast.FunctionDef, ast.AsyncFunctionDef)
    return next((n for n in scope if isinstance(n, defs) and n.name == func), None)


def classify(mutants: list[Mutant], listed: Listed) -> list[Mutant]:
    """Each mutant with the kind the score counts it as: a killed one stays killed; one that
    is not becomes 'equivalent' (listed), 'outside' (its function is listed as outside the
    scope) or 'message' (`message_only`), or keeps its status (survived, no tests, ...)."""
    out = []
    for m in mutants:
        kind = m.status
        if not m.killed:
            if m.name in listed.equivalent:
                kind = "equivalent"
            elif m.function in listed.outside:
                kind = "outside"
            elif m.status in ("survived", "no tests") and message_only(m, diff_of(m.name)):
                kind = "message"
        out.append(Mutant(m.name, m.file, kind))
    return out


def module_of(file: str) -> str:
    return next((m for m in MODULES if file.startswith(m)), file)


def score(classified: list[Mutant]) -> list[ModuleScore]:
    """Per-module counts of classified mutants."""
    scores = {m: ModuleScore(m) for m in MODULES}
    for mut in classified:
        module = module_of(mut.file)
        scores.setdefault(module, ModuleScore(module)).counts[mut.status] += 1
    return list(scores.values())


def report(mutants: list[Mutant], listed: Listed, diffs: bool, min_score: float) -> dict:
    """Print the per-module table, the survivors and stale list entries; the JSON record."""
    classified = classify(mutants, listed)
    scores = score(classified)
    print(f"{'module':<31}{'mutants':>8}" + "".join(f"{c:>12}" for c in COLUMNS) + "    score")
    for s in scores:
        cells = "".join(f"{s.counts[k]:>12}" for k in COLUMNS)
        print(f"{s.module:<31}{sum(s.counts.values()):>8}{cells}{100 * s.score:>8.1f}%")
    survivors = [m for m in classified if not m.killed and m.status not in EXCLUDED]
    print(f"\n{len(survivors)} surviving mutants (status, name):")
    for m in survivors:
        print(f"  {m.status:<12} {m.name}")
        if diffs:
            print("    " + "\n    ".join(diff_of(m.name).splitlines()[2:]))
    stale = _stale_entries(mutants, listed)
    for name, why in stale.items():
        print(f"listed {name}: {why}")
    failing = [s.module for s in scores if s.score < min_score / 100]
    if failing:
        print(f"\nbelow {min_score:g} %: {', '.join(failing)}")
    return {
        "score": "(killed + timeout) / (mutants - equivalent - message - outside - skipped)",
        "modules": {s.module: {**dict(s.counts), "score": round(s.score, 4)} for s in scores},
        "survivors": [{"mutant": m.name, "status": m.status} for m in survivors],
        "stale_list_entries": stale,
        "below_min_score": failing,
    }


def _stale_entries(mutants: list[Mutant], listed: Listed) -> dict[str, str]:
    """Equivalent entries whose mutant is gone, was killed, or now changes another line than
    recorded; out-of-scope functions that have no mutants any more."""
    by_name = {m.name: m for m in mutants}
    stale = {}
    for name, entry in listed.equivalent.items():
        if name not in by_name:
            stale[name] = "no such mutant any more (renumbered? list it again)"
        elif by_name[name].killed:
            stale[name] = "killed now: not equivalent, remove the entry"
        elif (line := mutated_line(diff_of(name))) != entry.get("line", "").strip():
            stale[name] = f"changes the line to '{line}' now, not to the listed one"
    functions = {m.function for m in mutants}
    for function in listed.outside:
        if function not in functions:
            stale[function] = "no mutants of this function any more"
    return stale


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2, help="mutmut children (default 2)")
    keep_help = "reuse mutants/ and its results (mutmut reruns the changed functions)"
    parser.add_argument("--keep", action="store_true", help=keep_help)
    parser.add_argument("--report-only", action="store_true", help="report the last run only")
    parser.add_argument("--rerun-survivors", action="store_true",
                        help="run the last run's surviving mutants again, then report")  # fmt: skip
    parser.add_argument("--diffs", action="store_true", help="print each survivor's diff")
    parser.add_argument("--min-score", type=float, default=95.0, help="percent, per module")
    parser.add_argument("--out", type=Path, help="write the report as JSON here")
    args = parser.parse_args()
    os.chdir(ROOT)  # mutmut reads pyproject.toml and mutants/ from the working directory
    wall = None
    if args.rerun_survivors:
        wall = rerun_survivors(load_listed(), args.workers, MUTANTS / "run.log")
    elif not args.report_only:
        wall = run_mutmut(args.workers, args.keep, MUTANTS / "run.log")
    if not MUTANTS.exists():
        sys.exit("no mutants/ folder: run without --report-only first")
    record = report(read_mutants(), load_listed(), args.diffs, args.min_score)
    if args.out:
        record |= {
            "date": datetime.now(UTC).isoformat(timespec="seconds"),
            "wall_s": None if wall is None else round(wall),
            "workers": args.workers,
            "commit": _git_head(),
        }
        args.out.write_text(json.dumps(record, indent=1) + "\n")
    return 1 if record["below_min_score"] else 0


def _git_head() -> str:
    cmd = ["git", "rev-parse", "--short", "HEAD"]
    return subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True).stdout.strip()


if __name__ == "__main__":
    raise SystemExit(main())
