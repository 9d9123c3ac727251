"""cnc_gym/files.py: a path a user names is read only when it is a regular file within its size limit, and
every refusal is one line (exit 2 on the command line), never a blocked read or a MemoryError."""

from __future__ import annotations

import os
import threading

import pytest

from cnc_gym.cli import main
from cnc_gym.config import MAX_CONFIG_BYTES, read_yaml
from cnc_gym.errors import ConfigError, ProgramError
from cnc_gym.files import MAX_PROGRAM_BYTES, read_regular_file
from cnc_gym.gcode import interpret_file


def finishes(call, seconds: float = 20.0):
    """Run ``call`` in a thread: it must return or raise within ``seconds`` (a read of a FIFO with no
    writer would block forever). Returns the exception it raised, or None."""
    outcome: list = []

    def run():
        try:
            call()
            outcome.append(None)
        except BaseException as exc:  # handed back to the test
            outcome.append(exc)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(seconds)
    assert not thread.is_alive(), "the read blocked"
    return outcome[0]


@pytest.fixture
def fifo(tmp_path):
    path = tmp_path / "part.nc"
    os.mkfifo(path)
    return path


def test_a_regular_file_and_a_link_to_one_are_read(tmp_path):
    path = tmp_path / "part.nc"
    path.write_bytes(b"G01 X1 F100\n")
    link = tmp_path / "link.nc"
    link.symlink_to(path)
    assert read_regular_file(path, limit=100) == read_regular_file(link, limit=100) == b"G01 X1 F100\n"
    assert read_regular_file(path, limit=12) == b"G01 X1 F100\n"  # exactly at the limit


def test_a_fifo_a_device_and_a_folder_are_refused_before_they_are_opened(tmp_path, fifo):
    for path, kind in ((fifo, "a FIFO"), ("/dev/zero", "a character device"), (tmp_path, "a folder")):
        err = finishes(lambda path=path: read_regular_file(path, limit=MAX_PROGRAM_BYTES, what="program"))
        assert isinstance(err, ConfigError)
        assert str(err).startswith(f"{path}: cannot read program: it is {kind}")
        assert str(err).count("\n") == 0


def test_a_file_over_the_limit_is_refused_by_its_size_without_reading_it(tmp_path):
    big = tmp_path / "big.nc"
    with open(big, "wb") as f:  # sparse: the size is there, the bytes are not
        f.truncate(MAX_PROGRAM_BYTES + 1)
    err = finishes(lambda: interpret_file(big))
    assert isinstance(err, ConfigError) and "larger than the limit of 64.0 MiB" in str(err)
    small = tmp_path / "small.nc"
    small.write_bytes(b"G01 X1 F100\n" * 10)
    with pytest.raises(ConfigError, match="120 bytes, larger than the limit of 100 bytes"):
        read_regular_file(small, limit=100)


def test_dev_null_is_the_empty_file():
    assert read_regular_file("/dev/null", limit=10) == b""


def test_a_missing_file_is_still_an_oserror(tmp_path):
    with pytest.raises(FileNotFoundError):
        read_regular_file(tmp_path / "none.nc", limit=10)


def test_yaml_configs_take_the_same_rule(tmp_path, fifo):
    err = finishes(lambda: read_yaml(fifo, "machine config"))
    assert isinstance(err, ConfigError) and "cannot read machine config: it is a FIFO" in str(err)
    err = finishes(lambda: read_yaml("/dev/zero", "machine config"))
    assert isinstance(err, ConfigError) and "a character device" in str(err)
    big = tmp_path / "big.yaml"
    big.write_text("a: 1\n" + "#" * MAX_CONFIG_BYTES)
    with pytest.raises(ConfigError, match="larger than the limit of 256 KiB"):
        read_yaml(big, "machine config")


@pytest.mark.parametrize("make", ["fifo", "zero", "folder", "big"])
def test_trace_refuses_in_one_line(tmp_path, capsys, make):
    program = {"zero": "/dev/zero", "folder": str(tmp_path)}.get(make, str(tmp_path / "p.nc"))
    if make == "fifo":
        os.mkfifo(program)
    elif make == "big":
        with open(program, "wb") as f:
            f.truncate(MAX_PROGRAM_BYTES + 1)
    status: list[int] = []
    assert finishes(lambda: status.append(main(["trace", program]))) is None
    assert status == [2]
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(program) and "Traceback" not in err


def test_trace_refuses_a_fifo_as_the_machine_config(tmp_path, capsys, fifo):
    program = tmp_path / "ok.nc"
    program.write_text("G01 X1 F100\n")
    machine = tmp_path / "machine.yaml"
    os.mkfifo(machine)
    status: list[int] = []
    assert finishes(lambda: status.append(main(["trace", str(program), "--machine", str(machine)]))) is None
    assert status == [2]
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cannot read machine config: it is a FIFO (named pipe)" in err


def test_a_called_program_that_is_no_regular_file_or_too_big_is_program_not_found(tmp_path):
    main_program = tmp_path / "main.nc"
    main_program.write_text("M98 P1002\nM30\n")
    os.mkfifo(tmp_path / "O1002.nc")  # not a regular file: not a candidate at all
    err = finishes(lambda: interpret_file(main_program))
    assert isinstance(err, ProgramError) and err.code == "program-not-found" and err.line == 1
    os.remove(tmp_path / "O1002.nc")
    with open(tmp_path / "O1002.nc", "wb") as f:
        f.truncate(MAX_PROGRAM_BYTES + 1)
    err = finishes(lambda: interpret_file(main_program))
    assert isinstance(err, ProgramError) and err.code == "program-not-found"
    assert "larger than the limit" in str(err)
    assert str(err).startswith(f"{main_program}:1: ")
