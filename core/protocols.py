"""Does an object satisfy a ``typing.Protocol``? Every method present, every call bindable.

``isinstance(obj, SomeProtocol)`` on a ``runtime_checkable`` protocol checks only that the
names exist. A plug-in (a skill set, a robot backend) is refused at load when it lacks a
method *or* when a method cannot accept the arguments the caller passes: the protocol's
positional parameters positionally, its keyword-only parameters by keyword. That is what
:func:`protocol_gaps` checks, with :meth:`inspect.Signature.bind`.
"""

from __future__ import annotations

import inspect
from typing import Any


def protocol_members(protocol: type) -> dict[str, inspect.Signature]:
    """The public methods a protocol declares, each with its signature without ``self``."""
    members: dict[str, inspect.Signature] = {}
    for klass in reversed(protocol.__mro__):
        if klass is object or klass.__module__ == "typing":
            continue
        for name, value in vars(klass).items():
            if name.startswith("_") or not callable(value):
                continue
            signature = inspect.signature(value)
            parameters = list(signature.parameters.values())[1:]  # drop self
            members[name] = signature.replace(parameters=parameters)
    return members


def binding_error(implementation: Any, signature: inspect.Signature) -> str | None:
    """Why ``implementation`` cannot be called as ``signature`` says, or None when it can.

    Both call styles a caller may use are tried: the protocol's positional-or-keyword
    parameters passed positionally, and passed by keyword; keyword-only ones by keyword.
    """
    try:
        target = inspect.signature(implementation)
    except (TypeError, ValueError):
        return None  # a builtin without a signature: nothing to check
    positional: list[Any] = []
    by_name: dict[str, Any] = {}
    keywords: dict[str, Any] = {}
    for parameter in signature.parameters.values():
        if parameter.kind in (parameter.VAR_POSITIONAL, parameter.VAR_KEYWORD):
            continue
        if parameter.kind == parameter.POSITIONAL_ONLY:
            positional.append(parameter.name)
        elif parameter.kind == parameter.POSITIONAL_OR_KEYWORD:
            by_name[parameter.name] = parameter.name
        else:
            keywords[parameter.name] = parameter.name
    for args, kwargs in (
        ([*positional, *by_name.values()], keywords),
        (positional, {**by_name, **keywords}),
    ):
        try:
            target.bind(*args, **kwargs)
        except TypeError as error:
            return f"takes {target}, not {signature} ({error})"
    return None


def protocol_gaps(obj: Any, protocol: type) -> list[str]:
    """What ``obj`` lacks to satisfy ``protocol``, one phrase each (empty: it satisfies it).

    Example: ``["no method scan_chair", "imagine_sitting takes (mesh), not (chair_mesh, *,
    seed, cancel=None) (...)"]``.
    """
    gaps = []
    for name, signature in protocol_members(protocol).items():
        method = getattr(obj, name, None)
        if method is None:
            gaps.append(f"no method {name}")
        elif not callable(method):
            gaps.append(f"{name} is not callable")
        else:
            problem = binding_error(method, signature)
            if problem is not None:
                gaps.append(f"{name} {problem}")
    return gaps
