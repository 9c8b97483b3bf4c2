"""`rehearse --plant-kind` (issue 29): the plant kind is a checked setting, recorded only
when it is not today's in-class plant."""

from __future__ import annotations

import pytest

from transfertwin._errors import InputError
from transfertwin.cli import main
from transfertwin.rehearsal import RehearsalConfig
from transfertwin.rehearsal._config import config_record


def test_plant_kind_is_checked_and_recorded_only_when_it_is_the_mismatch() -> None:
    base = {"plant_seed": 1, "objects": ("o3",), "calibration_experiments": 20}
    assert "plant_kind" not in config_record(RehearsalConfig(**base))
    cfg = RehearsalConfig(**base, plant_kind="mismatch")
    assert config_record(cfg)["plant_kind"] == "mismatch"
    with pytest.raises(InputError, match="--plant-kind"):
        RehearsalConfig(**base, plant_kind="drake")


def test_mismatch_parts_switched_off_are_checked_and_recorded() -> None:
    base = {"plant_seed": 1, "objects": ("o3",), "calibration_experiments": 20}
    cfg = RehearsalConfig(**base, plant_kind="mismatch", mismatch_off=["sag"])
    assert cfg.mismatch_off == ("sag",) and config_record(cfg)["mismatch_off"] == ("sag",)
    assert "mismatch_off" not in config_record(RehearsalConfig(**base, plant_kind="mismatch"))
    with pytest.raises(InputError, match="--mismatch-off"):
        RehearsalConfig(**base, plant_kind="mismatch", mismatch_off=("gravity",))
    with pytest.raises(InputError, match="--mismatch-off"):  # the in-class plant has no parts
        RehearsalConfig(**base, mismatch_off=("sag",))


def test_rehearse_refuses_an_unknown_plant_kind(tmp_path, monkeypatch, capfd) -> None:
    monkeypatch.chdir(tmp_path)
    code = main(["rehearse", "--plant-seed", "1", "--plant-kind", "sapien", "--objects", "o3",
                 "--calibration-experiments", "20", "--out", "r"])  # fmt: skip
    err = capfd.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--plant-kind" in err[0]
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("kind,off", [("mismatch", "sag,gravity"), ("in-class", "sag")])
def test_rehearse_passes_mismatch_off_on_and_refuses_what_it_cannot_switch_off(
    tmp_path, monkeypatch, capfd, kind, off
) -> None:
    monkeypatch.chdir(tmp_path)
    code = main(["rehearse", "--plant-seed", "1", "--plant-kind", kind, "--mismatch-off", off,
                 "--objects", "o3", "--calibration-experiments", "20", "--out", "r"])  # fmt: skip
    err = capfd.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--mismatch-off" in err[0]
    assert list(tmp_path.iterdir()) == []


def test_majority_scores_threshold_each_row_and_pair_before_with_after() -> None:
    from transfertwin.rehearsal import majority_scores

    y = [1, 1, 0, 0, 1, 0, 1, 1]
    perfect = [float(v) for v in y]
    coin = [0.5] * len(y)  # every row 'success' at the 0.5 threshold
    s = majority_scores(coin, perfect, y, n_resamples=200)
    assert s["f05_after"] == 1.0 and s["brier_after"] == 0.0
    base = 5 / 8
    assert s["f05_before"] == pytest.approx(1.25 * base / (0.25 * base + 1))
    assert s["brier_before"] == pytest.approx(0.25)
    assert s["f05_delta"] > 0 and s["brier_delta"] == pytest.approx(-0.25)
    assert s["brier_delta_ci"][1] < 0  # the same rows for both: never worse
    assert (s["threshold_before"], s["threshold_after"]) == (0.5, 0.5)
    # a threshold above the coin's P: every row 'failure' before (F0.5 0)
    t = majority_scores(coin, perfect, y, n_resamples=200, thresholds=(0.75, 0.5),
                        threshold_source="chosen on the training rows")  # fmt: skip
    assert t["f05_before"] == 0.0 and t["f05_after"] == 1.0
    assert t["threshold_source"] == "chosen on the training rows"


def test_the_training_threshold_maximises_f05_on_the_training_rows() -> None:
    from transfertwin.rehearsal import training_threshold

    # R = 4: shares 0, 0.25, ..., 1; the failures sit at 0.25 and 0.5, successes at 0.75+
    p = [0.0, 0.25, 0.5, 0.5, 0.75, 1.0, 1.0, 0.75]
    y = [0, 0, 0, 0, 1, 1, 1, 1]
    assert training_threshold(p, y) == 0.75  # 0.5 would let two failures through
    assert training_threshold([1.0, 1.0], [1, 0]) == 1.0  # constant: 'success'
    assert training_threshold([], []) == 0.5
    with pytest.raises(ValueError, match="training_threshold"):
        training_threshold([0.5], [1, 0])


def test_the_record_leaves_out_the_plant_seed() -> None:
    cfg = RehearsalConfig(plant_seed=918273, objects=("o3",), calibration_experiments=20)
    record = config_record(cfg)
    assert "plant_seed" not in record and 918273 not in record.values()
    assert record["seed"] == 0  # the twin's own master seed stays


def test_the_object_prior_is_checked_and_recorded_only_when_it_is_not_the_plain_body() -> None:
    base = {"plant_seed": 1, "objects": ("o3",), "calibration_experiments": 20}
    record = config_record(RehearsalConfig(**base))
    assert "object_prior" not in record and "min_face_rows" not in record
    cfg = RehearsalConfig(**base, object_prior="shipped", min_face_rows=3)
    assert (config_record(cfg)["object_prior"], config_record(cfg)["min_face_rows"]) == (
        "shipped", 3)  # fmt: skip
    with pytest.raises(InputError, match="--object-prior"):
        RehearsalConfig(**base, object_prior="scan")
    with pytest.raises(InputError, match="--min-face-rows"):
        RehearsalConfig(**base, min_face_rows=0)
