"""A stand-in behind an installed SDK's own surface: what the SDK lacks, the double refuses.

:func:`sdk_double` wraps a stand-in object with the SDK class (or module) it stands for.
Every attribute read is checked against the SDK: one the SDK does not have raises
``AttributeError`` even when the stand-in has it (a backend line reading an attribute only
the stand-in offers fails in the tests, as it would on the robot). Every call is bound to
the SDK's signature first (``inspect.signature`` for Python code such as ``openni``;
the signature lines pybind11 writes into the docstrings of ``panda_py`` and
``pyrealsense2``, every overload tried), so a call with arguments the SDK would refuse
raises ``TypeError``. Results whose SDK type is known (a pybind11 ``-> module.Class``
annotation, or ``returns``) come back wrapped the same way, as do instances made by
calling an SDK class. This is ``unittest.mock.create_autospec``'s idea, kept to a
working stand-in: autospec cannot read pybind11 signatures, and it answers with mocks.
"""

from __future__ import annotations

import inspect
import re
from collections.abc import Mapping
from typing import Any

_SIGNATURE_LINE = re.compile(r"^(?:\d+\. )?(?P<name>\w+)\((?P<params>.*)\) -> (?P<returns>[\w.]+)")


def _split_top_level(text: str) -> list[str]:
    """Splits on the commas outside brackets and quotes."""
    parts, depth, quote, current = [], 0, "", []
    for char in text:
        if quote:
            quote = "" if char == quote else quote
        elif char in "\"'":
            quote = char
        elif char in "[(":
            depth += 1
        elif char in "])":
            depth -= 1
        elif char == "," and depth == 0:
            parts.append("".join(current).strip())
            current = []
            continue
        current.append(char)
    if "".join(current).strip():
        parts.append("".join(current).strip())
    return parts


def pybind_signatures(function: Any) -> list[tuple[inspect.Signature, str]]:
    """Each overload's (signature without ``self``, return type name) from a pybind11 docstring."""
    found = []
    name = getattr(function, "__name__", "")
    for line in (getattr(function, "__doc__", None) or "").splitlines():
        match = _SIGNATURE_LINE.match(line.strip())
        if not match or match["name"] != name:
            continue
        parameters = []
        for part in _split_top_level(match["params"]):
            param_name = part.split(":", 1)[0].split("=", 1)[0].strip()
            if param_name in ("self", "*args", "**kwargs") or not param_name.isidentifier():
                continue
            default = inspect.Parameter.empty if "=" not in part else None
            parameters.append(
                inspect.Parameter(
                    param_name, inspect.Parameter.POSITIONAL_OR_KEYWORD, default=default
                )
            )
        found.append((inspect.Signature(parameters), match["returns"]))
    return found


def sdk_signatures(function: Any) -> list[tuple[inspect.Signature, str]]:
    """The SDK function's signatures (without ``self``) and return type names."""
    try:
        signature = inspect.signature(function)
    except (TypeError, ValueError):
        return pybind_signatures(function)
    parameters = [p for p in signature.parameters.values() if p.name != "self"]
    if any(p.kind == p.VAR_POSITIONAL for p in parameters) and pybind_signatures(function):
        return pybind_signatures(function)
    return [(signature.replace(parameters=parameters), "")]


class _Double:
    """The stand-in ``impl`` seen through ``spec`` (see the module docstring)."""

    def __init__(self, impl: Any, spec: Any, module: Any, returns: Mapping[str, Any]) -> None:
        object.__setattr__(self, "_impl", impl)
        object.__setattr__(self, "_spec", spec)
        object.__setattr__(self, "_module", module)
        object.__setattr__(self, "_returns", returns)

    def __getattr__(self, name: str) -> Any:
        spec, impl = self._spec, self._impl
        spec_name = getattr(spec, "__name__", type(spec).__name__)
        if not hasattr(spec, name):
            raise AttributeError(f"{spec_name} has no attribute {name!r} (the SDK lacks it)")
        try:
            value = getattr(impl, name)
        except AttributeError:
            raise NotImplementedError(f"the stand-in does not model {spec_name}.{name}") from None
        sdk_value = getattr(spec, name)
        if isinstance(sdk_value, type) and isinstance(value, type):
            return _Double(value, sdk_value, self._module, self._returns)
        if callable(sdk_value) and callable(value) and not isinstance(value, type):
            return self._method(f"{spec_name}.{name}", sdk_value, value, self._returns.get(name))
        return value

    def __setattr__(self, name: str, value: Any) -> None:
        setattr(self._impl, name, value)  # a test's handle on the stand-in (time_scale, ...)

    def __bool__(self) -> bool:
        return bool(self._impl)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        """An SDK class called: its constructor's signature, the instance a double too."""
        spec = self._spec
        if not isinstance(spec, type):
            raise TypeError(f"{type(spec).__name__} object is not callable")
        _bind(f"{spec.__name__}()", sdk_signatures(spec.__init__), args, kwargs)
        return _Double(self._impl(*args, **kwargs), spec, self._module, self._returns)

    def _method(self, what: str, sdk_function: Any, function: Any, result_spec: Any) -> Any:
        signatures = sdk_signatures(sdk_function)
        module, returns = self._module, self._returns

        def call(*args: Any, **kwargs: Any) -> Any:
            return_type = _bind(what, signatures, args, kwargs)
            result = function(*args, **kwargs)
            spec = result_spec or _resolve(module, return_type)
            plain = isinstance(result, bool | int | float | str) or hasattr(result, "__array__")
            if spec is None or result is None or plain:
                return result
            return _Double(result, spec, module, returns)

        return call


def _bind(
    what: str, signatures: list[tuple[inspect.Signature, str]], args: Any, kwargs: Any
) -> str:
    """Binds a call to the first signature that takes it; its return type name."""
    if not signatures:
        return ""
    for signature, returns in signatures:
        try:
            signature.bind(*args, **kwargs)
        except TypeError:
            continue
        return returns
    shown = " | ".join(str(signature) for signature, _ in signatures)
    raise TypeError(f"{what}: the SDK takes {shown}, not ({len(args)} args, {sorted(kwargs)})")


def _resolve(module: Any, type_name: str) -> Any:
    """The SDK class a pybind11 return annotation names (None for builtins and unknowns)."""
    if not type_name or module is None:
        return None
    last = type_name.rsplit(".", 1)[-1]
    for namespace in (module, getattr(module, "libfranka", None)):
        found = getattr(namespace, last, None) if namespace is not None else None
        if (
            isinstance(found, type)
            and found.__module__.split(".")[0] == module.__name__.split(".")[0]
        ):
            return found
    return None


def sdk_double(
    impl: Any, spec: Any, module: Any = None, returns: Mapping[str, Any] | None = None
) -> Any:
    """``impl`` behind the SDK class or module ``spec``.

    Args:
        impl: the stand-in.
        spec: the installed SDK's class (``panda_py.Panda``) or module (``openni.openni2``).
        module: where return annotations are resolved (default: ``spec``'s module).
        returns: SDK classes of methods' results where the SDK does not annotate them
            (``{"create_depth_stream": openni2.VideoStream}``).
    """
    if module is None:
        module = spec if inspect.ismodule(spec) else inspect.getmodule(spec)
    return _Double(impl, spec, module, returns or {})
