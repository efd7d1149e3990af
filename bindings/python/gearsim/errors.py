"""The gearsim exception tree.

- :class:`GearsimError` is the base of every error the package raises on purpose.
- :class:`ParameterError` (also a :class:`ValueError`): a parameter has an invalid
  value. ``.parameter`` is its program name (docs/physics.md section 9),
  ``.status`` the C status name (``"GS_E_NOT_POSITIVE"``, ...) and ``.file`` the
  model file it was read from, if any.
- :class:`ModelFileError` (also a :class:`ValueError`): a model file or model
  description cannot be read: unreadable file, TOML syntax, unknown key, value of
  the wrong type. ``.file`` and ``.parameter`` (the key) when known.
- A :class:`ParameterError` raised while reading a model file is also a
  :class:`ModelFileError`, so ``except ModelFileError`` catches every problem of a
  file.
- :class:`InputError` (also a :class:`ValueError`): bad per-step or batch inputs
  (missing driving input, shape mismatch, non-finite value).

Warnings: :class:`SubstepWarning` (a :class:`UserWarning`): a rig with backlash
whose automatic contact sub-step count stopped at its cap while the contact is
still under-resolved (h*omega_n above gearsim.AUTO_H_OMEGA_N_MAX).
"""

from __future__ import annotations

import os
import sys
from os import PathLike
from typing import Any

__all__ = [
    "GearsimError",
    "ParameterError",
    "ModelFileError",
    "InputError",
    "SubstepWarning",
    "caller_stacklevel",
]


class GearsimError(Exception):
    """Base class of the gearsim errors.

    Attributes:
        parameter: program name of the parameter (or model key) at fault, or None.
        status: name of the C status (``"GS_E_..."``), or None.
        file: the model file involved, or None.
    """

    def __init__(
        self,
        message: str,
        *,
        parameter: str | None = None,
        status: str | None = None,
        file: str | PathLike[str] | None = None,
    ) -> None:
        self.parameter = parameter
        self.status = status
        self.file = None if file is None else str(file)
        self.detail = message
        super().__init__(self._format())

    def _format(self) -> str:
        text = self.detail
        if self.parameter and not text.startswith(self.parameter):
            text = f"{self.parameter}: {text}"
        if self.file:
            text = f"{self.file}: {text}"
        return text

    def __reduce__(self) -> tuple[Any, ...]:
        return (
            _rebuild,
            (type(self), self.detail, self.parameter, self.status, self.file),
        )


def _rebuild(
    cls: type[GearsimError],
    message: str,
    parameter: str | None,
    status: str | None,
    file: str | None,
) -> GearsimError:
    return cls(message, parameter=parameter, status=status, file=file)


class ParameterError(GearsimError, ValueError):
    """A parameter value is invalid; the message names the parameter (and file)."""


class ModelFileError(GearsimError, ValueError):
    """A model file or model description is malformed (unknown key, wrong type,
    unreadable file, TOML syntax)."""


class _FileParameterError(ParameterError, ModelFileError):
    """A ParameterError raised while reading a model file."""


class InputError(GearsimError, ValueError):
    """Invalid inputs to Rig.step / Rig.run."""


def with_file(err: GearsimError, file: str | PathLike[str] | None) -> GearsimError:
    """Return err with its .file set (re-typed so that a ParameterError read
    from a file is also a ModelFileError)."""
    if file is None:
        return err
    cls: type[GearsimError] = type(err)
    if cls is ParameterError:
        cls = _FileParameterError
    return cls(err.detail, parameter=err.parameter, status=err.status, file=file)


class SubstepWarning(UserWarning):
    """The automatic contact sub-step count of a backlash rig stopped at its cap
    (16) with h*omega_n still above its target (``AUTO_H_OMEGA_N_MAX``): the
    contact is stable (backward Euler) but numerically over-damped, so rebounds
    come out too soft. Lower ``dt``, or set ``contact_substeps`` (up to 64), or
    soften the contact."""


_PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__))


def caller_stacklevel() -> int:
    """warnings.warn's stacklevel of the first frame outside the gearsim
    package, so that a warning points at the user's line however deep in
    gearsim it was raised."""
    frame = sys._getframe(1)
    level = 1
    while frame is not None and frame.f_code.co_filename.startswith(_PACKAGE_DIR):
        frame = frame.f_back
        level += 1
    return level
