"""The Python side of the C HIL runner ``gearsim-hil`` (docs/hil-runner.md).

- :func:`params_text` / :func:`write_params`: the runner's parameter file from a
  gearsim model (the C parameter structs the Python rig is built from, field
  by field, so that the C runner and ``Bridge`` step the same rig);
- :func:`find_runner`: the built executable;
- :func:`live_command`, :func:`replay_command`, :func:`launch`: command lines
  and a started process, with the Python bridge's defaults (period 1 ms,
  1 sub-step, timeout 0.1 s).
"""

from __future__ import annotations

import os
import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .. import params as P
from .._lib import ffi, lib
from .._outputs import atomic_write_text
from ..errors import GearsimError

__all__ = [
    "RunnerError",
    "RUNNER_ENV",
    "params_text",
    "write_params",
    "find_runner",
    "runner_precision",
    "live_command",
    "replay_command",
    "launch",
]

#: Environment variable naming the runner executable (takes precedence).
RUNNER_ENV = "GEARSIM_HIL_RUNNER"
RUNNER_NAME = "gearsim-hil"


class RunnerError(GearsimError, ValueError):
    """The C runner cannot be found or given this model."""


def _format_value(ctype: Any, value: Any) -> str:
    kind = ctype.kind
    if kind == "enum":
        return ctype.elements[int(value)]
    if kind == "array":
        items: list[str] = []
        for item in value:
            items.append(_format_value(ctype.item, item))
        return " ".join(items)
    if ctype.cname in ("double", "float"):
        return repr(float(value))  # shortest text that reads back as the same double
    return str(int(value))


def _struct_lines(prefix: str, struct: Any, skip: Sequence[str] = ()) -> list[str]:
    """``prefix.field = value`` for every member of a cffi struct (nested
    structs as ``prefix.member.field``)."""
    lines = []
    for name, field in ffi.typeof(struct).fields:
        if name in skip:
            continue
        value = getattr(struct, name)
        if field.type.kind == "struct":
            lines.extend(_struct_lines(f"{prefix}.{name}", value))
        else:
            lines.append(f"{prefix}.{name} = {_format_value(field.type, value)}")
    return lines


def params_text(model: Any) -> str:
    """The runner's parameter file for a gearsim.Model: the block's and the
    rig's C parameter structs as the Python rig fills them, every field, plus
    the ambient temperature. The step (rig.dt_s) is not in it: the runner
    takes it from --period / --substeps, like the Python bridge."""
    rig = model.rig(dt=1e-3)  # validates the model as the bridge would
    kind = rig.kind
    c_rig = ffi.new("gs_rig_params *")
    c_rig[0] = lib.gs_rig_params_default()
    full = rig.params
    P.write_struct(P.BLOCKS[kind][1], full, c_rig)
    c_rig.heat_path = 0 if full["thermal_resistance"] is None else 1
    c_rig.temperature_source = lib.GS_TEMPERATURE_FROM_MODEL
    lines = [
        "# gearsim-hil parameter file (docs/hil-runner.md), written by gearsim.hil.runner",
        f"block = {kind}",
        *_struct_lines("block", rig.block._c_params[0]),
        *_struct_lines("rig", c_rig[0], skip=("dt_s",)),
        f"run.ambient_temperature_K = {float(rig.ambient_temperature)!r}",
    ]
    return "\n".join(lines) + "\n"


def write_params(model: Any, path: str | os.PathLike[str]) -> Path:
    """Write :func:`params_text` to ``path`` atomically; returns the path."""
    atomic_write_text(path, params_text(model))
    return Path(path)


def _source_tree_candidates() -> list[Path]:
    """Runners built in this source tree (build/*/hil/gearsim-hil), newest first."""
    root = Path(__file__).resolve().parents[4]
    if not (root / "hil" / "CMakeLists.txt").is_file():
        return []
    found = [p for p in (root / "build").glob(f"*/hil/{RUNNER_NAME}") if os.access(p, os.X_OK)]
    return sorted(found, key=lambda p: p.stat().st_mtime, reverse=True)


def runner_precision(path: str | os.PathLike[str]) -> str | None:
    """ "double" or "float": the precision the runner was built in (its
    --version), or None if it does not run."""
    try:
        res = subprocess.run(
            [os.fspath(path), "--version"], capture_output=True, text=True, timeout=10
        )
    except (OSError, subprocess.SubprocessError):
        return None
    words = res.stdout.split()
    return words[-1] if res.returncode == 0 and words and words[0] == RUNNER_NAME else None


def find_runner(precision: str | None = "double") -> Path | None:
    """The gearsim-hil executable: $GEARSIM_HIL_RUNNER, else gearsim-hil on
    PATH, else the newest one built in this source tree (build/*/hil/) in
    the given precision ("double", the Python bindings' precision, whose
    answers are bit-identical to the Python bridge's; "float"; None: any).
    None when there is none."""
    env = os.environ.get(RUNNER_ENV)
    if env:
        return Path(env) if os.access(env, os.X_OK) else None
    on_path = shutil.which(RUNNER_NAME)
    candidates = ([Path(on_path)] if on_path else []) + _source_tree_candidates()
    for path in candidates:
        if precision is None or runner_precision(path) == precision:
            return path
    return None


def _runner_or_fail(runner: str | os.PathLike[str] | None) -> str:
    path = runner if runner is not None else find_runner()
    if path is None:
        raise RunnerError(
            f"the C runner {RUNNER_NAME} is not built: build it with CMake "
            f"(cmake -S . -B build && cmake --build build --target {RUNNER_NAME}; "
            f"docs/hil-runner.md) or set {RUNNER_ENV}"
        )
    return os.fspath(path)


def _command_head(
    runner: str | os.PathLike[str] | None,
    params: str | os.PathLike[str],
    period: float,
    substeps: int,
    timeout: float,
) -> list[str]:
    """The runner, its parameter file and the timing options: how every
    command line of the runner starts."""
    return [
        _runner_or_fail(runner),
        "--params",
        os.fspath(params),
        "--period",
        repr(float(period)),
        "--substeps",
        str(int(substeps)),
        "--timeout",
        repr(float(timeout)),
    ]


def live_command(
    params: str | os.PathLike[str],
    *,
    period: float = 1e-3,
    substeps: int = 1,
    timeout: float = 0.1,
    transport: str = "candump",
    rx: str = "-",
    tx: str = "-",
    channel: str = "can0",
    duration: float | None = None,
    spin_us: int | None = None,
    fifo: int | None = None,
    cpu: int | None = None,
    mlockall: bool = False,
    json: bool = True,
    runner: str | os.PathLike[str] | None = None,
) -> list[str]:
    """Command line of a live (paced) run of the runner."""
    cmd = _command_head(runner, params, period, substeps, timeout)
    cmd += ["--transport", transport]
    if transport == "socketcan":
        cmd += ["--channel", channel]
    else:
        cmd += ["--rx", rx, "--tx", tx]
    if duration is not None:
        cmd += ["--duration", repr(float(duration))]
    if spin_us is not None:
        cmd += ["--spin-us", str(int(spin_us))]
    if fifo is not None:
        cmd += ["--fifo", str(int(fifo))]
    if cpu is not None:
        cmd += ["--cpu", str(int(cpu))]
    if mlockall:
        cmd.append("--mlockall")
    return cmd + (["--json"] if json else [])


def replay_command(
    params: str | os.PathLike[str],
    log: str | os.PathLike[str],
    out: str | os.PathLike[str] | None = None,
    *,
    period: float = 1e-3,
    substeps: int = 1,
    timeout: float = 0.1,
    tail: float = 0.0,
    json: bool = True,
    runner: str | os.PathLike[str] | None = None,
) -> list[str]:
    """Command line of a replay of a candump .log through the runner."""
    cmd = _command_head(runner, params, period, substeps, timeout)
    cmd += ["--replay", os.fspath(log), "--tail", repr(float(tail))]
    if out is not None:
        cmd += ["-o", os.fspath(out)]
    return cmd + (["--json"] if json else [])


def launch(command: Sequence[str], **popen: Any) -> subprocess.Popen:
    """Start the runner (subprocess.Popen; pipes as given in ``popen``). Stop
    it with ``proc.send_signal(signal.SIGINT)`` or ``terminate()``: it prints
    its counters (and loop timing) on stderr and exits 0."""
    return subprocess.Popen(list(command), **popen)
