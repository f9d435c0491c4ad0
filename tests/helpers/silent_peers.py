"""Peers that accept a TCP connection and never send a byte: what a half-open Wi-Fi
link or a hung controller looks like."""

from __future__ import annotations

import contextlib
import random
import socket
import threading
from collections.abc import Iterator

import pytest


@contextlib.contextmanager
def silent_peer(host: str = "127.0.0.1", port: int = 0) -> Iterator[tuple[str, int]]:
    """A TCP listener that accepts every connection and never sends a byte."""
    server = socket.socket()
    server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    server.bind((host, port))
    server.listen(16)
    held: list[socket.socket] = []
    closing = threading.Event()

    def accept() -> None:
        while not closing.is_set():
            try:
                connection, _ = server.accept()
            except OSError:
                return
            held.append(connection)

    threading.Thread(target=accept, daemon=True).start()
    try:
        yield server.getsockname()
    finally:
        closing.set()
        server.close()
        for connection in held:
            connection.close()


@contextlib.contextmanager
def silent_panda() -> Iterator[str]:
    """A silent peer on libfranka's port 1337 at a free loopback address."""
    for _ in range(20):
        host = f"127.0.{random.randrange(1, 255)}.{random.randrange(2, 255)}"
        try:
            with silent_peer(host, 1337):
                yield host
                return
        except OSError:
            continue
    pytest.skip("no free loopback address for a silent Panda")
