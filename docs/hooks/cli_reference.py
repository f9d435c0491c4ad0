"""MkDocs hook: the CLI reference page, generated from ``bearchair``'s own argparse parser.

A page holding the line ``<!-- cli-reference -->`` gets, in its place, the ``--help`` of
``bearchair`` and of every subcommand, so the reference cannot lag the code.
"""

from __future__ import annotations

import argparse
import os

MARKER = "<!-- cli-reference -->"
HELP_WIDTH_COLUMNS = "96"  # argparse wraps help to $COLUMNS: fixed, so the page is reproducible


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:  # argparse keeps subparsers only here
        if isinstance(action, argparse._SubParsersAction):
            return dict(sorted(action.choices.items()))
    return {}


def cli_reference() -> str:
    """Markdown: ``bearchair --help``, then one section per subcommand with its help."""
    from bearchair.executive.cli import build_parser

    previous = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = HELP_WIDTH_COLUMNS
    try:
        parser = build_parser()
        blocks = ["### bearchair", "", "```text", parser.format_help().rstrip(), "```", ""]
        for name, sub in _subcommands(parser).items():
            blocks += [
                f"### bearchair {name}",
                "",
                "```text",
                sub.format_help().rstrip(),
                "```",
                "",
            ]
    finally:
        if previous is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = previous
    return "\n".join(blocks)


def on_page_markdown(markdown: str, page, config, files) -> str:
    if MARKER not in markdown:
        return markdown
    return markdown.replace(MARKER, cli_reference())
