"""``check-hardware`` against devices that accept a connection and never answer.

A peer that accepts TCP and stays silent is what a half-open Wi-Fi link or a hung
controller looks like: each device in turn (the NAO at its qi port, the Panda at
libfranka's port 1337, the camera as an OpenNI device that never streams) must be named
within ``--timeout`` and the command exit 1; Ctrl-C and SIGTERM must end it within 1 s
(run as a real process, as an operator would).
"""

from __future__ import annotations

import contextlib
import functools
import json
import os
import queue
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from bearchair.executive.cli import main
from tests.helpers.silent_peers import silent_panda, silent_peer

pytest.importorskip("qi")

TIMEOUT_S = 0.5
"""The ``--timeout`` the tests give each device."""
STARTUP_S = 20.0
"""How long a subprocess may take to import bearchair (a loaded 2-core machine)."""


def _cell(tmp_path, nao_url: str, panda_host: str = "standin"):
    path = tmp_path / "cell.json"
    path.write_text(
        json.dumps(
            {
                "nao_url": nao_url,
                "panda_host": panda_host,
                "T_world_base": np.eye(4).tolist(),
                "T_flange_camera": np.eye(4).tolist(),
                "nao_start_x_m": 1.9,
                "nao_start_y_m": 0.0,
                "nao_start_yaw_rad": 3.14159,
            }
        )
    )
    return path


def _check_hardware(cell, timeout_s: float) -> subprocess.Popen:
    command = "import sys; from bearchair.executive.cli import main; sys.exit(main())"
    return subprocess.Popen(
        [
            sys.executable,
            "-c",
            command,
            "check-hardware",
            "--robots",
            str(cell),
            "--timeout",
            f"{timeout_s:g}",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )


def _wait_for_line(
    process: subprocess.Popen, prefix: str, within_s: float = STARTUP_S
) -> list[str]:
    """Reads stdout until a line starting with ``prefix`` (the lines read), for at most
    ``within_s``: a process that hangs fails the test instead of hanging it."""
    assert process.stdout is not None
    lines: queue.Queue[str] = getattr(process, "lines", None) or queue.Queue()
    if not hasattr(process, "lines"):
        process.lines = lines  # type: ignore[attr-defined]
        stdout = process.stdout
        threading.Thread(target=lambda: [lines.put(line) for line in stdout], daemon=True).start()
    seen: list[str] = []
    deadline = time.monotonic() + within_s
    while (remaining := deadline - time.monotonic()) > 0.0:
        try:
            line = lines.get(timeout=remaining)
        except queue.Empty:
            break
        seen.append(line)
        if line.startswith(prefix):
            return seen
    process.kill()
    raise AssertionError(f"no line {prefix!r} within {within_s:g} s after {seen}")


@pytest.mark.slow
def test_a_silent_nao_is_named_within_its_timeout(tmp_path):
    with silent_peer() as (host, port):
        process = _check_hardware(_cell(tmp_path, f"tcp://{host}:{port}"), TIMEOUT_S)
        _wait_for_line(process, "[  ok] sdk pyrealsense2")  # the last line before the NAO
        started = time.monotonic()
        failed = _wait_for_line(process, "[FAIL] nao", within_s=TIMEOUT_S + 5.0)[-1]
        took_s = time.monotonic() - started
        rest = _wait_for_line(process, "check-hardware:")
        process.wait(timeout=STARTUP_S)
    assert process.returncode == 1
    assert f"cannot reach the NAO at tcp://{host}:{port}: no answer in 0.5 s" in failed
    assert took_s < TIMEOUT_S + 0.5
    assert rest[-1].strip() == "check-hardware: FAILED: nao"


@pytest.mark.slow
def test_a_silent_panda_is_named_within_its_timeout(tmp_path):
    from bearchair.hardware.real.standins import NaoqiStandin

    _run_in_process(tmp_path / "none.json", TIMEOUT_S)  # imports done
    with NaoqiStandin() as naoqi, silent_panda() as host:
        started = time.monotonic()
        status = _run_in_process(_cell(tmp_path, naoqi.url, host), TIMEOUT_S)
        took_s = time.monotonic() - started
    out = status[1]
    assert status[0] == 1
    assert f"[FAIL] panda: the Panda at {host}: no answer in 0.5 s" in out
    assert took_s < 3 * TIMEOUT_S + 2.0
    assert out.strip().splitlines()[-1] == "check-hardware: FAILED: panda"


def _run_in_process(cell, timeout_s: float) -> tuple[int, str]:
    """check-hardware in this process, its perception imports (seconds, not device time)
    done before the clock starts."""
    import io
    from contextlib import redirect_stdout

    import bearchair.skills.perception.tags
    import bearchair.skills.perception.views  # noqa: F401

    buffer = io.StringIO()
    with redirect_stdout(buffer):
        status = main(["check-hardware", "--robots", str(cell), "--timeout", f"{timeout_s:g}"])
    return status, buffer.getvalue()


def test_a_silent_camera_is_named_within_its_timeout(tmp_path, monkeypatch):
    from bearchair.hardware.real import robots
    from bearchair.hardware.real.standins import NaoqiStandin, OpenNI2Standin

    monkeypatch.setattr(robots, "OpenNI2Standin", functools.partial(OpenNI2Standin, silent=True))
    _run_in_process(tmp_path / "none.json", TIMEOUT_S)  # imports done
    with NaoqiStandin() as naoqi:
        started = time.monotonic()
        status, out = _run_in_process(_cell(tmp_path, naoqi.url), TIMEOUT_S)
        took_s = time.monotonic() - started
    assert status == 1
    # The camera's own read timeout and check-hardware's bound are both 0.5 s: whichever
    # fires first names the camera (on a loaded machine it is the bound's).
    assert (
        "[FAIL] camera: the Carmine sent no depth frame in 0.5 s" in out
        or "[FAIL] camera: the wrist camera: no answer in 0.5 s" in out
    )
    assert took_s < 2 * TIMEOUT_S + 3.0
    assert out.strip().splitlines()[-1] == "check-hardware: FAILED: camera"


@pytest.mark.slow
@pytest.mark.parametrize(("signum", "status"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
@pytest.mark.parametrize("device", ["nao", "panda"])
def test_a_stop_signal_ends_check_hardware_within_a_second(tmp_path, signum, status, device):
    from bearchair.hardware.real.standins import NaoqiStandin

    with contextlib.ExitStack() as stack:
        if device == "nao":
            host, port = stack.enter_context(silent_peer())
            cell = _cell(tmp_path, f"tcp://{host}:{port}")
        else:
            naoqi = stack.enter_context(NaoqiStandin())
            cell = _cell(tmp_path, naoqi.url, stack.enter_context(silent_panda()))
        process = _check_hardware(cell, 60.0)
        # Waiting on the silent device from here: NAO first, then the Panda.
        _wait_for_line(
            process, "[  ok] nao arm swing" if device == "panda" else "[  ok] sdk pyrealsense2"
        )
        time.sleep(0.3)
        sent = time.monotonic()
        process.send_signal(signum)
        try:
            process.wait(timeout=5.0)
        finally:
            process.kill()
        took_s = time.monotonic() - sent
        err = process.stderr.read() if process.stderr else ""
    assert took_s < 1.0, f"{signal.Signals(signum).name} took {took_s:.2f} s"
    assert process.returncode == status, err
    assert "Traceback" not in err


def test_a_camera_that_announces_a_frame_and_never_sends_it_is_named_within_its_timeout(
    tmp_path, monkeypatch
):
    """The driver says a frame is ready and ``read_frame`` then blocks: the camera's own
    wait cannot see that, check-hardware's bound on the capture must."""
    from bearchair.hardware.real import robots
    from bearchair.hardware.real.standins import NaoqiStandin, OpenNI2Standin

    class Announcing(OpenNI2Standin):
        def wait_for_any_stream(self, streams, timeout=None):
            return streams[0]

    monkeypatch.setattr(robots, "OpenNI2Standin", functools.partial(Announcing, silent=True))
    _run_in_process(tmp_path / "none.json", TIMEOUT_S)  # imports done
    with NaoqiStandin() as naoqi:
        cell = _cell(tmp_path, naoqi.url)
        result: list[tuple[int, str]] = []
        worker = threading.Thread(
            target=lambda: result.append(_run_in_process(cell, TIMEOUT_S)), daemon=True
        )
        worker.start()
        worker.join(2 * TIMEOUT_S + 3.0)
        assert not worker.is_alive(), "check-hardware still waits for the camera: it hangs"
    status, out = result[0]
    assert status == 1
    assert "[FAIL] camera: the wrist camera: no answer in 0.5 s" in out
    assert out.strip().splitlines()[-1] == "check-hardware: FAILED: camera"
