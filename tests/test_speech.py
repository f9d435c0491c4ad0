"""The voice falls back to logged text when muted, without audio, or when pyttsx3 hangs."""

from __future__ import annotations

import logging
import sys
import threading
import time
import types

import pytest

from bearchair.hardware import speech
from bearchair.hardware.interfaces import Speaker
from bearchair.hardware.speech import TextToSpeech

SENTENCE = "Please rotate the chair about the vertical axis clockwise for 90 degrees"


def test_muted_voice_prints_and_logs_text_without_a_warning(
    caplog: pytest.LogCaptureFixture, capsys: pytest.CaptureFixture[str]
) -> None:
    caplog.set_level(logging.INFO, logger="bearchair.hardware.speech")
    voice = TextToSpeech(mute=True)
    assert isinstance(voice, Speaker)
    voice.say(SENTENCE)
    voice.say("second")
    assert not voice.audible
    assert voice.spoken == [SENTENCE, "second"]
    # Muting is what the user asked for: said once at info level, never as a warning.
    assert not [r for r in caplog.records if r.levelno >= logging.WARNING]
    said = [r.getMessage() for r in caplog.records if r.levelno == logging.INFO]
    assert said == ["speech: muted; instructions are printed", f"say: {SENTENCE}", "say: second"]
    # The person who must follow the instruction reads it on the console.
    assert capsys.readouterr().err.splitlines() == [
        f'say (text only): "{SENTENCE}"',
        'say (text only): "second"',
    ]
    shown: list[str] = []
    TextToSpeech(mute=True, echo=shown.append).say(SENTENCE)
    assert shown == [SENTENCE]


def test_no_audio_device_falls_back(monkeypatch: pytest.MonkeyPatch, caplog) -> None:
    monkeypatch.setattr(speech, "audio_device_available", lambda: False)
    voice = TextToSpeech()
    voice.say(SENTENCE)
    assert not voice.audible
    assert any("no audio device" in r.getMessage() for r in caplog.records)


def _fake_pyttsx3(run_and_wait) -> types.ModuleType:
    class Engine:
        def __init__(self) -> None:
            self.said: list[str] = []

        def setProperty(self, name, value) -> None:
            pass

        def say(self, text: str) -> None:
            self.said.append(text)

        def runAndWait(self) -> None:
            run_and_wait()

    module = types.ModuleType("pyttsx3")
    module.init = Engine
    return module


def test_speaks_through_pyttsx3_when_audio_works(monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[float] = []
    monkeypatch.setattr(speech, "audio_device_available", lambda: True)
    monkeypatch.setitem(sys.modules, "pyttsx3", _fake_pyttsx3(lambda: calls.append(time.time())))
    voice = TextToSpeech(timeout_s=2.0)
    voice.say(SENTENCE)
    assert voice.audible and len(calls) == 1


def test_hanging_engine_times_out_and_falls_back(monkeypatch: pytest.MonkeyPatch, caplog) -> None:
    never = threading.Event()
    monkeypatch.setattr(speech, "audio_device_available", lambda: True)
    monkeypatch.setitem(sys.modules, "pyttsx3", _fake_pyttsx3(lambda: never.wait(30.0)))
    voice = TextToSpeech(timeout_s=0.3)
    began = time.perf_counter()
    voice.say(SENTENCE)
    voice.say("next")  # text only now: no second wait
    assert time.perf_counter() - began < 1.5
    assert not voice.audible
    assert sum("text only" in r.getMessage() for r in caplog.records) == 1
    never.set()


def test_broken_engine_falls_back(monkeypatch: pytest.MonkeyPatch) -> None:
    def broken() -> None:
        raise RuntimeError("no driver")

    module = types.ModuleType("pyttsx3")
    module.init = broken
    monkeypatch.setattr(speech, "audio_device_available", lambda: True)
    monkeypatch.setitem(sys.modules, "pyttsx3", module)
    voice = TextToSpeech(timeout_s=1.0)
    voice.say(SENTENCE)
    assert not voice.audible and voice.spoken == [SENTENCE]


def test_without_pyttsx3_the_text_names_the_extra(monkeypatch: pytest.MonkeyPatch, caplog) -> None:
    monkeypatch.setattr(speech, "audio_device_available", lambda: True)
    monkeypatch.setitem(sys.modules, "pyttsx3", None)  # import pyttsx3 raises ImportError
    voice = TextToSpeech(timeout_s=1.0)
    voice.say(SENTENCE)
    assert not voice.audible and voice.spoken == [SENTENCE]
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1 and "bearchair[voice]" in warnings[0]


def test_records_wav_without_audio(tmp_path) -> None:
    if speech.shutil.which("espeak-ng") is None:
        pytest.skip("espeak-ng not installed")
    voice = TextToSpeech(mute=True, record_dir=tmp_path)
    voice.say("hello")
    wavs = list(tmp_path.glob("*.wav"))
    assert len(wavs) == 1 and wavs[0].stat().st_size > 1000
