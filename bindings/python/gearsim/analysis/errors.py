"""Errors of the analysis layer.

Both are :class:`gearsim.GearsimError` and :class:`ValueError`, so the command
line turns them into exit status 2 with their one-line message.

- :class:`MeasurementError`: a measurement file cannot be used (missing file,
  missing or non-numeric column, non-finite value, time not increasing,
  sampling that cannot be made uniform). ``.file``, ``.line`` (1-based line of
  the file) and ``.column`` locate the fault when known.
- :class:`EffectError`: an effect name is unknown, does not apply to the rig,
  or the model already has it. ``.parameter`` is the effect name.
"""

from __future__ import annotations

from os import PathLike

from ..errors import GearsimError

__all__ = ["MeasurementError", "EffectError", "AnalysisError"]


class AnalysisError(GearsimError):
    """An analysis step failed for a reason other than bad input (exit 1)."""


class MeasurementError(GearsimError, ValueError):
    """A measurement file is unusable; the message names the file, line and column."""

    def __init__(
        self,
        message: str,
        *,
        file: str | PathLike[str] | None = None,
        line: int | None = None,
        column: str | None = None,
    ) -> None:
        self.line = line
        self.column = column
        super().__init__(message, parameter=column, file=file)

    def _format(self) -> str:
        where = []
        if self.file:
            where.append(str(self.file))
        if self.line is not None:
            where.append(f"line {self.line}")
        if self.column is not None:
            where.append(f"column '{self.column}'")
        return (", ".join(where) + ": " if where else "") + self.detail


class EffectError(GearsimError, ValueError):
    """An effect name is unknown or not applicable to the model."""

    def _format(self) -> str:
        return self.detail
