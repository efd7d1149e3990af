"""Scenarios of a HIL test campaign (docs/hil.md, "Scenarios").

A scenario file is read by the C library (gs_hil_scenario_parse), the same
reader the C runner ``gearsim-hil --scenario`` uses, so a file means the same
to both and a bad one is refused with the same line ("FILE:LINE: key: what").
:class:`Scenario` holds the parsed C scenario; ``Bridge(..., scenario=...)``
attaches it; the verdict comes out of the bridge as JUnit XML
(:meth:`gearsim.hil.Bridge.junit`), byte for byte what the C runner writes for
the same frames.
"""

from __future__ import annotations

import os
from os import PathLike
from typing import Any

from .._lib import ffi, lib
from ..errors import InputError

__all__ = ["Scenario", "ScenarioError", "MAX_BYTES"]

#: The largest scenario file read (as the C runner).
MAX_BYTES = 1 << 20


class ScenarioError(InputError):
    """A scenario file that cannot be read or run: the message names the file,
    the line and the key. Bad input: exit status 2."""


class Scenario:
    """A scenario file read against a DBC's frame table and a rig block.

    Args:
        path: the scenario file (TOML subset, docs/hil.md).
        table: the C frame table (``RigDbc.table.dbc``, or a bridge's own).
        block: "simple_gear" or "rack_pinion".
        name: how the file is named in messages and in the verdict (default:
            the path as given).
    """

    def __init__(
        self, path: str | PathLike[str], table: Any, block: str, name: str | None = None
    ) -> None:
        self.path = os.fspath(path)
        shown = self.path if name is None else name
        try:
            with open(self.path, "rb") as fh:
                text = fh.read(MAX_BYTES + 1)
        except OSError as exc:
            raise ScenarioError(f"{shown}: {exc.strerror or exc}", parameter="scenario") from None
        if len(text) > MAX_BYTES:
            raise ScenarioError(f"{shown}: longer than 1 MiB", parameter="scenario")
        self.block = block
        self._text = text
        self._name = ffi.new("char[]", shown.encode("utf-8", "replace"))
        self._c = ffi.new("gs_hil_scenario *")
        err = ffi.new("gs_hil_error *")
        code = lib.GS_RIG_SIMPLE_GEAR if block == "simple_gear" else lib.GS_RIG_RACK_PINION
        if (
            lib.gs_hil_scenario_parse(self._c, text, len(text), self._name, table, code, err)
            != lib.GS_HIL_OK
        ):
            raise ScenarioError(
                ffi.string(err.message).decode("utf-8", "replace"), parameter="scenario"
            )

    @property
    def name(self) -> str:
        return ffi.string(self._c.name).decode("utf-8", "replace")

    @property
    def duration(self) -> float:
        """The scenario's length in seconds of simulated time."""
        return float(self._c.duration_s)

    @property
    def expectations(self) -> int:
        return int(self._c.expect_count)

    @property
    def faults(self) -> int:
        return int(self._c.fault_count)
