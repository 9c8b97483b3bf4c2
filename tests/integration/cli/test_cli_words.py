"""What a person reads from the CLI is in words: the tool in a sentence, outcomes as
'delivered' or 'failed … after 4.88 s' (the machine form under --json), options with help."""

from __future__ import annotations

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
