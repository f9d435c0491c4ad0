"""The project's exceptions: one hierarchy, one base.

Every exception the project raises derives from :class:`BearchairError` through one
domain class here::

    BearchairError
    ├── InputError          a command-line argument or value is not acceptable
    │   ├── ConfigError     a mission configuration file is wrong (one line naming the field)
    │   └── PluginError     a plug-in cannot be loaded or does not satisfy its Protocol
    ├── MeshError           a mesh file is unusable (MeshLoadError)
    ├── OutputError         an output place cannot be written (RecordWriteError)
    ├── RunRecordError      a run record cannot be read
    ├── ChairSetError       a chairs folder or manifest is unusable (BadChairsError)
    ├── RecordStoreError    a campaign database is unusable
    ├── BackendError        a robot or compute backend is missing, unreachable or refused
    │   ├── BackendUnavailable  (CellConfigError, RecordingUnavailable)
    │   └── EmergencyStopped, ArmFault (hardware.real)
    ├── RenderError         a picture cannot be drawn
    ├── SkillError          a skill cannot answer for this input (PerceptionError,
    │                       AccessibilityError, InfeasibleSeating, WalkError, ...)
    └── Cancelled           a long skill stopped because it was asked to (ScanCancelled,
                            SeatingCancelled)

At the command line (``bearchair.executive.cli.main``) a BearchairError is printed as one line
and the command exits with status 2; anything else that escapes a command is a bug:
status 3, one line on the terminal, the traceback in the run folder's log. In the
mission tree, a leaf turns any exception of its skill into FAILURE with its message.

The classes keep the builtin bases they had before the hierarchy (``ValueError``,
``RuntimeError``), so ``except ValueError`` clauses written for them still catch them.
"""

from __future__ import annotations


class BearchairError(Exception):
    """The root of the project's exceptions: a failure of the input, a place, a backend
    or a skill, not a bug (at the command line: one line, exit status 2)."""


class InputError(BearchairError):
    """A command-line argument or value is not acceptable."""


class ConfigError(InputError):
    """A mission configuration (``bearchair run --config``) is wrong: the message is one
    line naming the file and the field."""


class PluginError(InputError):
    """A plug-in (an entry point of the ``bearchair.*`` groups, or a ``module:factory``)
    cannot be loaded, or what it gives does not satisfy its Protocol: the message names
    the plug-in and what is missing."""


class MeshError(BearchairError):
    """A mesh file is missing, unreadable, or not a plausible chair (size, units, up axis)."""


class OutputError(BearchairError):
    """An output place (run folder, picture, report, cache) cannot be written."""


class RunRecordError(BearchairError, ValueError):
    """A run record (summary.json, ticks.jsonl, tree.json) cannot be read."""


class ChairSetError(BearchairError, ValueError):
    """A chairs folder or its manifest.json is missing, malformed or holds bad meshes."""


class RecordStoreError(BearchairError):
    """A campaign database is unreadable, read-only, of a foreign schema, or in use."""


class BackendError(BearchairError):
    """A robot or compute backend is not installed, not reachable, or refused."""


class BackendUnavailable(BackendError, RuntimeError):
    """A backend's library is not installed, its device not found, or it cannot connect."""


class RenderError(BearchairError, RuntimeError):
    """A picture of the tree or the scene cannot be drawn."""


class SkillError(BearchairError):
    """A skill cannot give an answer for this input (no chair in the frames, no path, no
    feasible seating): the leaf that called it fails with the message."""


class Cancelled(BearchairError):
    """A long skill or motion stopped early because its caller asked it to."""


def one_line(error: BaseException, limit: int = 400) -> str:
    """The error's message on one line (first line, at most ``limit`` characters)."""
    text = str(error).strip()
    first = text.splitlines()[0] if text else type(error).__name__
    return first if len(first) <= limit else first[: limit - 3] + "..."
