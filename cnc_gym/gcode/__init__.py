"""Stage 1 of the pipeline: the G-code interpreter (program text → canonical tool path).

    toolpath = interpret(text, dialect="gsk25i", file="part.nc")
    toolpath = interpret_file("part.nc")

Read (the dialect's lexer, ``lang/fanuc/reader.py`` for the Fanuc family) → check and execute (the core,
:mod:`~cnc_gym.gcode.interpreter`, with the dialect's actions and hooks) → canonical output
(:mod:`~cnc_gym.gcode.canonical`) → :class:`~cnc_gym.toolpath.Toolpath`. A dialect is a folder of tables
and hooks (:mod:`cnc_gym.gcode.dialects`) on a language family (:mod:`cnc_gym.gcode.lang`); the contract
between them and the core is :mod:`~cnc_gym.gcode.dialect`. See docs/gcode.md and docs/dialects.md.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import gc
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from cnc_gym.defaults import INPUT_UNITS
from cnc_gym.errors import ConfigError, ProgramError
from cnc_gym.files import MAX_PROGRAM_BYTES, read_regular_file
from cnc_gym.gcode.dialect import DEFAULT_DIALECT, DIALECT_MODULES, Dialect, get_dialect
from cnc_gym.gcode.dialect import calculator_input as calculator_dialect
from cnc_gym.gcode.interpreter import Interpreter
from cnc_gym.gcode.program import Program
from cnc_gym.gcode.settings import (
    DEFAULT_MAX_BLOCKS,
    DEFAULT_MAX_SECONDS,
    DEFAULT_MAX_SEGMENTS,
    FlowOptions,
    MacroCalls,
)

if TYPE_CHECKING:
    from cnc_gym.machine import MachineConfig, SetupConfig
    from cnc_gym.toolpath import Toolpath

__all__ = ["DIALECT_MODULES", "Dialect", "Interpreter", "Program", "get_dialect", "interpret",
           "interpret_file", "read_program"]  # fmt: skip


def _skip_switches(block_skip) -> frozenset[int]:
    switches = frozenset(block_skip)
    bad = sorted(n for n in switches if not (isinstance(n, int) and 1 <= n <= 9))
    if bad:
        raise ConfigError(f"block-skip switches are 1..9, got {bad}")
    return switches


def read_program(text: str, *, dialect: str | Dialect = DEFAULT_DIALECT, file: str = "<program>") -> Program:
    """Read phase only: text → blocks (syntax errors raise ProgramError)."""
    spec = get_dialect(dialect)
    return spec.language.reader(spec, None).read(text, file)


def interpret(
    text: str,
    *,
    dialect: str | Dialect = DEFAULT_DIALECT,
    file: str = "<program>",
    machine: MachineConfig | None = None,
    block_skip: frozenset[int] = frozenset(),
    max_blocks: int = DEFAULT_MAX_BLOCKS,
    max_seconds: float = DEFAULT_MAX_SECONDS,
    max_segments: int = DEFAULT_MAX_SEGMENTS,
    program_dir: str | Path | None = None,
    follow_links: bool = False,
    macro_calls: MacroCalls | dict | None = None,
    main_m99: str = "end",
    tool_offsets=None,
    tool_measurement=None,
    skip_signal=None,
    units: str | None = None,
    setup=None,
    calculator_input: bool | None = None,
) -> Toolpath:
    """Interpret a whole program once into an immutable Toolpath (machine coordinates, mm, mm/min, s).

    ``max_blocks``: bound on executed blocks (a runaway macro loop raises ``too-many-blocks``);
    ``max_seconds``: bound on the CPU seconds of the interpretation (``time-budget``); ``max_segments``:
    bound on the tool path's segments (``segment-budget``). The defaults (2 000 000 blocks, 60 s,
    2 000 000 segments) are far above real programs; raise them for a really long one.
    ``program_dir``: where M98/G65 look for programs not in the text (files ``O1002``, ``O1002.nc``,
    ``1002.nc``); default the folder of ``file`` when that is a real file. A called program's file that leads
    out of that folder (a symbolic link to elsewhere) is ``program-not-found`` unless ``follow_links``.
    ``macro_calls``: G/M/T codes that call programs (GSK parameters 6050-6089, 6001#0), as a
    :class:`~cnc_gym.gcode.dialect.MacroCalls` or ``{"g_macro": {12: 9010}, "m_macro": {…},
    "m_sub": {6: 9001}, "t_sub": 9000}``; default the dialect's (GSK: none, the parameters' standard setting).
    ``main_m99``: ``"end"`` (M99 in the main program ends the run after one pass) or ``"restart"``.
    ``tool_offsets``: initial tool offset memory (mm), ``{"H": {1: 20.0}, "D": {7: 5.0}, "H_wear": {…},
    "D_wear": {…}}`` or a :class:`~cnc_gym.gcode.offsets.ToolOffsets`; default all zero (G10 L10-L13 and
    #2001…/#10001… set them from the program).

    ``tool_measurement``: G37's simulated measuring instrument and parameters, a
    :class:`~cnc_gym.gcode.settings.ToolMeasurement` or ``{"signal_at": {1: 198.0}, "decel_mm": 10,
    "band_mm": 5}`` (H number → work coordinate where the approach-end signal comes; default: exactly at
    the commanded position, with the manual's standard P2651-P2653).
    ``skip_signal``: G31's simulated probe, ``{"Z": -5.0}``: a G31 move stops where it first reaches one of
    these program coordinates (mm); default none (every G31 move completes).
    ``block_skip``: the optional-block-skip switches that are ON (1..9; ``/`` alone is switch 1).
    ``machine``: when given, the path (line ends, arc extremes) must stay within the axes' travel.
    ``units``: the input unit in force at power-on, ``"mm"`` or ``"inch"`` (the controller parameter a
    machine sets; shop programs for inch machines often carry no G20); the program's own G20/G21 still
    rules. Default: ``machine``'s ``power_on_units`` when it sets one, else the dialect's power-on code
    (G21 on every built-in dialect; Syntec's G71).
    ``setup``: the operator's tables at power-on, a setup file's path, its data (``{"work_offsets": {"G54":
    [100, 50, -200]}, "tools": {1: {"length_mm": 120, "radius_mm": 5}}}``) or a
    :class:`~cnc_gym.machine.SetupConfig`, on top of ``machine``'s ``setup`` section (docs/configs.md
    "Setup"); ``tool_offsets`` entries go on top of both. G10 still changes the tables at run time.
    ``calculator_input``: True reads a number without a decimal point in mm, inch or seconds where the
    dialect reads least increments (Fanuc parameter 3401#0 DPI = 1;
    :func:`~cnc_gym.gcode.dialect.calculator_input`; a dialect without the setting is a ConfigError);
    None: ``machine``'s ``calculator_input``, else the dialect's standard reading.
    Every program error raises :class:`~cnc_gym.errors.ProgramError` (``FILE:LINE: message [code]``).
    """
    spec = get_dialect(dialect)
    if calculator_input is None and machine is not None:
        calculator_input = machine.calculator_input
    if calculator_input:
        spec = calculator_dialect(spec)
    switches = _skip_switches(block_skip)
    # The cyclic garbage collector would otherwise rescan the growing list of blocks and segment rows
    # again and again (no cycles are created here): pausing it makes a 100 000-line program several
    # times faster to interpret.
    collecting = gc.isenabled()
    gc.disable()
    try:
        calls = _macro_calls(macro_calls, spec)
        if main_m99 not in ("end", "restart"):
            raise ConfigError(f"main_m99 must be 'end' or 'restart', got {main_m99!r}")
        for name, value in (("max_blocks", max_blocks), ("max_segments", max_segments)):
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
                raise ConfigError(f"{name} must be a positive integer, got {value!r}")
        if isinstance(max_seconds, bool) or not isinstance(max_seconds, int | float) or not max_seconds > 0:
            raise ConfigError(f"max_seconds must be a positive number of seconds, got {max_seconds!r}")
        folder = None if program_dir is None else str(program_dir)
        options = FlowOptions(max_blocks=int(max_blocks), max_seconds=float(max_seconds),
                              max_segments=int(max_segments), program_dir=folder, macro_calls=calls,
                              main_m99=main_m99, follow_links=bool(follow_links))  # fmt: skip
        if units is not None and units not in INPUT_UNITS:
            raise ConfigError(f"units must be 'mm' or 'inch', got {units!r}")
        tables = _setup(machine, setup)
        reader = spec.language.reader(spec, calls)
        reader.max_blocks = int(max_blocks)  # a text of more blocks than a run may execute: refused as read
        program = reader.read(text, file)
        toolpath = Interpreter(program, spec, block_skip=switches, machine=machine, tool_offsets=tool_offsets,
                               tool_measurement=tool_measurement, skip_signal=skip_signal,
                               units=units, setup=tables).run(options)  # fmt: skip
    finally:
        if collecting:
            gc.enable()
    if machine is not None:
        _check_travel(toolpath, machine, spec)
    return toolpath


def _setup(machine: MachineConfig | None, setup) -> SetupConfig | None:
    """The setup of a run: the machine preset's section with ``setup=`` on top (None: none at all)."""
    if machine is None and setup is None:
        return None  # (the machine records not even loaded: a trace without a preset)
    from cnc_gym.machine import load_setup, merge_setups

    given = None if setup is None else load_setup(setup)
    if machine is None:
        return given
    return merge_setups(machine.setup, given)


def interpret_file(
    path: str | Path,
    *,
    dialect: str | Dialect = DEFAULT_DIALECT,
    machine: MachineConfig | None = None,
    block_skip: frozenset[int] = frozenset(),
    **options,
) -> Toolpath:
    """Interpret a program file (errors name the path). A path that is not a regular file, or a file over
    :data:`~cnc_gym.files.MAX_PROGRAM_BYTES` (64 MiB), is a ConfigError before anything is read
    (:func:`~cnc_gym.files.read_regular_file`); a missing or unreadable file raises OSError.

    ``options``: as :func:`interpret` (``max_blocks``, ``max_seconds``, ``max_segments``, ``program_dir``
    — default the file's folder —, ``macro_calls``, ``main_m99``, ``tool_offsets``, ``units`` …).
    """
    path = Path(path)
    raw = read_regular_file(path, limit=MAX_PROGRAM_BYTES, what="G-code program")
    try:
        text = raw.decode("utf-8-sig")  # a byte-order mark, if any, is not part of the program
    except UnicodeDecodeError:
        text = raw.decode("latin-1")  # controller files are often 8-bit ISO text
    return interpret(text, dialect=dialect, file=str(path), machine=machine, block_skip=block_skip, **options)


def _macro_calls(value: MacroCalls | dict | None, dialect: Dialect) -> MacroCalls:
    """``macro_calls=`` → MacroCalls, checked (ConfigError): G 1-255 but not G00/G65/G66/G67, M 1-255 but
    not the stop/call codes, at most 10 of each kind (§3.7.6), programs 1-9999."""
    if value is None:
        return dialect.macro_calls
    if isinstance(value, MacroCalls):
        calls = value
    elif isinstance(value, dict):
        unknown = set(value) - {"g_macro", "m_macro", "m_sub", "t_sub"}
        if unknown:
            raise ConfigError(f"macro_calls: unknown keys {sorted(unknown)} (g_macro, m_macro, m_sub, t_sub)")
        try:
            calls = MacroCalls(**{k: (dict(v) if k != "t_sub" else v) for k, v in value.items()})  # type: ignore[arg-type]
        except (TypeError, ValueError) as exc:
            raise ConfigError(f"macro_calls: {exc}") from None
    else:
        raise ConfigError(f"macro_calls must be a MacroCalls or a dict, got {type(value).__name__}")

    def program(number, what):
        if isinstance(number, bool) or not isinstance(number, int) or not 1 <= number <= 9999:
            raise ConfigError(f"macro_calls[{what}]: program number {number!r} is not 1..9999")

    reserved = _reserved_codes(dialect)
    for kind in ("g_macro", "m_macro", "m_sub"):
        table = getattr(calls, kind)
        if len(table) > 10:
            raise ConfigError(f"macro_calls[{kind}]: at most 10 codes (parameters 6050-6059 / 6071-6089)")
        for code, number in table.items():
            bad = isinstance(code, bool) or not isinstance(code, int) or not 1 <= code <= 255
            if bad or code in reserved[kind]:
                raise ConfigError(f"macro_calls[{kind}]: code {code!r} cannot call a program (1..255, not "
                                  f"{sorted(reserved[kind])})")  # fmt: skip
            program(number, kind)
    both = set(calls.m_macro) & set(calls.m_sub)
    if both:
        raise ConfigError(f"macro_calls: M{sorted(both)[0]} is both a macro and a subprogram call")
    if calls.t_sub is not None:
        program(calls.t_sub, "t_sub")
    return calls


def _reserved_codes(dialect: Dialect) -> dict[str, set[int]]:
    """Codes that cannot call a program: G00 and the macro-call codes (G65-G67); the stop and call M codes
    (M00-M02, M30, M98, M99, the Haas M97). Found in the dialect's tables by action."""
    g_codes = {key // 10 for key, spec in dialect.gcodes.items() if key % 10 == 0 and (
        spec.action in ("macro_call", "modal_call_cancel") or (spec.action == "motion" and spec.value == 0))}
    calls = ("stop", "subprogram_call", "subprogram_return", "local_subprogram_call")
    m_codes = {key // 10 for key, spec in dialect.mcodes.items() if spec.action in calls}
    return {"g_macro": g_codes, "m_macro": m_codes, "m_sub": m_codes}


def _check_travel(toolpath: Toolpath, machine: MachineConfig, dialect: Dialect) -> None:
    """Stored stroke check: every point of the path within each axis's [min, max] travel.

    Lines are checked at their ends; arcs also at the axis extremes their sweep passes (0°, 90°, 180°,
    270° in the plane). The first offending segment is reported as "OVER TRAVEL:+n" beyond the + side,
    "OVER TRAVEL:-n" beyond the − side (n = the axis number), with the dialect's stored stroke limit 1
    alarm, conditions ``travel-limit/+`` and ``travel-limit/-`` (GSK 25i operation manual §2.5.4: 500
    and 501; Fanuc OT500/OT501; none where the dialect's list has no number).
    """
    n = len(toolpath)
    if not n:
        return
    low = np.array(machine.axis_array("min_position_mm"))
    high = np.array(machine.axis_array("max_position_mm"))
    first = None
    for index, points in toolpath.extreme_points():
        outside = (points < low) | (points > high)
        if outside.any():
            k, axis = np.argwhere(outside)[0]
            row = int(index[k])
            if first is None or row < first[0]:
                first = (row, int(axis), float(points[k, axis]))
    if first is not None:
        row, axis, value = first
        file, line = toolpath.source(row)
        name = "XYZ"[axis]
        side = "+" if value > high[axis] else "-"
        raise ProgramError(f"OVER TRAVEL:{side}{axis + 1}: {name}{value:.4f} (machine) is beyond the travel "
                           f"limit {low[axis]:g} .. {high[axis]:g} of machine {machine.name}",
                           code="travel-limit", file=file, line=line,
                           alarm=dialect.alarm("travel-limit", f"travel-limit/{side}"))  # fmt: skip
