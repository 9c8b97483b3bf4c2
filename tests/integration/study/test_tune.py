"""`calibrate tune`: a joint, resumable TPE study over scene settings and proxy depths."""

from __future__ import annotations

import csv
import json

import optuna
import pytest

from transfertwin import InputError
from transfertwin.cli import main
from transfertwin.data import calibration_csv_path
from transfertwin.objects import builtin_features, load_builtin, load_object, read_proxy
from transfertwin.sim import SceneConfig
from transfertwin.store import read_results
from transfertwin.study import load_profile
from transfertwin.study.calibration import (
    parse_space,
    scene_with,
    study_name_for,
    study_settings,
    tune_tpe,
)

SPACE = "mu=0.3:0.8,gap_mm=8:16,object.o1.front_depth_mm=0:30,object.o1.com_shift_mm=-15:15"


def _tune(out, *extra: str) -> int:
    return main(["calibrate", "tune", "--runs", "1", "--limit", "3", "--workers", "1",
                 "--space", SPACE, "--out", str(out), *extra])  # fmt: skip


def _trials(out) -> list[dict[str, str]]:
    with (out / "trials.csv").open() as fh:
        return list(csv.DictReader(fh))


def _study(out) -> optuna.Study:
    (summary,) = optuna.get_all_study_summaries(f"sqlite:///{out / 'tune.sqlite'}")
    return optuna.load_study(study_name=summary.study_name, storage=f"sqlite:///{out}/tune.sqlite")


def test_resume_adds_only_the_missing_trials(tmp_path):
    a = tmp_path / "a"
    assert _tune(a, "--trials", "2") == 0
    first = _trials(a)
    assert [t["label"] for t in first] == ["T0", "T1"]
    assert _tune(a, "--trials", "4") == 0
    resumed = _trials(a)
    assert [t["label"] for t in resumed] == ["T0", "T1", "T2", "T3"]
    assert resumed[:2] == first
    trials = _study(a).get_trials()
    assert [t.state for t in trials] == [optuna.trial.TrialState.COMPLETE] * 4
    assert _tune(a, "--trials", "3") == 0  # nothing missing: no trial is added
    assert len(_study(a).get_trials()) == 4


@pytest.mark.slow
def test_a_resumed_run_matches_an_uninterrupted_one(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    assert _tune(a, "--trials", "2") == 0
    assert _tune(a, "--trials", "4") == 0
    assert _tune(b, "--trials", "4") == 0
    assert _trials(b) == _trials(a)
    best = json.loads((a / "best.json").read_text())
    assert best == json.loads((b / "best.json").read_text()) | {
        k: best[k] for k in ("study", "profile", "object_map")
    }


def test_the_same_seed_gives_the_same_trials_bit_for_bit(tmp_path):
    rows = read_results(calibration_csv_path())[:2]  # one real success, one failure
    space = parse_space(SPACE, SceneConfig())

    def run(seed: int, where: str) -> list[str]:
        study = tune_tpe(rows, space, base=SceneConfig(), n_trials=2, runs=1, seed=seed,
                         workers=1, work_dir=tmp_path / where)  # fmt: skip
        return [json.dumps([t.params, t.objective, t.metrics, t.scores]) for t in study.trials]

    first = run(7, "a")
    assert len(first) == 2
    assert run(7, "b") == first
    assert run(8, "c") != first


def test_an_interrupted_or_stale_trial_is_not_counted_and_is_proposed_again(tmp_path):
    rows = read_results(calibration_csv_path())[:2]
    space = parse_space("mu=0.3:0.8,object.o1.front_depth_mm=0:30", SceneConfig())
    storage = f"sqlite:///{tmp_path / 't.sqlite'}"
    calib = {"runs": 1, "seed": 3, "workers": 1}
    seen = []

    def interrupt(trial) -> None:
        seen.append(trial.params)
        if trial.number == 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        tune_tpe(rows, space, base=SceneConfig(), n_trials=2, storage=storage,
                 work_dir=tmp_path / "w", on_trial=interrupt, **calib)  # fmt: skip
    (summary,) = optuna.get_all_study_summaries(storage)
    left = optuna.load_study(study_name=summary.study_name, storage=storage)
    left.ask()  # a trial left 'running' by a killed process
    result = tune_tpe(rows, space, base=SceneConfig(), n_trials=2, storage=storage,
                      work_dir=tmp_path / "w", **calib)  # fmt: skip
    assert (result.added, result.stale) == (1, 1)
    assert [t.number for t in result.trials] == [0, 3]
    assert [t.params for t in result.trials] == seen  # the failed trial is proposed again
    states = [t.state.name for t in left.get_trials()]
    assert states == ["COMPLETE", "FAIL", "FAIL", "COMPLETE"]
    assert not list((tmp_path / "w").glob("*.proxy.json"))  # per-trial proxies are removed


def test_the_study_name_follows_the_settings_and_a_reused_name_is_checked(tmp_path, capsys):
    rows = read_results(calibration_csv_path())[:3]
    space = parse_space(SPACE, SceneConfig())
    kw = {"base": SceneConfig(), "metric": "f05", "runs": 1, "penalty": 0.02,
          "object_map": {"o1": "o1"}}  # fmt: skip
    name = study_name_for(study_settings(rows, space, seed=0, **kw))
    assert name == study_name_for(study_settings(rows, space, seed=0, **kw))
    assert name != study_name_for(study_settings(rows, space, seed=1, **kw))
    assert name != study_name_for(study_settings(rows[:2], space, seed=0, **kw))
    assert name != study_name_for(study_settings(rows, space, seed=0, **kw | {"metric": "brier"}))
    out = tmp_path / "t"
    assert _tune(out, "--trials", "1") == 0
    study = _study(out).study_name
    capsys.readouterr()
    assert _tune(out, "--trials", "1", "--runs", "2", "--study-name", study) == 2
    assert "other settings (runs)" in capsys.readouterr().err
    with pytest.raises(InputError, match="other settings"):
        tune_tpe(rows, space, base=SceneConfig(), n_trials=1, storage=f"sqlite:///{out}/tune.sqlite",
                 study_name=study, runs=1, seed=5, workers=1)  # fmt: skip


def test_best_trial_is_saved_as_a_profile_with_proxies_that_other_commands_accept(tmp_path):
    out = tmp_path / "t"
    assert _tune(out, "--trials", "2", "--metric", "brier", "--name", "joint") == 0
    best = json.loads((out / "best.json").read_text())
    rows = _trials(out)
    objective = [float(r["objective"]) for r in rows]
    chosen = next(r for r in rows if r["label"] == best["trial"])
    assert float(chosen["objective"]) == pytest.approx(min(objective))  # brier: lower is better
    assert float(chosen["objective"]) == pytest.approx(
        float(chosen["brier"]) + float(chosen["penalty"]), abs=2e-6)  # fmt: skip
    name, scene = load_profile(out / "profile.toml")
    assert name == "joint"
    assert scene == scene_with(SceneConfig(), best["params"])
    proxy = out / "objects" / "o1.proxy.json"
    assert best["object_map"] == f"o1={proxy}"
    depth = best["params"]["object.o1.front_depth_mm"]
    assert read_proxy(proxy).protrusions[0].depth_m == pytest.approx(depth / 1000)
    back = [p.depth_m for p in builtin_features("o1") if p.face == "back"]  # kept: not tuned
    assert [p.depth_m for p in read_proxy(proxy).protrusions[1:]] == back
    shift = best["params"]["object.o1.com_shift_mm"]
    assert read_proxy(proxy).com_shift_m == pytest.approx(shift / 1000)
    assert len(load_object(str(proxy)).hulls) == len(load_builtin("o1", features=False).hulls) + (
        depth > 0) + sum(d > 0 for d in back)  # fmt: skip
    assert not (out / "trials").exists()
    t = ["transfer", "--object", str(proxy), "--face", "front", "--conveyor", "both",
         "--theta", "0", "--profile", str(out / "profile.toml"), "--json"]  # fmt: skip
    assert main(t) == 0
    run = ["calibrate", "run", "--runs", "1", "--limit", "1", "--workers", "1", "--profile",
           str(out / "profile.toml"), "--object-map", best["object_map"], "--out",
           str(tmp_path / "again")]  # fmt: skip
    assert main(run) == 0
    study = ["study", "run", "--db", str(tmp_path / "s.sqlite"), "--objects", str(proxy),
             "--theta-step", "180", "--runs", "1", "--max-experiments", "1", "--workers", "1",
             "--profile", str(out / "profile.toml")]  # fmt: skip
    assert main(study) == 0


def test_lhs_searches_the_same_joint_space(tmp_path):
    out = tmp_path / "lhs"
    rc = main(["calibrate", "tune", "--method", "lhs", "--trials", "1", "--runs", "1",
               "--limit", "2", "--workers", "1", "--space",
               "physics.solref[0]=0.002:0.02:log,object.o1.front_depth_mm=0:30",
               "--out", str(out)])  # fmt: skip
    assert rc == 0
    rows = _trials(out)
    assert [r["label"] for r in rows] == ["I0.0", "I1.0"]
    for r in rows:
        assert 0.002 <= float(r["physics.solref[0]"]) <= 0.02
    _, scene = load_profile(out / "profile.toml")
    assert 0.002 <= scene.physics.solref[0] <= 0.02
    assert not (out / "tune.sqlite").exists()
