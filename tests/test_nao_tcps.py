"""NAOqi >= 2.9's ``tcps://`` endpoint with ``nao_user``/``nao_password``, against a
TLS front of the NAOqi stand-in.

The qi 3.1.5 Python bindings can *connect* over ``tcps://`` but cannot *listen* on it:
``Session.listenStandalone("tcps://...")`` fails with "SSL certificates/key missing, the
SSL configuration is incomplete", and no binding sets the server's certificate
(libqi's ``ssl::ServerConfig`` is C++ only). So the stand-in keeps listening on
``tcp://``, and :class:`_TlsFront` stands where the robot's ``tcps://`` port would: it
terminates TLS with a throwaway self-signed certificate (made with the ``openssl``
command at test time), reads qi's first message, the ``authenticate`` call that carries
the client authenticator's data, lets the connection through only when ``auth_user``
and ``auth_token`` are the cell's credentials (the keys NAOqi 2.9's authentication
provider reads; libqi prefixes the authenticator's ``user``/``token`` with ``auth_``),
and then relays the session both ways. What this proves: :func:`bearchair.hardware.real.nao.connect`
speaks TLS on ``tcps://``, sends the credentials inside it, and the NAOqi calls of the
backend then travel through that TLS connection. What it cannot: that a real NAOqi 2.9
accepts them (its reply to ``authenticate`` is relayed from the stand-in, which accepts
anyone).
"""

from __future__ import annotations

import contextlib
import json
import math
import shutil
import socket
import ssl
import struct
import subprocess
import threading
from pathlib import Path
from typing import Any

import pytest

from bearchair.core.errors import BackendUnavailable
from bearchair.core.se2 import SE2Pose

pytest.importorskip("qi")

HEADER = struct.Struct("<IIIHBBIII")
"""qi's message header: magic, id, size, version, type, flags, service, object, action."""
MAGIC = 0x42ADDE42  # libqi: MessagePrivate::magic
AUTHENTICATE = (0, 0, 8)  # service 0 (the server), object 0, action 8: authenticate
USER, PASSWORD = "nao", "s3cret-Pa55"


def _read_exactly(stream: Any, size: int) -> bytes:
    data = b""
    while len(data) < size:
        chunk = stream.recv(size - len(data))
        if not chunk:
            raise ConnectionError("closed")
        data += chunk
    return data


def _parse_dynamic(body: bytes, at: int) -> tuple[Any, int]:
    """One qi dynamic value (its signature, then the value) at ``at``."""
    length = struct.unpack_from("<I", body, at)[0]
    signature = body[at + 4 : at + 4 + length].decode()
    at += 4 + length
    if signature == "b":
        return bool(body[at]), at + 1
    if signature == "s":
        size = struct.unpack_from("<I", body, at)[0]
        return body[at + 4 : at + 4 + size].decode(), at + 4 + size
    if signature == "m":
        return _parse_dynamic(body, at)
    raise ValueError(f"unexpected qi signature {signature!r} in the authentication data")


def parse_capabilities(body: bytes) -> dict[str, Any]:
    """The ``authenticate`` call's argument: a map of strings to dynamic values."""
    count = struct.unpack_from("<I", body, 0)[0]
    at, result = 4, {}
    for _ in range(count):
        size = struct.unpack_from("<I", body, at)[0]
        key = body[at + 4 : at + 4 + size].decode()
        result[key], at = _parse_dynamic(body, at + 4 + size)
    return result


class _TlsFront:
    """A ``tcps://`` endpoint in front of a ``tcp://`` qi stand-in (see the module doc)."""

    def __init__(self, upstream_url: str, certificate: Path, key: Path) -> None:
        host, port = upstream_url.removeprefix("tcp://").rsplit(":", 1)
        self._upstream = (host, int(port))
        self._context = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
        self._context.load_cert_chain(str(certificate), str(key))
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.url = f"tcps://127.0.0.1:{self._listener.getsockname()[1]}"
        self.handshakes: list[str] = []  # TLS versions negotiated
        self.credentials: list[dict[str, Any]] = []  # what each authenticate call carried
        self.refused = 0
        self.relayed_to_nao = 0  # bytes from the client to the stand-in after authentication
        self._sockets: list[socket.socket] = []
        self._lock = threading.Lock()
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                raw, _ = self._listener.accept()
            except OSError:
                return  # closed
            threading.Thread(target=self._serve, args=(raw,), daemon=True).start()

    def _serve(self, raw: socket.socket) -> None:
        try:
            raw.settimeout(5.0)
            client = self._context.wrap_socket(raw, server_side=True)
            client.settimeout(None)
            self.handshakes.append(str(client.version()))
            head = _read_exactly(client, HEADER.size)
            fields = HEADER.unpack(head)
            body = _read_exactly(client, fields[2])
            data = parse_capabilities(body) if fields[6:] == AUTHENTICATE else {}
            self.credentials.append(data)
            if (fields[0], data.get("auth_user"), data.get("auth_token")) != (
                MAGIC,
                USER,
                PASSWORD,
            ):
                self.refused += 1
                client.close()
                return
            upstream = socket.create_connection(self._upstream)
            with self._lock:
                self._sockets += [client, upstream]
            upstream.sendall(head + body)
            threading.Thread(target=self._pump, args=(client, upstream, True), daemon=True).start()
            self._pump(upstream, client, False)
        except (OSError, ssl.SSLError, ConnectionError):
            with contextlib.suppress(OSError):
                raw.close()

    def _pump(self, source: socket.socket, sink: socket.socket, to_nao: bool) -> None:
        try:
            while data := source.recv(65536):
                if to_nao:
                    self.relayed_to_nao += len(data)
                sink.sendall(data)
        except OSError:
            pass
        finally:
            for end in (source, sink):
                with contextlib.suppress(OSError):
                    end.shutdown(socket.SHUT_RDWR)

    def close(self) -> None:
        self._listener.close()
        with self._lock:
            for end in self._sockets:
                with contextlib.suppress(OSError):
                    end.close()


@pytest.fixture(scope="module")
def certificate(tmp_path_factory) -> tuple[Path, Path]:
    """A throwaway self-signed certificate and its key (the ``openssl`` command)."""
    openssl = shutil.which("openssl")
    if openssl is None:
        pytest.skip("the openssl command is not installed")
    folder = tmp_path_factory.mktemp("tls")
    key, cert = folder / "key.pem", folder / "cert.pem"
    subprocess.run(
        [openssl, "req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1",
         "-nodes", "-keyout", str(key), "-out", str(cert), "-days", "1", "-subj", "/CN=nao.local"],
        check=True,
        capture_output=True,
        timeout=30,
    )  # fmt: skip
    return cert, key


@pytest.fixture
def nao_over_tls(certificate):
    from bearchair.hardware.real.standins import NaoqiStandin

    with NaoqiStandin(time_scale=20.0) as standin:
        front = _TlsFront(standin.url, *certificate)
        try:
            yield standin, front
        finally:
            front.close()


def test_tcps_with_credentials_reaches_the_nao_through_tls(nao_over_tls):
    from bearchair.hardware.real.nao import NaoHumanoid, connect

    standin, front = nao_over_tls
    session = connect(front.url, USER, PASSWORD, timeout_s=5.0)
    try:
        assert front.handshakes and front.handshakes[0].startswith("TLSv1.")
        assert front.credentials[-1]["auth_user"] == USER
        assert front.credentials[-1]["auth_token"] == PASSWORD
        before = front.relayed_to_nao
        state = NaoHumanoid(session, SE2Pose(1.9, 0.0, math.pi)).state()
        assert state["battery_percent"] == 87 and state["autonomous_life"] == "solitary"
        # The backend's calls went through the TLS connection, not around it.
        assert front.relayed_to_nao > before + 200
        assert standin.called("getBatteryCharge") == [()]
    finally:
        session.close()


def test_tcps_with_a_wrong_password_or_none_is_refused_in_one_line(nao_over_tls):
    from bearchair.hardware.real.nao import connect

    standin, front = nao_over_tls
    for user, password in ((USER, "wrong"), (None, None)):
        with pytest.raises(BackendUnavailable, match=r"^cannot reach the NAO at tcps://") as caught:
            connect(front.url, user, password, timeout_s=3.0)
        assert "\n" not in str(caught.value)
    assert front.refused == 2
    assert front.credentials[0]["auth_token"] == "wrong"
    assert "auth_user" not in front.credentials[1]  # no authenticator: nothing sent
    assert not standin.calls


def test_plain_tcp_to_the_tls_port_is_refused(nao_over_tls):
    from bearchair.hardware.real.nao import connect

    _, front = nao_over_tls
    with pytest.raises(BackendUnavailable, match="cannot reach the NAO"):
        connect(front.url.replace("tcps://", "tcp://"), timeout_s=3.0)
    assert not front.credentials


def test_check_hardware_with_a_tcps_cell_file(nao_over_tls, tmp_path, capsys):
    import numpy as np

    from bearchair.executive.cli import main

    _, front = nao_over_tls
    cell = tmp_path / "cell.json"
    cell.write_text(
        json.dumps(
            {
                "nao_url": front.url,
                "nao_user": USER,
                "nao_password": PASSWORD,
                "panda_host": "standin",
                "T_world_base": np.eye(4).tolist(),
                "T_flange_camera": np.eye(4).tolist(),
                "nao_start_x_m": 1.9,
                "nao_start_y_m": 0.0,
                "nao_start_yaw_rad": 3.14159,
            }
        )
    )
    status = main(["check-hardware", "--robots", str(cell)])
    out = capsys.readouterr().out
    assert status == 0, out
    assert f"[  ok] nao: reached at {front.url}" in out
    assert front.credentials[-1]["auth_token"] == PASSWORD
    assert PASSWORD not in out


def test_this_qi_cannot_listen_on_tcps_which_is_why_the_front_exists():
    """If a qi release can listen on tcps:// (a certificate setter in the bindings), the
    stand-in should listen there itself and this front can go."""
    import qi

    session = qi.Session()
    assert not hasattr(session, "setIdentity")
    with pytest.raises(RuntimeError, match="SSL certificates/key missing"):
        session.listenStandalone("tcps://127.0.0.1:0")
    session.close()
