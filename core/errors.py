"""The project's exceptions: one base, one type per failure domain.

Every error a user can act on (a bad argument, an unreadable mesh, an unusable output
folder, a corrupt run record or campaign database) derives from :class:`BearchairError`;
``executive.cli.main`` prints it as one line and exits with status 2. Anything else that
escapes a command is a bug: status 3, one line on the terminal, the traceback in the
run folder's log.

The domain classes live in the core, below every other package, so each
package's own exception (``core.meshes.MeshLoadError``,
``executive.inspect_run.RunRecordError``, ...) can derive from its domain without
importing upward. Those existing classes keep their names and their old bases
(``ValueError`` where they had it), so existing ``except`` clauses still catch them.
"""

from __future__ import annotations


class BearchairError(Exception):
    """A failure the user can act on: printed as one line, exit status 2."""


class InputError(BearchairError):
    """A command-line argument or value is not acceptable."""


class MeshError(BearchairError):
    """A mesh file is missing, unreadable, or not a plausible chair (size, units, up axis)."""


class OutputError(BearchairError):
    """An output place (run folder, picture, report, cache) cannot be written."""


class RunRecordError(BearchairError):
    """A run record (summary.json, ticks.jsonl, tree.json) cannot be read."""


class ChairSetError(BearchairError):
    """A chairs folder or its manifest.json is missing, malformed or holds bad meshes."""


class RecordStoreError(BearchairError):
    """A campaign database is unreadable, read-only, of a foreign schema, or in use."""


class BackendError(BearchairError):
    """A robot or compute backend is not installed, not reachable, or refused."""


class RenderError(BearchairError):
    """A picture of the tree or the scene cannot be drawn."""


def one_line(error: BaseException, limit: int = 400) -> str:
    """The error's message on one line (first line, at most ``limit`` characters)."""
    text = str(error).strip()
    first = text.splitlines()[0] if text else type(error).__name__
    return first if len(first) <= limit else first[: limit - 3] + "..."
