"""What a person reads from the CLI is in words: the tool in a sentence, outcomes as
'delivered' or 'failed … after 4.88 s' (the machine form under --json), options with help."""

from __future__ import annotations

import argparse

import pytest

from transfertwin.cli import build_parser, main

T = ["transfer", "--object", "o1", "--face", "back", "--conveyor", "left", "--theta", "0"]


def _help(*argv: str) -> str:
    with pytest.raises(SystemExit):
        build_parser().parse_args([*argv, "--help"])
    return ""


def test_the_top_level_help_is_a_sentence_about_the_tool(capsys) -> None:
    _help()
    text = " ".join(capsys.readouterr().out.split())
    assert "Command line interface" not in text
    assert "transfertwin simulates an object crossing the gap" in text


def test_dock_and_docking_say_which_is_which(capsys) -> None:
    _help()
    text = " ".join(capsys.readouterr().out.split())
    assert "docking errors drawn from a model fitted to measured ones" in text
    assert "docking errors that emerge from simulated navigation" in text


def _helps(parser: argparse.ArgumentParser, path: str = "transfertwin"):
    """(command path, help text) of every command and option under `parser`."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for choice in action._choices_actions:
                yield f"{path} {choice.dest}", choice.help or ""
            for name, sub in action.choices.items():
                yield from _helps(sub, f"{path} {name}")
        elif action.help:
            yield f"{path} {'/'.join(action.option_strings) or action.dest}", action.help


def test_help_says_the_source_notation_in_words(capsys) -> None:
    """A help text that cites E^V or E^P says 'virtual'/'physical' beside it, and the
    top-level help is the legend (plain text: help has no math)."""
    _help()
    legend = " ".join(capsys.readouterr().out.split())
    assert "E^V is a virtual experiment" in legend and "E^P a physical one" in legend
    words = {"E^V": "virtual", "E^P": "physical"}
    bare = [f"{where}: {text}" for where, text in _helps(build_parser())
            for symbol, word in words.items() if symbol in text and word not in text]  # fmt: skip
    assert not bare, "\n".join(bare)


def test_every_demo_option_has_help(capsys) -> None:
    _help("demo")
    text = " ".join(capsys.readouterr().out.split())
    assert "--object OBJECT built-in core id" in text
    assert "must divide 360" in text


def test_transfer_prints_its_outcome_in_words(capsys) -> None:
    assert main(T) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0].startswith("o1, back face, left conveyor, θ = 0°, seed 0")
    assert "failed on the way there: caught in the gap after 4.88 s" in out
    for code_word in ("status", "y1", "success", "None"):
        assert code_word not in out



def test_real_angles_move_to_the_nearest_state_of_a_study_grid(tmp_path, capsys) -> None:
    import csv

    from transfertwin.cli._data import snap_theta
    from transfertwin.ots import state_index

    assert snap_theta(-11, [-30, 30, 60]) == -30 and snap_theta(170, [0, 180]) == 180
    assert snap_theta(-170, [-150, 150]) == -150 and snap_theta(0, [-30, 30]) == -30
    out = tmp_path / "real.csv"
    assert main(["data", "calibration", "--out", str(out), "--theta-step", "30"]) == 0
    assert "moved to the nearest state on a 30° grid" in capsys.readouterr().out
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 191 and all(int(r["theta_deg"]) % 30 == 0 for r in rows)
    for r in rows:  # every moved row is an experiment state (Eq. 6.7)
        state_index(r["face"], r["conveyor"], int(r["theta_deg"]))
    assert main(["data", "calibration", "--out", str(out), "--theta-step", "7"]) == 2


def test_cps_status_sorts_ids_by_their_numbers() -> None:
    from transfertwin.cli._cps_floor import natural_key

    ids = ["o10", "o2", "TM_10", "o1", "TM_2", "KG"]
    assert sorted(ids, key=natural_key) == ["KG", "TM_2", "TM_10", "o1", "o2", "o10"]


def test_a_calibration_rows_outcomes_read_as_words() -> None:
    from transfertwin.cli._replay import _word

    assert [_word(1), _word(0), _word(None)] == ["delivered", "failed", "not known"]
