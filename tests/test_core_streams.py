"""bearchair.core.streams: C-level output inside silenced_fds goes nowhere, output after it arrives."""

from __future__ import annotations

import ctypes
import os

import pytest

from bearchair.core.streams import silenced_fds


def test_a_c_level_write_inside_is_lost_and_one_after_arrives(capfd):
    with silenced_fds(1):
        os.write(1, b"inside\n")
        ctypes.CDLL(None).printf(b"buffered in C\n")
    os.write(1, b"after\n")
    assert capfd.readouterr().out == "after\n"


def test_output_before_the_block_reaches_the_original_file(capfd):
    print("before", end="|", flush=False)
    with silenced_fds(1, 2):
        os.write(2, b"inside\n")
    captured = capfd.readouterr()
    assert captured.out == "before|" and captured.err == ""


def test_a_target_fd_receives_what_was_written(capfd):
    with silenced_fds(1, target_fd=2):
        os.write(1, b"to stderr\n")
    os.write(1, b"to stdout\n")
    captured = capfd.readouterr()
    assert captured.err == "to stderr\n" and captured.out == "to stdout\n"


def test_the_descriptors_come_back_when_the_block_raises(capfd):
    with pytest.raises(RuntimeError), silenced_fds(1):
        raise RuntimeError("inside")
    os.write(1, b"after\n")
    assert capfd.readouterr().out == "after\n"
