"""Where Rerun's viewers listen, and the links printed to open them.

Both web viewers (``bearchair view RUN --web`` and ``bearchair run --live web``) are two
servers: an HTTP server for the viewer's page and a gRPC server for the recording's
data, which the page fetches from the browser. Both listen on loopback
(:data:`LOOPBACK`) unless ``--bind ADDR`` opens them to a network, because a recording
shows the room, and Rerun's own default is every interface.

rerun-sdk 0.41 binds the gRPC server where asked (``GrpcServerSink(bind_ip=...)`` and
the CLI's ``--bind``), but its in-process page server (``rr.serve_web_viewer``) always
listens on 0.0.0.0; the CLI's ``--serve-web --bind ADDR URL`` serves the page alone on
``ADDR``, so the page comes from that program (:func:`serve_web_page`).

The printed link (:func:`web_viewer_link`) names a host the browser can reach: the
bind address itself, or for a wildcard bind (``0.0.0.0``, ``::``) this machine's
address on its default route. For a browser on another machine with the default bind,
:func:`ssh_tunnel_hint` says how to forward both ports with ``ssh -L``.
"""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import ipaddress
import os
import socket
import subprocess
import sys
import time
from pathlib import Path
from urllib.parse import quote

LOOPBACK = "127.0.0.1"
"""Where the viewers listen unless ``--bind`` says otherwise."""
PAGE_START_S = 20.0
"""Longest wait for Rerun's program to serve the page (it takes about 0.4 s here)."""
_ROUTE_PROBE = ("192.0.2.1", 9)
"""A TEST-NET-1 address (RFC 5737): connecting a UDP socket to it sends nothing, and the
socket's own address is then this machine's address on its default route."""


def bind_address(text: str) -> str:
    """An argparse type: an IPv4 or IPv6 address to listen on (``0.0.0.0``: every one).

    Raises:
        argparse.ArgumentTypeError: not an IP address (a host name is not bindable here).
    """
    try:
        return str(ipaddress.ip_address(text.strip("[]")))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"not an IP address: {text!r} (127.0.0.1: this machine only; 0.0.0.0: every network)"
        ) from None


def add_bind_argument(parser: argparse.ArgumentParser, *, configured: bool = False) -> None:
    """``--bind ADDR`` for a command that serves a viewer; ``configured``: left off, the
    mission configuration's ``outputs.bind`` stands (default None here)."""
    parser.add_argument(
        "--bind",
        type=bind_address,
        default=None if configured else LOOPBACK,
        metavar="ADDR",
        help="the address the viewer listens on: 127.0.0.1 serves this machine only "
        "(reach it from elsewhere with ssh -L), 0.0.0.0 every network (anyone who can reach "
        "this machine can watch)" + (" (default: 127.0.0.1, or --config's)" if configured else ""),
    )


def is_wildcard(bind: str) -> bool:
    """True for an address that listens on every interface (``0.0.0.0``, ``::``)."""
    return ipaddress.ip_address(bind).is_unspecified


def reachable_host(bind: str) -> str:
    """A host a browser can open for a server bound to ``bind`` (never ``0.0.0.0``)."""
    if not is_wildcard(bind):
        return bind
    with contextlib.suppress(OSError), socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.connect(_ROUTE_PROBE)
        address = probe.getsockname()[0]
        if not ipaddress.ip_address(address).is_unspecified:
            return address
    return socket.gethostname()


def _url_host(host: str) -> str:
    with contextlib.suppress(ValueError):
        if ipaddress.ip_address(host).version == 6:
            return f"[{host}]"
    return host


def grpc_url(host: str, grpc_port: int) -> str:
    """The Rerun URL of a gRPC server (what a viewer connects to)."""
    return f"rerun+http://{_url_host(host)}:{grpc_port}/proxy"


def web_viewer_link(bind: str, web_port: int, grpc_port: int) -> str:
    """The link that opens the web viewer on the recording: the page and, in ``?url=``,
    the gRPC server's address, both on a reachable host."""
    host = _url_host(reachable_host(bind))
    data = grpc_url(reachable_host(bind), grpc_port)
    return f"http://{host}:{web_port}/?url={quote(data, safe='')}"


def ssh_tunnel_hint(bind: str, web_port: int, grpc_port: int) -> str | None:
    """How to open a loopback-bound viewer from another machine (None when it is open)."""
    if not ipaddress.ip_address(bind).is_loopback:
        return None
    user = os.environ.get("USER") or "USER"
    host = socket.gethostname()
    return (
        f"from another machine: ssh -L {web_port}:{bind}:{web_port} -L {grpc_port}:{bind}:"
        f"{grpc_port} {user}@{host}, then open the same link there"
    )


def free_port(bind: str = LOOPBACK) -> int:
    """A port free on ``bind`` now (the OS's pick)."""
    family = socket.AF_INET6 if ipaddress.ip_address(bind).version == 6 else socket.AF_INET
    with socket.socket(family) as probe:
        probe.bind((bind, 0))
        return int(probe.getsockname()[1])


def rerun_binary() -> str:
    """The viewer program rerun-sdk ships (what ``python -m rerun`` starts)."""
    if "RERUN_CLI_PATH" in os.environ:
        return os.environ["RERUN_CLI_PATH"]
    import rerun_cli

    folder = Path(rerun_cli.__file__).parent
    bundled = folder / "Rerun.app" / "Contents" / "MacOS" / "Rerun"
    if sys.platform == "darwin" and bundled.exists():
        return str(bundled)
    return str(folder / ("rerun.exe" if sys.platform.startswith("win") else "rerun"))


def quiet_rerun_environment() -> dict[str, str]:
    """The environment for Rerun's program: its own log only from warnings up (we print
    the link ourselves, one that works)."""
    return {**os.environ, "RUST_LOG": os.environ.get("RUST_LOG", "warn")}


def serve_web_page(bind: str, web_port: int, connect_to: str) -> subprocess.Popen[bytes]:
    """Starts Rerun's program serving the web viewer's page alone on ``bind:web_port``,
    pointed at the gRPC server ``connect_to``; it dies with this process (Linux)."""
    command = [
        rerun_binary(),
        "--serve-web",
        "--bind",
        bind,
        "--web-viewer-port",
        str(web_port),
        connect_to,
    ]
    server = subprocess.Popen(
        command,
        stdin=subprocess.DEVNULL,
        env=quiet_rerun_environment(),
        preexec_fn=_die_with_parent if sys.platform.startswith("linux") else None,
    )
    try:
        wait_until_listening(reachable_host(bind), web_port, server)
    except BaseException:
        server.terminate()
        raise
    return server


def wait_until_listening(
    host: str, port: int, server: subprocess.Popen[bytes], timeout_s: float = PAGE_START_S
) -> None:
    """Returns once ``host:port`` accepts connections, so that a link printed next opens.

    Raises:
        OSError: the server exited, or did not listen within ``timeout_s``.
    """
    deadline = time.monotonic() + timeout_s
    while True:
        with contextlib.suppress(OSError), socket.create_connection((host, port), timeout=0.5):
            return
        if server.poll() is not None:
            raise OSError(
                f"Rerun's web viewer exited ({server.returncode}) instead of serving port {port}"
            )
        if time.monotonic() > deadline:
            raise OSError(
                f"Rerun's web viewer did not listen on port {port} within {timeout_s:.0f} s"
            )
        time.sleep(0.05)


def _die_with_parent() -> None:
    """In the child, before exec: SIGTERM when the parent dies (even by SIGKILL), so a
    run killed mid-way leaves no page server behind."""
    pr_set_pdeathsig, sigterm = 1, 15
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(pr_set_pdeathsig, sigterm)


def spawn_native_viewer(bind: str, grpc_port: int, *, headless: bool = False) -> int | None:
    """Starts Rerun's native viewer, detached (it outlives the run), its gRPC server on
    ``bind:grpc_port`` (``RecordingStream.spawn`` takes no bind address and listens on
    every interface); returns its process id. ``headless``: no window (tests)."""
    import rerun_bindings

    return rerun_bindings.spawn(
        port=grpc_port,
        executable_path=rerun_binary(),
        extra_args=["--bind", bind],
        # What RecordingStream.spawn tells the program: it is a viewer only (no analytics prompt).
        extra_env=[("RERUN_APP_ONLY", "true")],
        headless=headless,
    )
