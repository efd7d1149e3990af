"""Fixtures of the FMU tests: the built FMUs, FMPy helpers and the direct C reference.

Build first: scripts/build_fmu.sh (FMUs in build/fmu/, or GEARSIM_FMU_DIR).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from fmu_support import FMU_DIR, MAX_DIFFS, REPO, RIGS, Instance, fmu_path


@pytest.fixture(scope="session")
def fmus() -> dict[str, Path]:
    missing = [str(fmu_path(r)) for r in RIGS if not fmu_path(r).is_file()]
    if missing:
        pytest.fail(f"FMU not built: {', '.join(missing)}; run scripts/build_fmu.sh", pytrace=False)
    return {r: fmu_path(r) for r in RIGS}


@pytest.fixture(scope="session")
def unzipped(fmus, tmp_path_factory) -> dict[str, str]:
    from fmpy import extract

    return {
        r: extract(str(p), unzipdir=str(tmp_path_factory.mktemp(f"{r}_fmu")))
        for r, p in fmus.items()
    }


@pytest.fixture(scope="session")
def model_descriptions(fmus):
    from fmpy import read_model_description

    return {r: read_model_description(str(p), validate=True) for r, p in fmus.items()}


@pytest.fixture(scope="session")
def reference():
    from fmu_reference import Reference

    lib = Path(os.environ.get("GEARSIM_LIB", FMU_DIR / "reference" / "libgearsim.so"))
    if not lib.is_file():
        pytest.fail(f"reference library {lib} not built; run scripts/build_fmu.sh", pytrace=False)
    return Reference(lib, REPO)


@pytest.fixture
def instance(unzipped, model_descriptions):
    created: list[Instance] = []

    def make(rig: str) -> Instance:
        inst = Instance(unzipped[rig], model_descriptions[rig])
        created.append(inst)
        return inst

    yield make
    for inst in created:
        inst.free()


def pytest_terminal_summary(terminalreporter):
    if MAX_DIFFS:
        terminalreporter.write_sep("-", "FMU vs direct C rig: max |difference| over all outputs")
        for name, diff in sorted(MAX_DIFFS.items()):
            terminalreporter.write_line(f"{name}: {diff:.3g}")
