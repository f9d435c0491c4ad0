"""Reading the user's files safely, and showing what they hold safely.

A file named on the command line or found in a folder may be anything: a FIFO (a read
blocks forever), ``/dev/zero`` (a read never ends), a symlink loop, a 3 GiB "manifest",
JSON nested 100000 deep (the parser's recursion ends in RecursionError), a 401-digit
number (OverflowError where it is used), or YAML of nested aliases that expands to
gigabytes. Every reader here takes regular files only (opened non-blocking, checked
with ``fstat`` before a byte is read), reads at most a stated number of bytes, and
parses with bounds on nesting, numbers and alias expansion. What fails is one line:
an instance of the caller's error class, naming the file and the reason.

Strings from files and records are shown through :func:`printable`: a control
character in a chair's name must not retitle the terminal, clear the screen, or start
a new line that looks like the program's own.
"""

from __future__ import annotations

import errno
import json
import math
import os
import stat
from pathlib import Path
from typing import Any

from bearchair.core.errors import BearchairError

MAX_TEXT_BYTES = 16 * 1024 * 1024
"""Largest manifest, cell file, calibration file or record document read (bytes): the
calibration manifest of 173 meshes is 60 kB, a 100-view calibration file about 100 kB."""
MAX_JSON_DEPTH = 64
"""Deepest nesting of arrays and objects accepted: the project's documents nest 5 deep."""
MAX_INT_DIGITS = 30
"""Longest integer accepted in a document (digits): seeds are at most 10 digits; beyond
about 308 an integer cannot even become a float."""
MAX_YAML_NODES = 100_000
"""Most nodes a YAML document may stand for once its aliases are expanded (a cell file
has about 60)."""


def printable(text: object, limit: int = 300) -> str:
    """``text`` with every control character written as an escape (``\\n``, ``\\x1b``),
    shortened to ``limit`` characters: safe on a terminal and on one line."""
    shown = str(text)
    if len(shown) > limit:
        shown = shown[: limit - 3] + "..."
    if shown.isprintable():
        return shown
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in shown)


def open_regular_file(path: Path, what: str, error: type[BearchairError]) -> int:
    """A read-only descriptor of ``path`` after checking it is a regular file.

    Opened non-blocking, so a FIFO is refused instead of waiting for a writer.

    Raises:
        error: missing, a symlink loop, unreadable, a folder, a FIFO or a device.
    """
    shown = printable(path)
    try:
        descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as failure:
        raise error(f"{shown}: {_open_failure(failure)}") from None
    kind = os.fstat(descriptor).st_mode
    if not stat.S_ISREG(kind):
        os.close(descriptor)
        if stat.S_ISDIR(kind):
            raise error(f"{shown}: is a directory, not a {what}")
        raise error(f"{shown}: not a regular file (a pipe or a device); give a {what}")
    return descriptor


def _open_failure(failure: OSError) -> str:
    if failure.errno == errno.ELOOP:
        return "a symlink loop (the link points back at itself)"
    if failure.errno == errno.ENOENT:
        return "no such file"
    if failure.errno == errno.EACCES:
        return "not readable (permission denied)"
    return f"cannot open it ({failure.strerror or failure})"


def read_user_bytes(
    path: Path, what: str, error: type[BearchairError], max_bytes: int = MAX_TEXT_BYTES
) -> bytes:
    """The bytes of a regular file of at most ``max_bytes`` (see :func:`open_regular_file`)."""
    descriptor = open_regular_file(Path(path), what, error)
    try:
        with os.fdopen(descriptor, "rb") as stream:
            data = stream.read(max_bytes + 1)
    except OSError as failure:
        raise error(f"{printable(path)}: cannot read it ({failure.strerror})") from None
    if len(data) > max_bytes:
        raise error(
            f"{printable(path)}: larger than {max_bytes / 1e6:.0f} MB; too large for a {what}"
        )
    return data


def read_user_text(
    path: Path, what: str, error: type[BearchairError], max_bytes: int = MAX_TEXT_BYTES
) -> str:
    """The UTF-8 text of a regular file of at most ``max_bytes``."""
    data = read_user_bytes(path, what, error, max_bytes)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as failure:
        raise error(f"{printable(path)}: not UTF-8 text (byte {failure.start})") from None


def _bounded_int(digits: str) -> int:
    if len(digits.lstrip("-")) > MAX_INT_DIGITS:
        raise ValueError(f"an integer of {len(digits.lstrip('-'))} digits")
    return int(digits)


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"the number {text[:20]} is too large")
    return value


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    found: dict[str, Any] = {}
    for key, value in pairs:
        if key in found:
            raise ValueError(
                f"the key {printable(json.dumps(key), 60)} appears twice in one object"
            )
        found[key] = value
    return found


def _no_constant(name: str) -> float:
    raise ValueError(f"{name} is not a number")


def parse_json(text: str, where: str, error: type[BearchairError]) -> Any:
    """``text`` as JSON, with nesting, integers and floats bounded, and no key twice in an
    object (the later one would silently win).

    Raises:
        error: ``<where>: not valid JSON (<reason>)``, one line.
    """
    try:
        document = json.loads(
            text,
            parse_int=_bounded_int,
            parse_float=_finite_float,
            parse_constant=_no_constant,
            object_pairs_hook=_unique_keys,
        )
    except json.JSONDecodeError as failure:
        reason = f"{failure.msg} at line {failure.lineno} column {failure.colno}"
        raise error(f"{where}: not valid JSON ({reason})") from None
    except RecursionError:
        raise error(f"{where}: not valid JSON (nested too deeply)") from None
    except ValueError as failure:
        raise error(f"{where}: not valid JSON ({printable(failure, 80)})") from None
    if nesting_depth(document) > MAX_JSON_DEPTH:
        raise error(f"{where}: not valid JSON (nested deeper than {MAX_JSON_DEPTH})")
    return document


def nesting_depth(document: Any) -> int:
    """How deep lists and dicts nest in ``document`` (0 for a scalar), without recursion."""
    deepest, stack = 0, [(document, 1)]
    while stack:
        node, depth = stack.pop()
        if isinstance(node, dict | list):
            deepest = max(deepest, depth)
            if depth > MAX_JSON_DEPTH:
                return depth
            children = node.values() if isinstance(node, dict) else node
            stack.extend((child, depth + 1) for child in children)
    return deepest


def load_user_json(
    path: Path, what: str, error: type[BearchairError], max_bytes: int = MAX_TEXT_BYTES
) -> Any:
    """A bounded JSON document from a regular file (:func:`read_user_bytes`, :func:`parse_json`)."""
    data = read_user_bytes(path, what, error, max_bytes)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as failure:
        raise error(
            f"{printable(path)}: not valid JSON (not UTF-8 text at byte {failure.start})"
        ) from None
    return parse_json(text, printable(path), error)


def parse_yaml(text: str, where: str, error: type[BearchairError]) -> Any:
    """``text`` as YAML (PyYAML's safe loader), refused when its aliases would expand to
    more than :data:`MAX_YAML_NODES` nodes or it nests deeper than :data:`MAX_JSON_DEPTH`.

    Raises:
        error: one line; ImportError when PyYAML is not installed.
    """
    import yaml

    loader = yaml.SafeLoader(text)
    try:
        root = loader.get_single_node()
        if root is None:
            return None
        nodes, depth = _expanded_size(root)
        if nodes > MAX_YAML_NODES:
            raise error(
                f"{where}: its aliases expand to more than {MAX_YAML_NODES} values; "
                "write the values out"
            )
        if depth > MAX_JSON_DEPTH:
            raise error(f"{where}: nested deeper than {MAX_JSON_DEPTH}")
        return loader.construct_document(root)
    except yaml.YAMLError as failure:
        first = str(failure).splitlines()[0] if str(failure) else type(failure).__name__
        raise error(f"{where}: not valid YAML ({printable(first, 120)})") from None
    except RecursionError:
        raise error(f"{where}: not valid YAML (nested too deeply)") from None
    finally:
        loader.dispose()


def _expanded_size(root: Any) -> tuple[int, int]:
    """(nodes, depth) of a composed YAML graph with every alias expanded, by memo over
    shared nodes (a billion laughs costs one visit per distinct node)."""
    import yaml

    sizes: dict[int, tuple[int, int]] = {}
    stack: list[tuple[Any, bool]] = [(root, False)]
    while stack:
        node, children_done = stack.pop()
        if id(node) in sizes:
            continue
        if isinstance(node, yaml.MappingNode):
            children = [part for pair in node.value for part in pair]
        elif isinstance(node, yaml.SequenceNode):
            children = list(node.value)
        else:
            sizes[id(node)] = (1, 0)
            continue
        if not children_done:
            if len(stack) > 10 * MAX_JSON_DEPTH + len(children) + 1000:
                return MAX_YAML_NODES + 1, MAX_JSON_DEPTH + 1
            stack.append((node, True))
            stack.extend((child, False) for child in children if id(child) not in sizes)
            continue
        total = 1 + sum(sizes[id(child)][0] for child in children)
        depth = 1 + max((sizes[id(child)][1] for child in children), default=0)
        sizes[id(node)] = (min(total, MAX_YAML_NODES + 1), depth)
    return sizes[id(root)]
