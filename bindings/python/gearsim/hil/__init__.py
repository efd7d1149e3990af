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
- :func:`replay`: a recorded log drives the model in log time; answers as a log.
- :func:`log_to_measurement`: a log of commands and feedback as the canonical
  measurement CSV for ``gearsim compare|diagnose|fit``.
- ``gearsim hil run|replay|to-csv|dbc`` (:mod:`gearsim.hil.cli`).
"""

from __future__ import annotations

from .bridge import (
    IGNORE_REASONS,
    LATE_REASONS,
    REJECT_REASONS,
    Bridge,
    BridgeError,
    Counters,
    LoopStats,
)
from .codec import DbcError, FrameSpec, Rejection, RigDbc, SignalSpec, shipped_dbc
from .recording import COLUMNS, Recording, RecordingError, log_to_measurement, write_csv
from .replay import ReplayResult, read_log, replay, replay_messages

__all__ = [
    "Bridge",
    "BridgeError",
    "Counters",
    "LoopStats",
    "REJECT_REASONS",
    "LATE_REASONS",
    "IGNORE_REASONS",
    "RigDbc",
    "DbcError",
    "FrameSpec",
    "SignalSpec",
    "Rejection",
    "shipped_dbc",
    "replay",
    "replay_messages",
    "read_log",
    "ReplayResult",
    "log_to_measurement",
    "write_csv",
    "Recording",
    "RecordingError",
    "COLUMNS",
]
