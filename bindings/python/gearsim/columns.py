"""The measurement CSV columns of docs/measurement-format.md section 1, defined once.

For each rig: the canonical column names, their SI units, what each is used as,
and which rig signal it maps to. The CSV names are the external contract and
never change; the rig's own names may differ: the driven side is
``follower_speed`` in the gear rig's CSV but ``rack_velocity`` in the rack
rig's, and the rig calls it ``follower_speed`` in both.

Both layers that read or write measurements derive from this table:

- the analysis (:mod:`gearsim.analysis.measurement`: ``RigSpec``, the columns
  a file must have, their units; :mod:`gearsim.analysis.simulate`: which rig
  input each column drives and which rig output is compared with it);
- the HIL recording (:mod:`gearsim.hil.recording`: ``COLUMNS`` and the DBC
  roles each column is taken from, ``out.<rig output>``, ``in.<rig input>`` or
  ``cmd.<rig input>``).

Plain data with no import beyond the standard library: the analysis and the
HIL extras both use it, and neither may need the other.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "RIG_TIME_MARKER",
    "INPUTS_SINCE",
    "BEFORE_SUFFIX",
    "Column",
    "RigColumns",
    "TIME",
    "TEMPERATURE",
    "AMBIENT_TEMPERATURE",
    "OPTIONAL",
    "RIGS",
]


@dataclass(frozen=True)
class Column:
    """One measurement column.

    name: the CSV header (contract); unit: its SI unit, as pint spells it;
    kind: "time", "input", "output" or "optional input"; rig_input: the
    ``Rig.run`` keyword it drives (None for outputs and time); rig_output: the
    ``RigResult`` field that holds the same signal (None when the rig has no
    such output); doc: one line, as in docs/measurement-format.md."""

    name: str
    unit: str
    kind: str
    rig_input: str | None
    rig_output: str | None
    doc: str


@dataclass(frozen=True)
class RigColumns:
    """The columns of one rig (``block`` of the model file).

    driven: the driven side's name in texts ("follower" shaft or "rack");
    driven_force_unit: the unit of a force or torque on the driven side."""

    block: str
    driven: str
    speed_input: Column
    load_input: Column
    torque_output: Column
    speed_output: Column
    driven_force_unit: str

    @property
    def inputs(self) -> tuple[Column, Column]:
        return (self.speed_input, self.load_input)

    @property
    def outputs(self) -> tuple[Column, Column]:
        return (self.torque_output, self.speed_output)

    @property
    def required(self) -> tuple[Column, ...]:
        """The columns every measurement of this rig has, in file order."""
        return (TIME, *self.inputs, *self.outputs)

    @property
    def names(self) -> tuple[str, str, str, str]:
        """(speed input, load input, torque output, speed output) names."""
        return (
            self.speed_input.name,
            self.load_input.name,
            self.torque_output.name,
            self.speed_output.name,
        )

    def column(self, name: str) -> Column | None:
        """The column called ``name`` (required or optional), or None."""
        for col in (*self.required, *OPTIONAL):
            if col.name == name:
                return col
        return None


#: Start of the first line of a CSV written by ``gearsim hil to-csv``: how its
#: rows were made (``time_base=rig rig_dt=H held=COLUMNS`` or ``time_base=wall``;
#: docs/measurement-format.md section 1.7).
RIG_TIME_MARKER = "# gearsim hil to-csv:"
#: Column of a rig-time CSV: the time (s) from which each row's inputs were applied.
INPUTS_SINCE = "inputs_since"
#: Suffix of the column holding a held input's value before ``inputs_since``.
BEFORE_SUFFIX = "_before"

TIME = Column("time", "s", "time", None, None, "when the sample was taken")

#: The measured temperature drives the rig's temperature input (the rig then
#: runs with ``temperature_input=True``); a HIL recording reads it from the
#: rig's temperature output, which repeats that input.
TEMPERATURE = Column(
    "temperature",
    "K",
    "optional input",
    "measured_temperature",
    "temperature",
    "the measured gear temperature; the temperature-dependent losses follow it",
)
AMBIENT_TEMPERATURE = Column(
    "ambient_temperature",
    "K",
    "optional input",
    "ambient_temperature",
    None,
    "the surroundings' temperature seen by the thermal model",
)
#: Columns a measurement of either rig may add, in file order.
OPTIONAL: tuple[Column, ...] = (TEMPERATURE, AMBIENT_TEMPERATURE)

RIGS: dict[str, RigColumns] = {
    "simple_gear": RigColumns(
        block="simple_gear",
        driven="follower",
        speed_input=Column(
            "base_speed",
            "rad/s",
            "input",
            "base_speed",
            "base_speed",
            "the measured speed of the base shaft, which the drive imposes",
        ),
        load_input=Column(
            "load_torque",
            "N*m",
            "input",
            "load",
            None,
            "the torque that the external load puts on the follower shaft",
        ),
        torque_output=Column(
            "base_torque",
            "N*m",
            "output",
            None,
            "base_torque",
            "the torque the drive delivers to the base shaft",
        ),
        speed_output=Column(
            "follower_speed",
            "rad/s",
            "output",
            None,
            "follower_speed",
            "the measured speed of the follower shaft",
        ),
        driven_force_unit="N*m",
    ),
    "rack_pinion": RigColumns(
        block="rack_pinion",
        driven="rack",
        speed_input=Column(
            "pinion_speed",
            "rad/s",
            "input",
            "base_speed",
            "base_speed",
            "the measured speed of the pinion shaft, which the drive imposes",
        ),
        load_input=Column(
            "load_force",
            "N",
            "input",
            "load",
            None,
            "the force that the external load puts on the rack",
        ),
        torque_output=Column(
            "pinion_torque",
            "N*m",
            "output",
            None,
            "base_torque",
            "the torque the drive delivers to the pinion shaft",
        ),
        speed_output=Column(
            "rack_velocity",
            "m/s",
            "output",
            None,
            "follower_speed",
            "the measured speed of the rack",
        ),
        driven_force_unit="N",
    ),
}
