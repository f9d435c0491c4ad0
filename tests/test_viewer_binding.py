"""The web viewers listen on loopback unless ``--bind`` opens them, and their printed link
opens the recording: the sockets are read from the processes (psutil), the link is
fetched. Skipped without rerun-sdk (the ``[viewer]`` extra)."""

from __future__ import annotations

import subprocess
import sys
import time
import urllib.request
from pathlib import Path
from urllib.parse import parse_qs, unquote, urlparse

import psutil
import pytest

from bearchair.executive import cli
from bearchair.executive.viewer_links import (
    LOOPBACK,
    free_port,
    reachable_host,
    ssh_tunnel_hint,
    web_viewer_link,
)
from bearchair.trees.mission import create_tree

pytest.importorskip("rerun", reason="rerun-sdk (the [viewer] extra) is not installed")

from bearchair.executive.recording.mission_recording import RECORDING_FILE, MissionRecording


def _listening(pids: list[int]) -> dict[int, set[str]]:
    """port -> the addresses the given processes listen on (TCP)."""
    found: dict[int, set[str]] = {}
    for pid in pids:
        for connection in psutil.Process(pid).net_connections(kind="inet"):
            if connection.status == psutil.CONN_LISTEN:
                found.setdefault(connection.laddr.port, set()).add(connection.laddr.ip)
    return found


def _wait_for_page(url: str, process: subprocess.Popen | None = None) -> int:
    deadline = time.monotonic() + 30.0
    while True:
        try:
            with urllib.request.urlopen(url, timeout=2) as page:
                return page.status
        except OSError:
            if process is not None:
                assert process.poll() is None, process.stderr.read().decode()
            assert time.monotonic() < deadline, f"{url} did not answer in 30 s"
            time.sleep(0.3)


def _data_url(link: str) -> str:
    return unquote(parse_qs(urlparse(link).query)["url"][0])


def _tiny_recording(path: Path) -> Path:
    import rerun as rr

    stream = rr.RecordingStream("test")
    stream.save(str(path))
    stream.log("world/point", rr.Points3D([[0.0, 0.0, 0.0]]))
    stream.flush()
    stream.disconnect()
    return path


def test_live_web_listens_on_loopback_only_and_its_link_opens(tmp_path):
    web_port, grpc_port = free_port(), free_port()
    recording = MissionRecording(
        create_tree(), path=tmp_path / RECORDING_FILE, live="web", web_port=web_port,
        grpc_port=grpc_port,
    )  # fmt: skip
    try:
        link = recording.viewer_url
        assert link is not None
        assert _wait_for_page(link) == 200
        me = psutil.Process()
        listening = _listening([me.pid] + [child.pid for child in me.children(recursive=True)])
        assert listening[web_port] == {LOOPBACK}
        assert listening[grpc_port] == {LOOPBACK}
        assert urlparse(link).hostname == LOOPBACK
        assert _data_url(link) == f"rerun+http://{LOOPBACK}:{grpc_port}/proxy"
        assert recording.viewer_hint is not None and f"-L {grpc_port}:" in recording.viewer_hint
    finally:
        recording.close()


def test_live_web_opened_with_bind_names_a_reachable_host(tmp_path):
    web_port, grpc_port = free_port("0.0.0.0"), free_port("0.0.0.0")
    recording = MissionRecording(
        create_tree(), path=None, live="web", web_port=web_port, grpc_port=grpc_port,
        bind="0.0.0.0",
    )  # fmt: skip
    try:
        link = recording.viewer_url
        assert link is not None and "0.0.0.0" not in link
        host = urlparse(link).hostname
        assert host == reachable_host("0.0.0.0")
        assert _wait_for_page(link) == 200  # the host in the link reaches the page
        me = psutil.Process()
        listening = _listening([me.pid] + [child.pid for child in me.children(recursive=True)])
        assert listening[web_port] == {"0.0.0.0"} and listening[grpc_port] == {"0.0.0.0"}
        assert recording.viewer_hint is None
    finally:
        recording.close()


def test_view_web_listens_on_loopback_and_reads_a_file_named_like_an_option(tmp_path):
    # rerun's own CLI has --version: the file must be read as a file, not as that option.
    recording = _tiny_recording(tmp_path / "--version.rrd")
    port = free_port()
    viewer = subprocess.Popen(
        [sys.executable, "-m", "bearchair.executive.cli", "view", str(recording), "--web",
         "--port", str(port)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )  # fmt: skip
    try:
        assert viewer.stderr is not None
        line = viewer.stderr.readline().decode()
        assert line.startswith("web viewer: http://127.0.0.1:"), line
        link = line.split()[2]
        hint = viewer.stderr.readline().decode()
        assert "ssh -L" in hint
        assert _wait_for_page(link, viewer) == 200
        grpc_port = int(urlparse(_data_url(link)).port or 0)
        listening = _listening([viewer.pid])
        assert listening[port] == {LOOPBACK} and listening[grpc_port] == {LOOPBACK}
        assert set(listening) == {port, grpc_port}, listening
    finally:
        viewer.terminate()
        viewer.wait(timeout=10)


def test_links_never_name_a_wildcard_and_say_how_to_tunnel():
    link = web_viewer_link("0.0.0.0", 9090, 9877)
    assert "0.0.0.0" not in link and _data_url(link).endswith(":9877/proxy")
    assert web_viewer_link("::1", 9090, 9877).startswith("http://[::1]:9090/?url=")
    assert web_viewer_link("192.168.3.4", 1, 2) == (
        "http://192.168.3.4:1/?url=rerun%2Bhttp%3A%2F%2F192.168.3.4%3A2%2Fproxy"
    )
    hint = ssh_tunnel_hint(LOOPBACK, 9090, 9877)
    assert hint is not None and "-L 9090:127.0.0.1:9090 -L 9877:127.0.0.1:9877" in hint
    assert ssh_tunnel_hint("0.0.0.0", 9090, 9877) is None


def test_bind_takes_an_address_only(tmp_path, capsys):
    from pydantic import ValidationError

    from bearchair.executive.mission_config import MissionConfig

    # run: left off, the configuration's outputs.bind stands, loopback by default.
    assert cli.build_parser().parse_args(["run"]).bind is None
    assert MissionConfig().outputs.bind == LOOPBACK
    assert MissionConfig().run_config(tmp_path).bind == LOOPBACK
    opened = MissionConfig.model_validate({"outputs": {"bind": "0.0.0.0"}})
    assert opened.run_config(tmp_path).bind == "0.0.0.0"
    with pytest.raises(ValidationError, match="not an IP address"):
        MissionConfig.model_validate({"outputs": {"bind": "example.org"}})
    assert cli.main(["run", "--bind", "example.org", "--out", str(tmp_path / "r")]) == 2
    assert "not an IP address" in capsys.readouterr().err
    assert cli.build_parser().parse_args(["view", "x"]).bind == LOOPBACK
    assert cli.build_parser().parse_args(["view", "x", "--bind", "0.0.0.0"]).bind == "0.0.0.0"
    assert cli.main(["view", str(tmp_path), "--web", "--bind", "example.org"]) == 2
    assert "not an IP address" in capsys.readouterr().err
