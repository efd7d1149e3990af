"""Shared helpers of the FMU tests (paths, an FMU instance driven call by call)."""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[2]
FMU_DIR = Path(os.environ.get("GEARSIM_FMU_DIR", REPO / "build" / "fmu"))
RIGS = ("gear", "rack")

# max |FMU - direct C| per scenario, printed at the end of the run
MAX_DIFFS: dict[str, float] = {}


def fmu_path(rig: str) -> Path:
    return FMU_DIR / f"gearsim_{rig}_rig.fmu"


class Instance:
    """One FMU instance driven call by call through FMPy's FMU2Slave."""

    def __init__(self, unzipdir: str, md):
        self.md = md
        self.vars = {v.name: v for v in md.modelVariables}
        from fmpy.simulation import instantiate_fmu

        self.logs: list[tuple[int, str, str]] = []
        self.fmu = instantiate_fmu(unzipdir, md, logger=self._log)
        self.time = 0.0

    def _log(self, env, name, status, category, message):
        self.logs.append((int(status), category.decode(), message.decode()))

    def errors(self) -> list[str]:
        return [m for s, _, m in self.logs if s == 3]

    def set(self, values: Mapping[str, Any]) -> None:
        """One fmi2Set* call per type, in the order Real, Integer, Boolean."""
        groups: dict[str, tuple[list[int], list[Any]]] = {
            "Real": ([], []),
            "Integer": ([], []),
            "Boolean": ([], []),
        }
        for name, value in values.items():
            v = self.vars[name]
            kind = "Integer" if v.type == "Enumeration" else v.type
            groups[kind][0].append(v.valueReference)
            groups[kind][1].append(value)
        if groups["Real"][0]:
            self.fmu.setReal(*groups["Real"])
        if groups["Integer"][0]:
            self.fmu.setInteger(groups["Integer"][0], [int(x) for x in groups["Integer"][1]])
        if groups["Boolean"][0]:
            self.fmu.setBoolean(groups["Boolean"][0], [bool(x) for x in groups["Boolean"][1]])

    def get(self, names) -> np.ndarray:
        return np.array(self.fmu.getReal([self.vars[n].valueReference for n in names]))

    def setup(self, start_values: Mapping[str, Any] | None = None, start_time: float = 0.0) -> None:
        self.fmu.setupExperiment(startTime=start_time)
        self.time = start_time
        self.fmu.enterInitializationMode()
        if start_values:
            self.set(start_values)

    def start(self, start_values: Mapping[str, Any] | None = None, start_time: float = 0.0) -> None:
        self.setup(start_values, start_time)
        self.fmu.exitInitializationMode()

    def step(self, h: float) -> None:
        self.fmu.doStep(currentCommunicationPoint=self.time, communicationStepSize=h)
        self.time += h

    def free(self) -> None:
        self.fmu.freeInstance()
