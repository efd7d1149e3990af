"""gearsim.hil: the HIL bridge on CAN (docs/hil.md).

A gearsim rig behind a python-can bus, described by a DBC file that cantools
encodes and decodes:

    import can, gearsim
    from gearsim.hil import Bridge

    model = gearsim.Model.load("model.toml")
    with can.Bus(interface="socketcan", channel="can0") as bus:
        bridge = Bridge.from_model(model, period=1e-3, substeps=1, timeout=0.1, bus=bus)
        bridge.run()           # paced by the wall clock; tick() / advance(n) never sleep
        print(bridge.close())  # counters

- :class:`RigDbc` (codec): the DBC, with the roles of its signals; range-checked
  decoding of commands, saturating encoding of feedback.
- :class:`Bridge`: frame periods of ``substeps`` rig steps; held commands,
  command timeout and safe state, feedback at the DBC cycle times, counters.
  Both run the C HIL library (hil/src, gearsim/hil.h) that the C runner
  gearsim-hil runs: python-can is the transport, the semantics are C's.
- :func:`replay`: a recorded log drives the model in log time; answers as a log.
- :func:`log_to_measurement`: a log of commands and feedback as the canonical
  measurement CSV for ``gearsim compare|diagnose|fit``.
- ``gearsim hil run|replay|to-csv|dbc`` (:mod:`gearsim.hil.cli`).
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import Any

# name -> submodule. The submodules import python-can and cantools (the hil
# extra); they are imported on first use, so that ``gearsim hil --help`` and
# the ``gearsim`` command itself work without the extra, and a missing extra is
# named when something of it is used.
_EXPORTS: dict[str, str] = {
    "Bridge": "bridge",
    "BridgeError": "bridge",
    "Counters": "bridge",
    "LoopStats": "bridge",
    "RigTimeRecorder": "bridge",
    "REJECT_REASONS": "names",
    "LATE_REASONS": "names",
    "IGNORE_REASONS": "names",
    "RigDbc": "codec",
    "DbcError": "codec",
    "FrameSpec": "codec",
    "SignalSpec": "codec",
    "Rejection": "codec",
    "shipped_dbc": "codec",
    "replay": "replay",
    "replay_messages": "replay",
    "read_log": "replay",
    "ReplayResult": "replay",
    "log_to_measurement": "recording",
    "write_csv": "recording",
    "Recording": "recording",
    "INPUTS_SINCE": "recording",
    "RecordingError": "recording",
    "COLUMNS": "recording",
    "Scenario": "scenario",
    "ScenarioError": "scenario",
    "tunable_parameters": "names",
    "FAULTS": "names",
}

__all__ = list(_EXPORTS)


def __getattr__(name: str) -> Any:
    try:
        submodule = _EXPORTS[name]
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    from .._extras import missing_extra

    try:
        module = importlib.import_module(f".{submodule}", __name__)
    except ModuleNotFoundError as exc:
        err = missing_extra(exc, "gearsim.hil")
        if err is None:
            raise
        raise err from exc
    value = getattr(module, name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))


class _Package(types.ModuleType):
    """The import system binds each submodule on its package once it has
    loaded; ``replay`` is both a submodule and the function exported under that
    name. Loaded eagerly, the function was bound last and won; loaded lazily,
    the submodule would shadow it whenever something imported it first. An
    export keeps its name here, and the submodule stays in sys.modules."""

    def __setattr__(self, name: str, value: Any) -> None:
        if name in _EXPORTS and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
