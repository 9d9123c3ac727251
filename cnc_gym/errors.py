"""The project's own exceptions.

Every error a user can cause (a bad program, a bad config, a bad action) is one of these, so the command
line can print one clear line instead of a traceback. ``str()`` of every one of them is safe to print on a
terminal (:func:`printable`): one line, control characters escaped, at most a bounded excerpt of whatever
text the message quotes.
"""

from __future__ import annotations

import re

from cnc_gym import error_codes

#: Most characters of a message that reach the user (a 10 MB program word must not make a 10 MB line).
MAX_MESSAGE_CHARS = 400
#: Most characters of a file name in a ``FILE:LINE:`` prefix.
MAX_FILE_CHARS = 200
#: Most characters of a whole error line (file, line, message, alarm and code fit well within it).
MAX_LINE_CHARS = 1000

# Characters a terminal would act on or hide rather than show: the C0/C1 controls and DEL (ESC starts
# terminal commands), and the Unicode format and separator characters (bidi overrides, zero widths).
_UNPRINTABLE = re.compile(r"[\x00-\x1f\x7f-\x9f\u00ad\u061c\u180e\u200b-\u200f\u2028-\u202e\u2060-\u206f"
                          r"\ufeff\ufff9-\ufffb\U000e0000-\U000e007f]")  # fmt: skip


def printable(text: str, limit: int = MAX_MESSAGE_CHARS) -> str:
    """``text`` made safe to print as (part of) one terminal line.

    Runs of whitespace (newlines included) become one space; other control and invisible format
    characters are written as Python escapes (``\\x1b``, ``\\u202e``); the result is at most ``limit``
    characters, cut with ``…`` and the length of the whole text.
    """
    head = text[: limit + 1]  # only a bounded prefix is ever processed
    out = _UNPRINTABLE.sub(_escape, " ".join(head.split()))
    if len(out) <= limit and len(head) == len(text):
        return out
    more = f"… ({len(text)} characters in all)"
    return out[: max(limit - len(more), 0)] + more


def _escape(match: re.Match) -> str:
    return match.group().encode("unicode_escape").decode("ascii")


def notice_line(file: str, line: int, message: str, code: str, level: str = "note") -> str:
    """A note about a program, one line as an error's: ``FILE:LINE: note: message [code]`` (``level``:
    ``note``, or ``warning`` for what is probably a mistake; ``code``: one of :mod:`cnc_gym.error_codes`)."""
    error_codes.check(code)
    return f"{printable(str(file), MAX_FILE_CHARS)}:{line}: {level}: {printable(message)} [{code}]"


class CncGymError(Exception):
    """Base class of every error cnc-gym raises on purpose. ``str()`` is :func:`printable`."""

    def __str__(self) -> str:
        return printable(super().__str__())


class ProgramError(CncGymError):
    """A G-code program cannot be run: names file, line (1-based), a stable code (one of
    :mod:`cnc_gym.error_codes`) and the controller alarm.

    ``str(err)`` is the contract line ``FILE:LINE: message [code]`` (file and message through
    :func:`printable`); ``err.message`` keeps the message as raised; ``err.notices`` the notes about the
    program made before it stopped (e.g. the warning that explains the error), printed before the error.
    """

    notices: tuple[str, ...] = ()

    def __init__(
        self,
        message: str,
        *,
        code: str,
        file: str = "<program>",
        line: int = 0,
        column: int | None = None,
        alarm: int | None = None,
    ) -> None:
        error_codes.check(code)
        super().__init__(message)
        self.message = message
        self.code = code
        self.file = file
        self.line = line
        self.column = column
        self.alarm = alarm

    def __str__(self) -> str:
        alarm = f" (controller alarm {self.alarm})" if self.alarm is not None else ""
        where = printable(str(self.file), MAX_FILE_CHARS)
        return f"{where}:{self.line}: {printable(self.message)}{alarm} [{self.code}]"

    def located(self, file: str, line: int) -> ProgramError:
        """Fill in file and line where the raiser did not know them."""
        if self.file == "<program>":
            self.file = file
        if self.line == 0:
            self.line = line
        return self


class ConfigError(CncGymError):
    """A machine, task or training config is invalid (names the file and the key)."""
