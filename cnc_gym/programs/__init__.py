r"""The built-in program suite and the program loader the env uses.

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

What a program argument may be (``load_program``, the env's ``programs=``, ``cnc-gym run/trace
PROGRAM``) — one rule, :func:`resolve_program`:

=======================  ===================================================================================
``Path``, ``PathLike``   a program file (it must exist and not be a folder; ``/dev/null``: an empty program)
:class:`ProgramText`     G-code text, never taken for a name or a path
:class:`Program`         an already interpreted program (what :func:`load_program` returns), used as is
``str``                  in this order: a built-in name; G-code text if it has a line break; a file if it
                         names an existing one or ends in ``.nc .ngc .gcode .tap .cnc .txt``; an error if it
                         looks like a name or a path (only letters, digits and ``_ . - / \ ~ :``, with two
                         letters in a row, e.g. ``circel`` or ``parts/bracket``); else one line of G-code text
                         (``G01 X10 F100``, ``F1/80``, ``/G00 X5`` with its block skip)
=======================  ===================================================================================

Interpretation is cached (once per program, dialect, machine and block budget; a file's modification
time is part of the key, so an edited file is read again).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Literal, NamedTuple

from cnc_gym.errors import ConfigError
from cnc_gym.gcode.dialect import DEFAULT_DIALECT
from cnc_gym.gcode.settings import DEFAULT_MAX_BLOCKS
from cnc_gym.toolpath import Toolpath

if TYPE_CHECKING:
    from cnc_gym.machine import MachineConfig

PROGRAMS_DIR = Path(__file__).resolve().parent

#: Built-in programs in suite order (the env's default program set).
BUILTIN_PROGRAMS: tuple[str, ...] = ("circle", "star", "freeform", "pocket")

#: File name endings that make a one-line string a path even when no such file exists (then: not found).
PROGRAM_SUFFIXES = (".nc", ".ngc", ".gcode", ".tap", ".cnc", ".txt")

# A one-line string made of name/path characters with two letters in a row (``circel``, ``parts/bracket``)
# is a mistyped name or a missing file, not a block of G-code (addresses are single letters).
_NAME_OR_PATH = re.compile(r"[\w.~:/\\-]*[A-Za-z]{2}[\w.~:/\\-]*")


@dataclass(frozen=True)
class ProgramText:
    """G-code text, taken as text whatever it looks like; ``name`` defaults to ``text-<8 hex of SHA-1>``."""

    text: str
    name: str | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.text, str):
            raise ConfigError(f"ProgramText needs a str, got {type(self.text).__name__}")
        if self.name is not None and not (isinstance(self.name, str) and self.name.strip()):
            raise ConfigError(f"ProgramText name must be a non-empty str, got {self.name!r}")


class Program(NamedTuple):
    """An interpreted program: its name (built-in name, file stem or text name) and its tool path."""

    name: str
    toolpath: Toolpath


#: Everything a program argument may be (see the module docstring for the rule).
ProgramLike = str | os.PathLike | ProgramText | Program
PROGRAM_TYPES = (str, os.PathLike, ProgramText, Program)


@dataclass(frozen=True)
class ProgramSource:
    """Where a program comes from, once :func:`resolve_program` has applied the rule."""

    kind: Literal["builtin", "file", "text"]
    name: str
    path: Path | None = None  # builtin and file (None for text)
    text: str | None = None  # text (None for builtin and file)


def program_names() -> list[str]:
    """Names of the built-in programs, in suite order."""
    return list(BUILTIN_PROGRAMS)


def program_path(name: str) -> Path:
    """The package-data file of built-in program ``name``."""
    if name not in BUILTIN_PROGRAMS:
        raise ConfigError(f"unknown built-in program {name!r}; built-ins: {', '.join(BUILTIN_PROGRAMS)}")
    return PROGRAMS_DIR / f"{name}.nc"


def resolve_program(program: str | os.PathLike | ProgramText) -> ProgramSource:
    """Apply the rule of the module docstring: a built-in, a file or text. Raises ConfigError otherwise."""
    if isinstance(program, ProgramText):
        return ProgramSource("text", program.name or _text_name(program.text), text=program.text)
    if isinstance(program, os.PathLike):
        return _file_source(Path(program))
    if not isinstance(program, str):
        raise ConfigError(
            "a program must be a built-in name, a path, G-code text or a ProgramText, "
            f"got {type(program).__name__}"
        )
    if program in BUILTIN_PROGRAMS:
        return ProgramSource("builtin", program, path=program_path(program))
    if "\n" in program or "\r" in program:
        return ProgramSource("text", _text_name(program), text=program)
    if _exists(program) or Path(program).suffix.lower() in PROGRAM_SUFFIXES:
        return _file_source(Path(program))
    if _NAME_OR_PATH.fullmatch(program):
        raise ConfigError(
            f"unknown program {_excerpt(program)}: not a built-in ({', '.join(BUILTIN_PROGRAMS)}) "
            "nor an existing file (pass G-code text as ProgramText)"
        )
    return ProgramSource("text", _text_name(program), text=program)


def load_program(program: ProgramLike, dialect: str = DEFAULT_DIALECT,
                 machine: MachineConfig | None = None, *,
                 max_blocks: int = DEFAULT_MAX_BLOCKS, units: str | None = None) -> Program:  # fmt: skip
    """Interpret a program once and cache it. Returns :class:`Program` ``(name, toolpath)``.

    ``program`` follows the rule of the module docstring; the name is the built-in name, the file's stem,
    or the text's name. Program errors raise :class:`~cnc_gym.errors.ProgramError` (``FILE:LINE: message
    [code]``). With ``machine`` the program may move the machine's rotary axes and must stay within its
    travel (see :func:`cnc_gym.gcode.interpret`). ``max_blocks`` bounds the executed blocks (a runaway
    loop ends in ``too-many-blocks``). ``units``: the input unit at power-on, ``"mm"`` or ``"inch"``
    (default: the machine's ``power_on_units``, else the dialect's; see :func:`cnc_gym.gcode.interpret`).
    A :class:`Program` is returned as it is.
    """
    if isinstance(program, Program):
        return program
    source = resolve_program(program)
    key = machine  # machines are frozen and hashable: part of the cache key
    if source.path is None:  # text
        return Program(source.name, _load_text(source.text or "", source.name, dialect, key, max_blocks,
                                               units))  # fmt: skip
    # The modification time is part of the cache key so an edited file is read again.
    mtime = 0.0 if source.kind == "builtin" else source.path.stat().st_mtime
    return Program(source.name, _load_file(str(source.path.resolve()), dialect, mtime, key, max_blocks,
                                           units))  # fmt: skip


def _file_source(path: Path) -> ProgramSource:
    if not _exists(path):
        raise ConfigError(f"program file not found: {path}")
    if path.is_dir():
        raise ConfigError(f"{path}: is a folder, not a program file")
    return ProgramSource("file", path.stem or path.name, path=path)


def _exists(path: str | Path) -> bool:
    """Whether ``path`` names something (a file, ``/dev/null``, a pipe); a string too long or with a NUL
    byte to be a path is not one."""
    try:
        return Path(path).exists()
    except (OSError, ValueError):
        return False


def _excerpt(text: str, limit: int = 60) -> str:
    """``repr`` of at most ``limit`` characters of ``text`` (error lines stay short and printable)."""
    return repr(text) if len(text) <= limit else repr(text[:limit]) + f"… ({len(text)} characters)"


def _text_name(text: str) -> str:
    import hashlib  # here, not at the top: `cnc-gym trace` of a file never names a text

    return f"text-{hashlib.sha1(text.encode('utf-8', 'surrogatepass')).hexdigest()[:8]}"


@lru_cache(maxsize=64)
def _load_file(path: str, dialect: str, mtime: float, machine: MachineConfig | None,
               max_blocks: int, units: str | None) -> Toolpath:  # fmt: skip
    from cnc_gym.gcode import interpret_file

    return interpret_file(path, dialect=dialect, machine=machine, max_blocks=max_blocks, units=units)


@lru_cache(maxsize=64)
def _load_text(text: str, name: str, dialect: str, machine: MachineConfig | None,
               max_blocks: int, units: str | None) -> Toolpath:  # fmt: skip
    from cnc_gym.gcode import interpret

    return interpret(text, dialect=dialect, file=f"<{name}>", machine=machine, max_blocks=max_blocks,
                     units=units)  # fmt: skip


__all__ = [
    "BUILTIN_PROGRAMS",
    "DEFAULT_DIALECT",
    "PROGRAMS_DIR",
    "PROGRAM_SUFFIXES",
    "PROGRAM_TYPES",
    "Program",
    "ProgramLike",
    "ProgramSource",
    "ProgramText",
    "load_program",
    "program_names",
    "program_path",
    "resolve_program",
]
