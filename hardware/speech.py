"""The robot's voice: pyttsx3 (espeak-ng) text to speech, or logged text when it cannot speak.

:class:`TextToSpeech` implements :class:`bearchair.hardware.interfaces.Speaker`. Every sentence is
logged (logger ``bearchair.hardware.speech``, level INFO) whether or not it is heard. It speaks
only when it is not muted, pyttsx3 (the optional extra ``bearchair[voice]``) is installed
and starts, and there is an audio device (pyttsx3 2.99 on Linux plays espeak-ng's audio
through ``aplay``); otherwise it falls back to text with one warning (an info line when
muted: the user asked for it). A sentence not heard is printed (``echo``), so the person
who must follow an instruction can read it. pyttsx3's
``runAndWait`` can hang with a broken audio setup, so the engine lives in its own daemon
thread and ``say`` waits for it at most ``timeout_s`` per sentence; after a timeout the
voice falls back to text for good.
"""

from __future__ import annotations

import contextlib
import logging
import os
import queue
import shutil
import subprocess
import sys
import threading
from collections.abc import Callable
from pathlib import Path

logger = logging.getLogger(__name__)

VOICE_HINT = "pip install 'bearchair[voice]' to hear the instructions"


def print_to_stderr(sentence: str) -> None:
    """Where an unheard sentence goes by default: the console, beside the progress lines."""
    # Nobody reads stderr any more (a closed pipe): the log has the sentence.
    with contextlib.suppress(OSError, ValueError):
        print(f'say (text only): "{sentence}"', file=sys.stderr, flush=True)


def audio_device_available() -> bool:
    """True when a sound card or a PulseAudio/PipeWire server, and ``aplay``, are present."""
    if shutil.which("aplay") is None:
        return False
    if Path("/dev/snd").is_dir() and any(Path("/dev/snd").glob("pcm*")):
        return True
    runtime = os.environ.get("XDG_RUNTIME_DIR", "")
    return bool(os.environ.get("PULSE_SERVER")) or (
        bool(runtime) and (Path(runtime) / "pulse" / "native").exists()
    )


class TextToSpeech:
    """Says sentences with pyttsx3 + espeak-ng, or logs them as text.

    Attributes:
        spoken: every sentence passed to :meth:`say`, in order.
        audible: whether sentences are currently being spoken aloud.
    """

    def __init__(
        self,
        *,
        mute: bool = False,
        rate_wpm: int = 150,
        timeout_s: float = 10.0,
        record_dir: Path | None = None,
        echo: Callable[[str], None] | None = print_to_stderr,
    ) -> None:
        """Prepares the voice; never raises for a missing audio setup.

        Args:
            mute: text only, never audio.
            rate_wpm: speaking rate, words per minute.
            timeout_s: longest wait for one spoken sentence, seconds.
            record_dir: when given, each sentence is also saved there as a WAV file by
                ``espeak-ng -w`` (works without an audio device).
            echo: shows a sentence that is not heard (None: only logged).
        """
        self.spoken: list[str] = []
        self._rate_wpm = rate_wpm
        self._timeout_s = timeout_s
        self._record_dir = record_dir
        self._echo = echo
        self._requests: queue.Queue[tuple[str, threading.Event]] = queue.Queue()
        self._worker: threading.Thread | None = None
        self.audible = False
        self._warned = False
        self._failures: list[str] = []
        if mute:
            logger.info("speech: muted; instructions are printed")
        elif not audio_device_available():
            self._fall_back("no audio device (no sound card or PulseAudio server, or no aplay)")
        else:
            self._start_engine()

    def _fall_back(self, why: str) -> None:
        if not self._warned:
            logger.warning("speech: %s; instructions are given as text only", why)
            self._warned = True
        self.audible = False

    def _start_engine(self) -> None:
        started = threading.Event()
        failure = self._failures

        def run() -> None:
            try:
                import pyttsx3
            except ImportError:
                failure.append(f"pyttsx3 is not installed ({VOICE_HINT})")
                started.set()
                return
            try:
                engine = pyttsx3.init()
                engine.setProperty("rate", self._rate_wpm)
            except Exception as error:
                failure.append(f"pyttsx3 failed to start ({error})")
                started.set()
                return
            started.set()
            while True:
                sentence, done = self._requests.get()
                try:
                    engine.say(sentence)
                    engine.runAndWait()
                except Exception as error:
                    logger.debug("pyttsx3 failed: %s", error)
                    failure.append(str(error))
                done.set()

        self._worker = threading.Thread(target=run, name="text-to-speech", daemon=True)
        self._worker.start()
        if not started.wait(self._timeout_s):
            self._fall_back("pyttsx3 did not start in time")
        elif failure:
            self._fall_back(failure[0])
        else:
            self.audible = True

    def say(self, sentence: str) -> None:
        """Logs the sentence and speaks it when audio works; returns within ``timeout_s``."""
        self.spoken.append(sentence)
        logger.info("say: %s", sentence)
        if self._record_dir is not None:
            self._record(self._record_dir, sentence)
        if not self.audible:
            if self._echo is not None:
                self._echo(sentence)
            return
        done = threading.Event()
        self._requests.put((sentence, done))
        if not done.wait(self._timeout_s):
            self._fall_back(f"speaking took longer than {self._timeout_s:.0f} s")
        elif self._failures:
            self._fall_back(f"pyttsx3 failed ({self._failures[-1]})")

    def _record(self, record_dir: Path, sentence: str) -> None:
        espeak = shutil.which("espeak-ng") or shutil.which("espeak")
        if espeak is None:
            return
        record_dir.mkdir(parents=True, exist_ok=True)
        target = record_dir / f"sentence-{len(self.spoken):03d}.wav"
        try:
            subprocess.run(
                [espeak, "-s", str(self._rate_wpm), "-w", str(target), sentence],
                check=True,
                timeout=self._timeout_s,
                capture_output=True,
            )
        except (subprocess.SubprocessError, OSError) as error:
            logger.warning("speech: could not record '%s' (%s)", target.name, error)
