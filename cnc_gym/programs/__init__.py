"""The built-in program suite and the program loader the env uses.

Built-in programs ship as package data (``cnc_gym/programs/*.nc``, plain GSK 25i G-code written by
``scripts/make_programs.py``):

=========  ===========================================================================================
circle     full circle R 30 mm (G03) at F3000: steady, speed-squared contour error
star       pentagram (G01 only) at F4000: ten sharp corners, +144° at the tips, -72° inside; the
           controller's corner-speed limit, not the override, sets their error
freeform   a 3:2 Lissajous curve in 0.5 mm G01 segments at F2400: small turning angles, the case where
           the feed (not a corner stop) sets the contour error
pocket     a pocket-like spiral of rounded rectangles (G02) with tangent step-over arcs written in G91,
           roughing F3000, finishing loop F2000
=========  ===========================================================================================

:func:`load_program` accepts a built-in name, a path to a program file, or G-code text, and caches the
interpreted :class:`~cnc_gym.toolpath.Toolpath` (interpretation happens once per program and dialect).
"""

from __future__ import annotations

import hashlib
import re
from functools import lru_cache
from pathlib import Path

from cnc_gym.errors import ConfigError
from cnc_gym.machine import MachineConfig
from cnc_gym.toolpath import Toolpath

PROGRAMS_DIR = Path(__file__).resolve().parent

#: Built-in programs in suite order (the env's default program set).
BUILTIN_PROGRAMS: tuple[str, ...] = ("circle", "star", "freeform", "pocket")

# A bare word of two or more letters (``"circel"``) is a mistyped name, not a one-block program.
_NAME_LIKE = re.compile(r"[A-Za-z]{2,}[\w-]*")
_PROGRAM_SUFFIXES = (".nc", ".ngc", ".gcode", ".tap", ".cnc", ".txt")


def program_names() -> list[str]:
    """Names of the built-in programs, in suite order."""
    return list(BUILTIN_PROGRAMS)


def program_path(name: str) -> Path:
    """The package-data file of built-in program ``name``."""
    if name not in BUILTIN_PROGRAMS:
        raise ConfigError(f"unknown built-in program {name!r}; built-ins: {', '.join(BUILTIN_PROGRAMS)}")
    return PROGRAMS_DIR / f"{name}.nc"


def load_program(program: str | Path, dialect: str = "gsk25i",
                 machine: MachineConfig | None = None) -> tuple[str, Toolpath]:  # fmt: skip
    """Interpret a program once and cache it. Returns ``(name, toolpath)``.

    ``program`` is a built-in name (``"circle"`` …), a path to a program file (``str`` or ``Path``), or
    G-code text (anything containing a newline or a G/M word that is not an existing file). The name is
    the built-in name, the file's stem, or ``text-<8 hex digits of its SHA-1>``. Program errors raise
    :class:`~cnc_gym.errors.ProgramError` (``FILE:LINE: message [code]``). With ``machine`` the program may
    move the machine's rotary axes and must stay within its travel (see :func:`cnc_gym.gcode.interpret`).
    """
    key = machine  # machines are frozen and hashable: part of the cache key
    if not isinstance(program, str | Path):
        raise ConfigError(
            f"a program must be a built-in name, a path or G-code text, got {type(program).__name__}"
        )
    if isinstance(program, str) and program in BUILTIN_PROGRAMS:
        return program, _load_file(str(program_path(program)), dialect, 0.0, key)
    if isinstance(program, Path) or _looks_like_path(program):
        path = Path(program)
        if not path.is_file():
            raise ConfigError(f"program file not found: {path}")
        # The modification time is part of the cache key so an edited file is read again.
        return path.stem, _load_file(str(path.resolve()), dialect, path.stat().st_mtime, key)
    if _NAME_LIKE.fullmatch(program):
        raise ConfigError(
            f"unknown program {program!r}: not a built-in ({', '.join(BUILTIN_PROGRAMS)}) nor a file"
        )
    text = program
    digest = hashlib.sha1(text.encode("utf-8")).hexdigest()[:8]
    return f"text-{digest}", _load_text(text, dialect, key)


def _looks_like_path(program: str) -> bool:
    if "\n" in program or "\r" in program:
        return False
    if Path(program).suffix.lower() in _PROGRAM_SUFFIXES or "/" in program or "\\" in program:
        return True
    return Path(program).is_file()


@lru_cache(maxsize=64)
def _load_file(path: str, dialect: str, mtime: float, machine: MachineConfig | None) -> Toolpath:
    from cnc_gym.gcode import interpret_file

    return interpret_file(path, dialect=dialect, machine=machine)


@lru_cache(maxsize=64)
def _load_text(text: str, dialect: str, machine: MachineConfig | None) -> Toolpath:
    from cnc_gym.gcode import interpret

    digest = hashlib.sha1(text.encode("utf-8")).hexdigest()[:8]
    return interpret(text, dialect=dialect, file=f"<text-{digest}>", machine=machine)


__all__ = ["BUILTIN_PROGRAMS", "PROGRAMS_DIR", "load_program", "program_names", "program_path"]
