"""The figures `benchmarks/operations.py` prints from its arms' summaries: per seed and pooled
success shares, the differences between arms with their Newcombe intervals, the issue's
targets with a verdict, and the pooling of several runs' JSON outputs (one run per seed
or per arm, as long runs are split) into one report.

A difference, and a target, is pooled over the seeds on which *both* arms ran: arms run on
different plants are not compared. In cold start each difference is given for both
metrics, each object's first order and its first three; the targets are read on the
first order.
"""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["DIFFERENCES", "counts", "load_runs", "pair", "pooled", "report", "verdicts"]

#: The differences reported: (arm, baseline). The twin alone against learning alone and twin +
#: learning against the twin alone say what each source is worth without the other.
DIFFERENCES = (
    ("learning-alone", "nearest-idle"), ("twin-only", "nearest-idle"),
    ("predictive", "nearest-idle"), ("predictive", "learning-alone"),
    ("twin-only", "learning-alone"), ("predictive", "twin-only"),
    ("calibrated-only", "nearest-idle"), ("calibrated-only", "twin-only"),
    ("calibrated", "learning-alone"), ("calibrated", "predictive"),
)  # fmt: skip

#: The metrics of a regime: (key in an arm's summary or None for every order, words).
METRICS = {
    "steady": ((None, "every order"),),
    "cold-start": (("first_1", "each object's first order"),
                   ("first_3", "each object's first three orders")),
}  # fmt: skip


def counts(arm: dict, metric: str | None) -> tuple[int, int]:
    """The arm's (delivered, n) over every order (`metric` None) or over each object's
    first order(s) (`metric` 'first_1' or 'first_3')."""
    return (arm["delivered"], arm["n"]) if metric is None else tuple(arm[metric])


def pooled(per_seed: dict[int, dict[str, dict]], arm: str, metric: str | None,
           seeds: list[int]) -> tuple[int, int]:  # fmt: skip
    """`arm`'s (delivered, n) summed over those of `seeds` on which it ran."""
    got = [counts(per_seed[s][arm], metric) for s in seeds if arm in per_seed[s]]
    return sum(k for k, _ in got), sum(n for _, n in got)


def pair(per_seed: dict[int, dict[str, dict]], arm: str, base: str,
         metric: str | None) -> tuple[tuple[int, int], tuple[int, int], list[int]]:  # fmt: skip
    """`arm`'s and `base`'s counts pooled over the seeds on which both ran, and those seeds."""
    seeds = [s for s in sorted(per_seed) if arm in per_seed[s] and base in per_seed[s]]
    return pooled(per_seed, arm, metric, seeds), pooled(per_seed, base, metric, seeds), seeds


#: The issue's targets: (words, arm, baseline, margin, kind, regime, plant kind or None).
TARGETS = (
    ("cold start, mismatch: calibrated twin + learning beats learning alone by >= 0.10",
     "calibrated", "learning-alone", 0.10, "better-by", "cold-start", "mismatch"),
    ("cold start, mismatch: the calibrated twin alone beats nearest-idle",
     "calibrated-only", "nearest-idle", 0.0, "better-by", "cold-start", "mismatch"),
    ("steady: twin + learning not worse than learning alone (margin 0.05)",
     "predictive", "learning-alone", 0.05, "not-worse", "steady", None),
    ("steady: calibrated twin + learning not worse than learning alone (margin 0.05)",
     "calibrated", "learning-alone", 0.05, "not-worse", "steady", None),
)  # fmt: skip


def verdicts(per_seed: dict[int, dict[str, dict]], regime: str, kind: str) -> list[dict]:
    """The issue's targets, each met / missed / undecided by its Newcombe interval, pooled
    over the seeds on which both of its arms ran (cold start: on each object's first
    order)."""
    from transfertwin.study.validation import newcombe_difference

    metric = METRICS[regime][0][0]
    out = []
    for what, arm, base, margin, how, regime_, kind_ in TARGETS:
        if regime_ != regime or (kind_ is not None and kind_ != kind):
            continue
        a, b, seeds = pair(per_seed, arm, base, metric)
        if not seeds or not a[1] or not b[1]:
            continue
        d = newcombe_difference(*a, *b)
        if how == "better-by":  # better by at least `margin`, interval above 0
            ok, bad = d.estimate >= margin and d.low > 0, d.high < margin
        else:  # not worse by more than `margin`
            ok, bad = d.low > -margin, d.high < -margin
        out.append({"target": what, "difference": d.estimate, "ci95": [d.low, d.high],
                    "seeds": seeds, "verdict": "met" if ok else "missed" if bad else "undecided"})
    return out


def report(per_seed: dict[int, dict[str, dict]], regime: str, kind: str,
           title: str) -> dict:  # fmt: skip
    """Print the tables of `per_seed` ({seed: {arm: summary}}) and return the figures."""
    from transfertwin.study.fullstate import clopper_pearson
    from transfertwin.study.validation import newcombe_difference

    seeds = sorted(per_seed)
    names = list(dict.fromkeys(a for s in seeds for a in per_seed[s]))
    out: dict = {"pooled": {}, "differences": {}}
    for metric, words in METRICS[regime]:
        suffix = "" if metric in (None, "first_1") else f" ({metric})"
        print(f"\n{title}; success share over {words}")
        print(f"{'arm':<18}" + "".join(f"{'seed ' + str(s):>18}" for s in seeds)
              + f"{'pooled':>34}")  # fmt: skip
        for name in names:
            cells = []
            for s in seeds:
                k, n = counts(per_seed[s][name], metric) if name in per_seed[s] else (0, 0)
                cells.append(f"{k}/{n} = {k / n:.3f}" if n else "-")
            k_all, n_all = pooled(per_seed, name, metric, seeds)
            ci = clopper_pearson(k_all, n_all) if n_all else None
            text = f"{k_all}/{n_all} = {k_all / n_all:.3f} [{ci.low:.3f}, {ci.high:.3f}]" if ci \
                else "-"  # fmt: skip
            out["pooled"][name + suffix] = [k_all, n_all]
            print(f"{name:<18}" + "".join(f"{c:>18}" for c in cells) + f"{text:>34}")
        for arm, base in DIFFERENCES:
            a, b, common = pair(per_seed, arm, base, metric)
            if not common or not a[1] or not b[1]:
                continue
            d = newcombe_difference(*a, *b)
            verdict = "better" if d.low > 0 else "worse" if d.high < 0 else "undecided"
            out["differences"][f"{arm} - {base}{suffix}"] = {
                "share": d.estimate, "ci95": [d.low, d.high], "seeds": common,
                "verdict": verdict}  # fmt: skip
            print(f"{arm} - {base}: {d.estimate:+.3f} [{d.low:+.3f}, {d.high:+.3f}] "
                  f"(Newcombe, seeds {','.join(map(str, common))}: {verdict})")  # fmt: skip
    out["targets"] = verdicts(per_seed, regime, kind)
    for t in out["targets"]:
        lo, hi = t["ci95"]
        print(f"target: {t['target']}: {t['difference']:+.3f} [{lo:+.3f}, {hi:+.3f}] "
              f"(seeds {','.join(map(str, t['seeds']))}): {t['verdict']}")  # fmt: skip
    for s in seeds:
        for name, r in per_seed[s].items():
            tw = {leg: f"{v['wrong']}/{v['predicted']}" for leg, v in r["twin_wrong"].items()}
            print(f"seed {s} {name}: ops/floor-hour {r['ops_per_floor_hour']:.1f} "
                  f"{[round(v, 1) for v in r['ops_ci95']]} (campaign "
                  f"{r['campaign_floor_s']:.0f} s); faults {r['faults']}; twin wrong per leg "
                  f"{tw}; failures {r['failed_by_reason'] or 'none'}")  # fmt: skip
    return out


def load_runs(paths: list[Path]) -> tuple[str, str, list[str], dict[int, dict[str, dict]]]:
    """(regime, plant kind, mismatch parts off, {seed: {arm: summary}}) of several
    `operations.py` outputs. Raises ValueError when they are not one experiment: another
    regime, plant kind, ablation, floor, order count or order seed, or an arm of a seed
    found twice."""
    per_seed: dict[int, dict[str, dict]] = {}
    first: dict | None = None
    for path in paths:
        try:
            doc = json.loads(Path(path).read_text())
        except (OSError, json.JSONDecodeError) as exc:
            raise ValueError(f"{path}: not an operations.py output ({exc})") from None
        if not isinstance(doc, dict) or "per_seed" not in doc:
            raise ValueError(f"{path}: not an operations.py output (no per_seed)")
        first = first or doc
        for key in ("regime", "plant_kind", "mismatch_off", "floor", "orders", "seed"):
            if doc.get(key) != first.get(key):
                raise ValueError(f"{path}: {key} {doc.get(key)!r} differs from "
                                 f"{paths[0]}'s {first.get(key)!r}: not one experiment")
        for seed, arms in doc["per_seed"].items():
            mine = per_seed.setdefault(int(seed), {})
            for name, summary in arms.items():
                if name in mine:
                    raise ValueError(f"{path}: seed {seed} arm {name} is in two runs")
                mine[name] = summary
    if first is None:
        raise ValueError("no run given")
    return first["regime"], first["plant_kind"], list(first.get("mismatch_off") or []), per_seed
