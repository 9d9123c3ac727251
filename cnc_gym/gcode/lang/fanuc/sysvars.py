"""System variables of the Fanuc family's Macro B (#1000 and up), read and written through the seam.

The numbering is Fanuc's, as the GSK 25i manual documents it (its table is the same as a Fanuc 0i-M's,
memory C offsets included); the dialect's ``system_variables`` ranges say which exist.

§3.7.3-§3.7.4. Lengths are in the program's input unit (mm, or inch in G20),
like every value a program sees; the interpreter stores mm.

======================  =====  ================================================================
#1000-#1035             R      PLC inputs: no PLC in simulation, so 0
#1100-#1135             R/W    PLC outputs: stored (bits 0/1 for #1100-#1131)
#2001-#2200 / #2201-…   R/W    H wear / geometry 1-200 (compatibility range)
#10001-#13400           R/W    H wear, H geometry, D wear, D geometry 1-400 (offsets.ToolOffsets)
#2500-#2906             R/W    work offsets: #2500 + 100·(axis-1) + k, k = 0 external, 1-6 G54-G59
#3000                   W      0-200: user alarm 3000+n with the block's comment as its message
#3001 / #3002           R/W    ms / hour clocks: the nominal time of the path so far (see below)
#3003                   R/W    0-3 single-block / FIN wait (recorded; 0 at power-on)
#3004                   R/W    0-7: bit 1 locks the feed override (segments OVERRIDE_LOCKED), bit 2
                               disables exact stop (G61's EXACT_STOP flag dropped); bit 0 recorded
#3006                   W      1: message stop (a 0 s exact-stop dwell, like M00)
#3011 / #3012           R      date YYYYMMDD / time HHMMSS when interpretation started
#3901 / #3902           R/W    parts done (M02/M30 add 1) / parts required
#4001-#4022             R      modal G code of group 1-22 (the state before the block: assignments
                               are blocks of their own)
#4107 … #4130           R      last D F H M N O S T and G54.1 P
#5001-#5005             R      block end point, work coordinates, without tool offsets
#5021-#5025             R      machine position (with offsets)
#5041-#5045             R      work position with offsets (machine − work origin)
#5061-#5065             R      G31 skip position (work coordinates), null before any G31
#5081-#5083             R      tool length offset vector in use
#5101-#5105             R      servo position deviation: 0 (the interpreter runs before the servo)
#3020-#3027             R      Haas timers and spindle (a dialect that has them, ``fanuc``): #3020
                               power-on, #3021 cycle start, #3023 present part timer, the nominal
                               seconds so far; #3022 feed timer, those cutting; #3024/#3025 last and
                               previous part, 0; #3026 tool in the spindle; #3027 spindle r/min
#5401-#6000             R      Haas tool life table of tools 1-100 (the ``fanuc`` dialect): #5400+n
                               feed time and #5500+n total time of tool n in seconds (nominal, this
                               run); #5600+n life limit, #5700+n life counter, #5800+n and #5900+n
                               load monitor: 0 (the simulated machine starts with new, unmonitored tools)
======================  =====  ================================================================

The clocks: the interpreter runs before any motion, so #3001/#3002 give the *nominal* time of the path
emitted so far — feed moves at their programmed F, rapids at :data:`NOMINAL_RAPID_MM_MIN`, dwells —
plus whatever the program wrote to them. The 4th and 5th axis positions (#5004, #5024, #5044 …) are the
machine's rotary axes in A, B, C order (degrees; null where the machine has none); their work offsets
(#2800-#2906 4th/5th columns) do not exist here (rotary axes have only the G92 origin).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
import time
from typing import TYPE_CHECKING, NoReturn

from cnc_gym.errors import ProgramError
from cnc_gym.toolpath import SegmentMode

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Seam
    from cnc_gym.gcode.offsets import ToolOffsets

#: Rapid rate for the nominal clock (#3001/#3002), mm/min: the manual's example rate (GSK 25i operation manual
#: §4.1.3).
NOMINAL_RAPID_MM_MIN = 6000.0
_MS_WRAP = 2147483648.0
_HOURS_WRAP = 9544.371767
#: (first, last, table letter, wear?, number offset)
_TOOL_RANGES = (
    (2001, 2200, "H", True, 2000),
    (2201, 2400, "H", False, 2200),
    (10001, 10400, "H", True, 10000),
    (11001, 11400, "H", False, 11000),
    (12001, 12400, "D", True, 12000),
    (13001, 13400, "D", False, 13000),
)
_LAST_VALUE = {
    4107: "D",
    4109: "F",
    4111: "H",
    4113: "M",
    4114: "N",
    4115: "O",
    4119: "S",
    4120: "T",
    4130: "P",
}


class SystemVariables:
    """The system-variable table of one run (module docstring)."""

    def __init__(self, core: Seam) -> None:
        self.core = core
        self.dialect = core.dialect
        self.outputs: dict[int, float] = {}
        self.single_block = 0.0  # #3003
        self.run_control = 0  # #3004
        self.parts_done = 0.0
        self.parts_required = 0.0
        self._clock_rows = 0
        self._clock_s = 0.0
        self._tool_rows = 0
        self._tool_seconds: dict[int, list[float]] = {}  # tool → [in the spindle, cutting], nominal s
        self._ms_offset = 0.0
        self._hours_offset = 0.0
        now = time.localtime()
        self.date = float(now.tm_year * 10000 + now.tm_mon * 100 + now.tm_mday)
        self.time_of_day = float(now.tm_hour * 10000 + now.tm_min * 100 + now.tm_sec)

    def _error(self, message: str, code: str, alarm: str | int | None = None) -> ProgramError:
        return self.dialect.error(message, code, alarm=alarm)

    @property
    def _scale(self) -> float:
        return self.core.state.scale

    # ------------------------------------------------------------------ read
    def read(self, index: int) -> float | None:
        core = self.core
        if 1000 <= index <= 1035:
            return 0.0
        if 1100 <= index <= 1135:
            return self.outputs.get(index, 0.0)
        for low, high, letter, wear, base in _TOOL_RANGES:
            if low <= index <= high:
                number = self._offset_number(index - base)
                return self._tool_offsets().get(letter, number, wear=wear) / self._scale
        if 2500 <= index <= 2906:
            axis, k = self._work_offset(index)
            if axis >= 3:
                return None
            offsets = core.state.offsets
            table = offsets.external if k == 0 else offsets.wcs[k - 1]
            return table[axis] / self._scale
        if index == 3000 or index == 3006:
            raise self._error(f"#{index} can only be written", "read-only-variable")
        if index in (3001, 3002):
            seconds = self._nominal_seconds()
            if index == 3001:
                return math.fmod(seconds * 1000.0 + self._ms_offset, _MS_WRAP)
            return math.fmod(seconds / 3600.0 + self._hours_offset, _HOURS_WRAP)
        if index == 3003:
            return self.single_block
        if index == 3004:
            return float(self.run_control)
        if index == 3011:
            return self.date
        if index == 3012:
            return self.time_of_day
        if index == 3901:
            return self.parts_done
        if index == 3902:
            return self.parts_required
        if 4001 <= index <= 4022:
            key = core.state.modal.get(index - 4000)
            return None if key is None else key / 10.0
        if index in _LAST_VALUE:
            return self._last_value(_LAST_VALUE[index])
        if 5001 <= index <= 5105:
            return self._position(index)
        if 3020 <= index <= 3027:
            return self._haas_timer(index)
        if 5401 <= index <= 6000:
            return self._tool_life(index)
        raise self._error(f"system variable #{index} does not exist", "bad-variable")

    def _haas_timer(self, index: int) -> float:
        """#3020-#3027 (module docstring): the nominal clock of the run, by what it counts."""
        if index in (3020, 3021, 3023):
            return self._nominal_seconds()
        if index == 3022:
            return sum(cutting for _, cutting in self._tools_so_far().values())
        if index in (3024, 3025):
            return 0.0
        if index == 3026:
            return float(self.core.state.tool)
        return abs(self.core.state.spindle_speed) if index == 3027 else self._missing(index)

    def _tool_life(self, index: int) -> float:
        """#5401-#6000 (module docstring): tools 1-100's timers from this run's path; limits, counters and
        load monitoring 0."""
        block, tool = divmod(index - 5401, 100)
        if block >= 2:
            return 0.0
        spindle, cutting = self._tools_so_far().get(tool + 1, (0.0, 0.0))
        return cutting if block == 0 else spindle

    def _tools_so_far(self) -> dict[int, list[float]]:
        builder = self.core.state.builder
        builder.tool_seconds_since(self._tool_rows, NOMINAL_RAPID_MM_MIN, self._tool_seconds)
        self._tool_rows = len(builder)
        return self._tool_seconds

    def _offset_number(self, number: int) -> int:
        count = self._tool_offsets().count
        if number > count:
            raise self._error(f"tool offset {number} does not exist (offsets 1..{count})", "bad-variable")
        return number

    def _tool_offsets(self) -> ToolOffsets:
        return self.core.state.comp.offsets

    def _work_offset(self, index: int) -> tuple[int, int]:
        axis, k = divmod(index - 2500, 100)
        if k > 6:
            raise self._error(
                f"system variable #{index} does not exist (#25k0-#25k6 per axis)", "bad-variable"
            )
        return axis, k

    def _nominal_seconds(self) -> float:
        builder = self.core.state.builder
        self._clock_s = builder.nominal_seconds_since(self._clock_rows, NOMINAL_RAPID_MM_MIN, self._clock_s)
        self._clock_rows = len(builder)
        return self._clock_s

    def _last_value(self, letter: str) -> float | None:
        core = self.core
        if letter == "F":
            st = core.state
            feed = st.feed_programmed if st.feed_per_rev else st.feed
            return None if feed is None else feed / self._scale
        if letter == "S":
            return core.state.spindle_speed
        if letter == "T":
            return float(core.state.tool)
        if letter == "O":
            unit = core.state.flow.frames[-1].unit
            return None if unit.number is None else float(unit.number)
        if letter in "HD":
            # The offset numbers in use live with the tool compensation (compensation.py).
            comp = core.state.comp
            return float(comp.d_number if letter == "D" else comp.h_number)
        if letter == "P":
            return float(core.state.offsets.extra_wcs_number)
        # N and M: the last one in program order up to this block (a scan back through the running unit
        # from the block of the current line; the fast path does not track the program counter).
        runner = core.state.flow
        unit = runner.frames[-1].unit
        line = core.state.out.line
        here = next((i for i in range(unit.start, unit.end) if unit.blocks[i].line == line), runner.pc - 1)
        for i in range(here, unit.start - 1, -1):
            block = unit.blocks[i]
            if letter == "N" and block.number is not None:
                return float(block.number)
            if letter == "M":
                for word in reversed(block.words):
                    if word[0] == "M" and isinstance(word[1], float | str):
                        return float(word[1])  # a literal (plain blocks keep the digits as text)
        return None

    def _position(self, index: int) -> float | None:
        group, axis = divmod(index - 5001, 20)
        core = self.core
        if index >= 5101:
            return 0.0 if index <= 5105 else self._missing(index)
        if axis >= 5:
            return self._missing(index)
        if group == 4:  # #5081-#5085: tool length offset vector
            return core.state.offsets.tool_length[axis] / self._scale if axis < 3 else None
        if axis >= 3:
            # The 4th/5th axis: the machine's rotary axes in A, B, C order (degrees, never scaled).
            rotary = axis - 3
            if rotary >= len(core.state.rotary_axes) or group == 3:
                return None
            machine_deg = core.state.out.rotary[rotary]
            return machine_deg if group == 1 else machine_deg - core.state.rotary_origin[rotary]
        scale = self._scale
        if group == 0:
            return core.program_position[axis] / scale
        machine = core.state.out.position
        if group == 1:
            return machine[axis] / scale
        if group == 2:
            return (machine[axis] - self._work_origin()[axis]) / scale
        if group == 3:
            skip = core.state.skip_position
            return None if skip is None else skip[axis] / scale
        return self._missing(index)

    def _work_origin(self) -> list[float]:
        offsets = self.core.state.offsets
        work = offsets.work_origin()
        return [work[a] + offsets.local[a] for a in range(3)]

    def _missing(self, index: int) -> NoReturn:
        raise self._error(f"system variable #{index} does not exist", "bad-variable")

    # ------------------------------------------------------------------ write
    def write(self, index: int, value: float | None) -> None:
        core = self.core
        if index == 3000:
            self._user_alarm(value)
        if 1100 <= index <= 1135:
            value = 0.0 if value is None else value
            if index <= 1131 and value not in (0.0, 1.0):
                raise self._error(f"#{index} is an output bit: 0 or 1, not {value:g}", "bad-variable")
            self.outputs[index] = value
            return
        for low, high, letter, wear, base in _TOOL_RANGES:
            if low <= index <= high:
                number = self._offset_number(index - base)
                self._tool_offsets().set(
                    letter,
                    number,
                    (value or 0.0) * self._scale,
                    wear=wear,
                    # GSK: alarm 29 ILLEGAL OFFSET VALUE here, 32 "… IN G10" for the G10 form
                    error=lambda message, code: self._error(
                        message, code, "bad-offset-value/variable" if code == "bad-offset-value" else None),
                )
                return
        if 2500 <= index <= 2906:
            axis, k = self._work_offset(index)
            if axis >= 3:
                raise self._error(f"#{index}: the machine has no axis {axis + 1} (XYZ)", "unsupported-axis")
            offsets = core.state.offsets
            table = offsets.external if k == 0 else offsets.wcs[k - 1]
            table[axis] = (value or 0.0) * self._scale
            offsets.update()
            core.resync_program_position()
            return
        if index in (3001, 3002):
            seconds = self._nominal_seconds()
            if index == 3001:
                self._ms_offset = (value or 0.0) - seconds * 1000.0
            else:
                self._hours_offset = (value or 0.0) - seconds / 3600.0
            return
        if index == 3003:
            self.single_block = self._small_int(index, value, 3)
            return
        if index == 3004:
            self.run_control = int(self._small_int(index, value, 7))
            add = SegmentMode.OVERRIDE_LOCKED if self.run_control & 2 else SegmentMode.NONE
            drop = SegmentMode.EXACT_STOP if self.run_control & 4 else SegmentMode.NONE
            core.state.sys_modes = (add, drop)
            core.update_modes()
            return
        if index == 3006:
            if value is None or value == 0:
                return
            core.state.out.dwell(0.0, SegmentMode.EXACT_STOP)
            core.state.stops.append((core.state.out.line, "message_stop"))
            return
        if index in (3901, 3902):
            value = value or 0.0
            if value < 0:
                raise self._error(f"#{index} cannot be negative", "bad-variable")
            if index == 3901:
                self.parts_done = value
            else:
                self.parts_required = value
            return
        if (index in (3011, 3012) or 1000 <= index <= 1035 or 4001 <= index <= 5105 or 3020 <= index <= 3027
                or 5401 <= index <= 6000):  # fmt: skip
            where = self.dialect.cite("§3.7.3")
            raise self._error(f"system variable #{index} is read-only" + (f" ({where})" if where else ""),
                              "read-only-variable")  # fmt: skip
        raise self._error(f"system variable #{index} does not exist", "bad-variable")

    def _small_int(self, index: int, value: float | None, high: int) -> float:
        value = value or 0.0
        if value != int(value) or not 0 <= value <= high:
            raise self._error(f"#{index} takes 0..{high}, not {value:g}", "bad-variable")
        return float(value)

    def _user_alarm(self, value: float | None) -> None:
        number = value or 0.0
        if number != int(number) or not 0 <= number <= 200:
            raise self._error(f"#3000={number:g}: the user alarm number is 0..200 (GSK 25i §3.7.3)",
                              "bad-variable")
        runner = self.core.state.flow
        message = getattr(runner, "message", None) or f"user alarm {int(number)}"
        base = self.dialect.user_alarm_base
        raise self._error(message[:26], "user-alarm", alarm=None if base is None else base + int(number))

    def count_part(self) -> None:
        """M02/M30: one more part done (§4.1.3)."""
        self.parts_done += 1.0

