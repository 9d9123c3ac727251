"""The project's own exceptions.

Every error a user can cause (a bad program, a bad config, a bad action) is one of these, so the command
line can print one clear line instead of a traceback.
"""

from __future__ import annotations


class CncGymError(Exception):
    """Base class of every error cnc-gym raises on purpose."""


class ProgramError(CncGymError):
    """A G-code program cannot be run: names file, line (1-based), a stable code and the controller alarm.

    ``str(err)`` is the contract line ``FILE:LINE: message [code]``.
    """

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
        super().__init__(message)
        self.message = message
        self.code = code
        self.file = file
        self.line = line
        self.column = column
        self.alarm = alarm

    def __str__(self) -> str:
        alarm = f" (controller alarm {self.alarm})" if self.alarm is not None else ""
        return f"{self.file}:{self.line}: {self.message}{alarm} [{self.code}]"

    def located(self, file: str, line: int) -> ProgramError:
        """Fill in file and line where the raiser did not know them."""
        if self.file == "<program>":
            self.file = file
        if self.line == 0:
            self.line = line
        return self


class ConfigError(CncGymError):
    """A machine, task or training config is invalid (names the file and the key)."""
