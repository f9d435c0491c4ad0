"""Calling the CLI in this process."""

from __future__ import annotations

from bearchair.executive import cli


def refused(argv: list[str], capsys, status: int = 2) -> str:
    """Runs the CLI; asserts the status, one stderr line and no traceback; returns it."""
    got = cli.main(argv)
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert got == status, err
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]
