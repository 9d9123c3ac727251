"""G47 text engraving (Haas mills): the text of the block's comment cut in single strokes.

    G47 P0 (BONES) X2. Y2. I45. J0.5 R0.05 Z-0.005 F15. E10.

* ``P0``: engrave the comment's text; ``P1``: engrave the serial number #599 with as many digits as the
  comment has ``#`` signs (``(####)`` → ``0042``), then add 1 to #599; ``P32``-``P126``: the one ASCII
  character of that code.
* ``X``, ``Y``: the start, the lower left corner of the first character (absolute; default: where the tool
  is); ``I``: the angle of the text line, degrees counter-clockwise (default 0); ``J``: the height of the
  capital letters (default 1 in the unit in force); ``R``: the return plane (absolute Z; default: the Z the
  tool is at); ``Z``: the depth of cut (absolute, below R); ``F``: the engraving feed; ``E``: the plunge
  feed (default F).
* Each stroke: rapid to its start at the return plane, feed down to Z at E, feed along it at F, rapid
  back to R; a stroke that starts where the last one ended continues at depth.

The font is this project's own single-stroke font (:data:`FONT`): capital letters on a 4 × 6 grid
(height 6 = J), digits and ``- . , / : + = _``, characters 6 grid units apart (one J per character); small
letters are engraved as capitals. Haas's own font is not published, so character shapes and spacing are
ours; the moves around them (return plane, plunge feed) are Haas's.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam

Stroke = tuple[tuple[float, float], ...]

_O = ((1, 0), (0, 1), (0, 5), (1, 6), (3, 6), (4, 5), (4, 1), (3, 0), (1, 0))
_P = ((0, 0), (0, 6), (3, 6), (4, 5), (4, 4), (3, 3), (0, 3))
#: Character → strokes (polylines) on a grid 4 wide and 6 high, the baseline at 0.
FONT: dict[str, tuple[Stroke, ...]] = {
    "A": (((0, 0), (2, 6), (4, 0)), ((1, 3), (3, 3))),
    "B": (((0, 0), (0, 6), (3, 6), (4, 5), (4, 4), (3, 3), (0, 3)), ((3, 3), (4, 2), (4, 1), (3, 0), (0, 0))),
    "C": (((4, 5), (3, 6), (1, 6), (0, 5), (0, 1), (1, 0), (3, 0), (4, 1)),),
    "D": (((0, 0), (0, 6), (3, 6), (4, 5), (4, 1), (3, 0), (0, 0)),),
    "E": (((4, 6), (0, 6), (0, 0), (4, 0)), ((0, 3), (3, 3))),
    "F": (((4, 6), (0, 6), (0, 0)), ((0, 3), (3, 3))),
    "G": (((4, 5), (3, 6), (1, 6), (0, 5), (0, 1), (1, 0), (3, 0), (4, 1), (4, 3), (2, 3)),),
    "H": (((0, 0), (0, 6)), ((4, 0), (4, 6)), ((0, 3), (4, 3))),
    "I": (((1, 6), (3, 6)), ((2, 6), (2, 0)), ((1, 0), (3, 0))),
    "J": (((4, 6), (4, 1), (3, 0), (1, 0), (0, 1)),),
    "K": (((0, 0), (0, 6)), ((4, 6), (0, 2)), ((1, 3), (4, 0))),
    "L": (((0, 6), (0, 0), (4, 0)),),
    "M": (((0, 0), (0, 6), (2, 3), (4, 6), (4, 0)),),
    "N": (((0, 0), (0, 6), (4, 0), (4, 6)),),
    "O": (_O,),
    "P": (_P,),
    "Q": (_O, ((2, 2), (4, 0))),
    "R": (_P, ((2, 3), (4, 0))),
    "S": (((4, 5), (3, 6), (1, 6), (0, 5), (0, 4), (1, 3), (3, 3), (4, 2), (4, 1), (3, 0), (1, 0), (0, 1)),),
    "T": (((0, 6), (4, 6)), ((2, 6), (2, 0))),
    "U": (((0, 6), (0, 1), (1, 0), (3, 0), (4, 1), (4, 6)),),
    "V": (((0, 6), (2, 0), (4, 6)),),
    "W": (((0, 6), (1, 0), (2, 3), (3, 0), (4, 6)),),
    "X": (((0, 6), (4, 0)), ((0, 0), (4, 6))),
    "Y": (((0, 6), (2, 3), (4, 6)), ((2, 3), (2, 0))),
    "Z": (((0, 6), (4, 6), (0, 0), (4, 0)),),
    "0": (_O, ((0, 1), (4, 5))),
    "1": (((1, 5), (2, 6), (2, 0)), ((1, 0), (3, 0))),
    "2": (((0, 5), (1, 6), (3, 6), (4, 5), (4, 4), (0, 0), (4, 0)),),
    "3": (((0, 5), (1, 6), (3, 6), (4, 5), (4, 4), (3, 3), (1, 3)),
          ((3, 3), (4, 2), (4, 1), (3, 0), (1, 0), (0, 1))),
    "4": (((3, 0), (3, 6), (0, 2), (4, 2)),),
    "5": (((4, 6), (0, 6), (0, 3), (3, 3), (4, 2), (4, 1), (3, 0), (0, 0)),),
    "6": (((4, 5), (3, 6), (1, 6), (0, 5), (0, 1), (1, 0), (3, 0), (4, 1), (4, 2), (3, 3), (0, 3)),),
    "7": (((0, 6), (4, 6), (1, 0)),),
    "8": (((1, 3), (0, 4), (0, 5), (1, 6), (3, 6), (4, 5), (4, 4), (3, 3), (1, 3), (0, 2), (0, 1), (1, 0),
           (3, 0), (4, 1), (4, 2), (3, 3)),),
    "9": (((4, 3), (1, 3), (0, 4), (0, 5), (1, 6), (3, 6), (4, 5), (4, 1), (3, 0), (1, 0), (0, 1)),),
    "-": (((1, 3), (3, 3)),),
    ".": (((2, 0), (2, 0.5)),),
    ",": (((2, 1), (1.5, -1)),),
    "/": (((0, 0), (4, 6)),),
    ":": (((2, 1), (2, 1.5)), ((2, 4), (2, 4.5))),
    "+": (((2, 1), (2, 5)), ((0, 3), (4, 3))),
    "=": (((0, 2), (4, 2)), ((0, 4), (4, 4))),
    "_": (((0, 0), (4, 0)),),
    " ": (),
}  # fmt: skip
#: Grid height of a capital letter (J) and the distance from one character to the next, grid units.
CAP_HEIGHT = 6.0
ADVANCE = 6.0
#: Most characters one G47 block engraves.
MAX_CHARACTERS = 256
SERIAL_VARIABLE = 599


def text_of(core: Seam, p: float) -> str:
    """The characters a G47 block engraves (module docstring), upper case."""
    comment = core.state.block.comment if core.state.block is not None else None
    if p == 0:
        if not comment:
            raise core.error("G47 P0 engraves the text of the block's comment: G47 P0 (TEXT) X_ Y_ …",
                             "engrave-no-text")  # fmt: skip
        text = comment
    elif p == 1:
        digits = len(comment or "")
        if not comment or comment.strip("#"):
            raise core.error("G47 P1 engraves the serial number #599 in the digits of its comment: (####)",
                             "engrave-no-text")  # fmt: skip
        variables = core.state.variables
        serial = variables.read(SERIAL_VARIABLE) or 0.0
        text = str(int(serial)).zfill(digits)
        variables.write(SERIAL_VARIABLE, float(int(serial) + 1))
    elif p == int(p) and 32 <= p <= 126:
        text = chr(int(p))
    else:
        raise core.error(f"G47 P{p:g}: P is 0 (the comment's text), 1 (the serial number) or an ASCII code "
                         "32-126", "bad-engrave")  # fmt: skip
    text = text.upper()
    if len(text) > MAX_CHARACTERS:
        raise core.error(f"G47: {len(text)} characters; one block engraves at most {MAX_CHARACTERS}",
                         "bad-engrave")  # fmt: skip
    missing = sorted({c for c in text if c not in FONT})
    if missing:
        raise core.error(f"G47: {''.join(missing)!r} not in the engraving font (capital letters, digits, "
                         f"space and {''.join(c for c in FONT if not c.isalnum() and c != ' ')})",
                         "bad-engrave")  # fmt: skip
    return text


def strokes(text: str, height: float, angle_deg: float, origin: tuple[float, float]) -> list[list[tuple]]:
    """The text's strokes as polylines in the plane, scaled to ``height``, turned by ``angle_deg`` about
    ``origin`` (the lower left corner of the first character)."""
    k = height / CAP_HEIGHT
    c, s = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    out = []
    for index, char in enumerate(text):
        for stroke in FONT[char]:
            points = []
            for gx, gy in stroke:
                x, y = (index * ADVANCE + gx) * k, gy * k
                points.append((origin[0] + c * x - s * y, origin[1] + s * x + c * y))
            out.append(points)
    return out


def engrave(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G47``: engrave the text (module docstring), through the coordinate seam (work offsets, tool length
    and the transforms apply as to any move)."""
    st = core.state
    if st.incremental:
        raise core.error("G47 in G91: give the engraving's X, Y, R and Z in absolute (G90)", "bad-engrave")
    if st.comp.side:
        raise core.error("G47 with cutter compensation on: cancel it with G40 first", "bad-engrave")
    if "Z" not in values:
        raise core.error("G47 needs Z, the depth of cut", "missing-value")
    text = text_of(core, values.get("P", 0.0))
    s = st.scale
    here = core.program_position
    origin = (values["X"] * s if "X" in values else here[0], values["Y"] * s if "Y" in values else here[1])
    height = values.get("J", 1.0) * s
    if not height > 0:
        raise core.error(f"G47 J{values['J']:g}: the text height must be positive", "bad-engrave")
    top = values["R"] * s if "R" in values else here[2]
    depth = values["Z"] * s
    if depth >= top:
        raise core.error("G47: the depth Z must be below the return plane R", "bad-engrave")
    feed = st.feed
    if not feed:
        raise core.error("G47 needs a feed: F (the engraving feed)", "missing-feed")
    plunge = values["E"] * s if "E" in values else feed
    if not plunge > 0:
        raise core.error(f"G47 E{values['E']:g}: the plunge feed must be positive", "zero-feed")
    z = here[2]
    if z < top:  # below the return plane: up first, then across
        core.move_linear(True, (None, None, top))
        z = top
    at: tuple[float, float] | None = None  # where the tool is at depth, or None: not at depth
    for stroke in strokes(text, height, values.get("I", 0.0), origin):
        first = stroke[0]
        if at is None or math.dist(at, first) > 1e-9:
            if at is not None:
                core.move_linear(True, (None, None, top))
                z = top
            core.move_linear(True, (first[0], first[1], None))
            if z != top:
                core.move_linear(True, (None, None, top))
            core.move_linear(False, (None, None, depth), feed=plunge)
        for point in stroke[1:]:
            core.move_linear(False, (point[0], point[1], None), feed=feed)
        at, z = stroke[-1], depth
        core.check_budget()
    if at is not None:
        core.move_linear(True, (None, None, top))


ACTIONS = {"engrave": engrave}
