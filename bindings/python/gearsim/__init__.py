"""gearsim: Simple Gear and Rack & Pinion for fixed-step simulation and HIL.

Python bindings of the gearsim C core (cffi, API mode; the C sources are
compiled into ``gearsim._gearsim``). The physics lives in C only; this package
adds parameter handling (names, defaults, units, TOML model files), numpy batch
runs and errors as exceptions. See docs/python.md and docs/python-api.md.

    import gearsim
    model = gearsim.Model.load("model.toml")
    rig = model.rig(dt=1e-3)
    out = rig.run(base_speed=w, load=tau_load)
    out.base_torque, out.follower_speed, out.temperature
"""

from __future__ import annotations

from ._lib import ffi as _ffi
from ._lib import lib as _lib
from .blocks import Block, RackPinion, SimpleGear, make_block
from .errors import GearsimError, InputError, ModelFileError, ParameterError, SubstepWarning
from .model import Model
from .params import param_units
from .rig import INPUT_NAMES, OUTPUT_NAMES, GearRig, RackRig, Rig, RigResult, RigSnapshot

#: The package's version: GS_VERSION_STRING of include/gearsim/version.h (the one
#: version source; setup.py reads the same line).
__version__: str = _ffi.string(_lib.GS_VERSION_STRING).decode()
#: Version of the compiled C library (gs_version()); equal to __version__
#: unless the extension was built from other sources than its headers.
C_VERSION: str = _ffi.string(_lib.gs_version()).decode()
#: Capacity of every interpolation table (GS_TABLE_MAX of the compiled core).
TABLE_MAX: int = int(_lib.GS_TABLE_MAX)
#: Largest contact sub-step count (GS_MAX_SUBSTEPS).
MAX_SUBSTEPS: int = int(_lib.GS_MAX_SUBSTEPS)
#: The automatic contact sub-step count's target: the smallest count with
#: h*omega_n <= AUTO_H_OMEGA_N_MAX (GS_AUTO_H_OMEGA_N_MAX).
AUTO_H_OMEGA_N_MAX: float = float(_lib.GS_AUTO_H_OMEGA_N_MAX)

__all__ = [
    "Block",
    "SimpleGear",
    "RackPinion",
    "make_block",
    "Rig",
    "GearRig",
    "RackRig",
    "RigResult",
    "RigSnapshot",
    "INPUT_NAMES",
    "OUTPUT_NAMES",
    "Model",
    "param_units",
    "GearsimError",
    "ParameterError",
    "ModelFileError",
    "InputError",
    "SubstepWarning",
    "TABLE_MAX",
    "MAX_SUBSTEPS",
    "AUTO_H_OMEGA_N_MAX",
    "C_VERSION",
    "__version__",
]
