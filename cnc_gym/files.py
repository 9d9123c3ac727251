"""Reading a file a user names, safely: a regular file, at most a documented size, one bounded read.

Every path cnc-gym reads on a user's word (a G-code program, a subprogram file found in the program's
folder, a YAML config) goes through :func:`read_regular_file`:

* a path that is not a regular file is refused **before it is opened**: a FIFO would block the read
  forever, ``/dev/zero`` or ``/dev/urandom`` never end, a folder cannot be read (``os.stat`` follows
  symbolic links, so a link to a regular file is fine). ``/dev/null``, the empty input, is read as
  empty;
* the file is opened non-blocking and checked again on the open descriptor, so a path swapped for a FIFO
  between the check and the open cannot block either;
* at most ``limit`` bytes are read: a larger file is refused with its size, in one line, before its
  content costs any memory.

Problems are :class:`~cnc_gym.errors.ConfigError` lines that name the path (a missing or unreadable file
stays an ``OSError``, which the command line prints as one line too).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from cnc_gym.errors import ConfigError

#: Largest G-code program file read (64 MiB: about 2.5 million lines of a CAM program, beyond what the
#: default budget of 2 000 000 tool-path segments can run; docs/gcode.md "Limits").
MAX_PROGRAM_BYTES = 64 * 2**20


def _kind(mode: int) -> str:
    """What a file that is not a regular file is, in words."""
    for test, name in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):  # fmt: skip
        if test(mode):
            return name
    return "a special file"


def _size(n: int) -> str:
    return f"{n / 2**20:.1f} MiB" if n >= 2**20 else f"{n / 2**10:.0f} KiB" if n >= 2**10 else f"{n} bytes"


def _is_null_device(info: os.stat_result) -> bool:
    """Whether ``info`` is that of ``/dev/null`` (the empty input every tool accepts: it ends at once)."""
    try:
        null = os.stat(os.devnull)
    except OSError:
        return False
    return stat.S_ISCHR(info.st_mode) and info.st_rdev == null.st_rdev


def _refused(path: str | Path, what: str, mode: int) -> ConfigError:
    return ConfigError(f"{path}: cannot read {what}: it is {_kind(mode)}, not a regular file")


def check_regular_file(path: str | Path, what: str) -> os.stat_result:
    """``os.stat(path)`` when ``path`` is a regular file (following links) or ``/dev/null``; ConfigError
    naming what it is otherwise. A missing file raises FileNotFoundError."""
    info = os.stat(path)
    if not stat.S_ISREG(info.st_mode) and not _is_null_device(info):
        raise _refused(path, what, info.st_mode)
    return info


def read_regular_file(path: str | Path, *, limit: int, what: str = "file") -> bytes:
    """The bytes of the regular file ``path``, at most ``limit`` of them (module docstring).

    ``what`` names the kind of file in messages (``"G-code program"``, ``"machine config"``). Raises
    ConfigError for a path that is not a regular file or a file larger than ``limit``; OSError when the
    file is missing or cannot be read."""
    info = check_regular_file(path, what)
    if info.st_size > limit:
        raise ConfigError(f"{path}: {what} is {_size(info.st_size)}, larger than the limit of {_size(limit)}")
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0))
    try:
        opened = os.fstat(fd)
        if not stat.S_ISREG(opened.st_mode) and not _is_null_device(opened):  # swapped since the check
            raise _refused(path, what, opened.st_mode)
        # One read of the size stat gave (plus one byte, to see a file that grew); more only if the
        # system returns less at a time.
        data = os.read(fd, min(info.st_size, limit) + 1)
        while 0 < len(data) <= limit:
            more = os.read(fd, limit + 1 - len(data))
            if not more:
                break
            data += more
    finally:
        os.close(fd)
    if len(data) > limit:  # the file grew after the check
        raise ConfigError(f"{path}: {what} is larger than the limit of {_size(limit)}")
    return data
