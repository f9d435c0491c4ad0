"""Every flag of every subcommand has help text, and ``--help`` shows the defaults that
matter; ``-v`` and ``--log-level`` work before and after the subcommand."""

from __future__ import annotations

import argparse
import logging

import pytest

from bearchair.executive import cli


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    actions = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    assert len(actions) == 1
    return dict(actions[0].choices)


def _arguments(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    return [
        a
        for a in parser._actions
        if not isinstance(a, argparse._HelpAction | argparse._SubParsersAction)
    ]


def test_every_argument_of_every_subcommand_has_help():
    parser = cli.build_parser()
    missing = [
        f"{name} {'/'.join(action.option_strings) or action.dest}"
        for name, subparser in [("bearchair", parser), *_subcommands(parser).items()]
        for action in _arguments(subparser)
        if not (action.help and action.help.strip()) or action.help == argparse.SUPPRESS
    ]
    assert not missing, f"arguments without help text: {missing}"


def test_help_shows_each_default_worth_saying():
    parser = cli.build_parser()
    silent = []
    for name, subparser in _subcommands(parser).items():
        text = " ".join(subparser.format_help().split())
        for action in _arguments(subparser):
            default = action.default
            if not action.option_strings or default is None or default is False:
                continue
            if default == argparse.SUPPRESS:
                continue
            if "default" not in (action.help or "") and f"(default: {action.default})" not in text:
                silent.append(f"{name} {action.option_strings[0]}")
    assert not silent, f"defaults not shown in --help: {silent}"
    run_help = " ".join(_subcommands(parser)["run"].format_help().split())
    # run: left off, a flag keeps the configuration's value, itself defaulted.
    assert "(default: accessible, or --config's)" in run_help
    assert "(default: obeys, or --config's)" in run_help


@pytest.mark.parametrize(
    "argv",
    [["-v", "tree", "--format", "ascii"], ["tree", "--format", "ascii", "-v"],
     ["tree", "-v", "--format", "ascii"], ["--log-level", "debug", "tree", "--format", "ascii"],
     ["tree", "--format", "ascii", "--log-level", "debug"]],
)  # fmt: skip
def test_verbosity_is_accepted_before_or_after_the_subcommand(argv):
    args = cli.build_parser().parse_args(argv)
    assert args.verbose or args.log_level == "debug"


def test_log_level_defaults_to_warnings_and_is_applied(monkeypatch, capsys):
    args = cli.build_parser().parse_args(["tree"])
    assert args.verbose is False and args.log_level == "warning"
    levels = []
    monkeypatch.setattr(logging, "basicConfig", lambda **kwargs: levels.append(kwargs["level"]))
    assert cli.main(["tree", "--format", "ascii", "--log-level", "info"]) == 0
    assert cli.main(["tree", "--format", "ascii", "-v"]) == 0
    assert levels == [logging.INFO, logging.DEBUG]
    assert cli.main(["tree", "--log-level", "loud"]) == 2
    assert "invalid choice" in capsys.readouterr().err
