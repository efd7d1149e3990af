"""Property-based fuzz of the ``gearsim`` command line (hypothesis).

Every example starts from a valid input and damages it in one way:

- a measurement CSV: the first 300 rows of examples/data/demo_gear.csv;
- a model file: examples/data/demo_gear_start.toml;
- a CAN log (``.asc`` or ``.blf``) written here with python-can from frames
  encoded with the shipped gear DBC (60 cycles of 10 ms, commands and
  feedback), as the HIL tests write theirs.

The damaged file is handed to ``compare``, ``diagnose``, ``fit --add
viscous_friction --out ...`` (CSV and model) or ``hil to-csv`` (log), run in
process through :func:`gearsim.cli.main`. Whatever the input, the command must

1. exit 0 or 2, never 1 and never let an exception escape;
2. print no traceback and no control character except the newline, on
   stderr or stdout (Python warnings are counted as stderr, formatted the way
   an interpreter with default filters would print them);
3. on a non-zero exit, say so in exactly one line on stderr;
4. on a non-zero exit, write nothing: the output path does not exist, no
   file appears next to the inputs or in the output directory, and nothing
   (no partial JSON, no library chatter) is printed on stdout;
5. leave every input byte for byte unchanged;
6. on exit 0, print exactly one JSON object on stdout (the commands run with
   ``--json``) and, for fit and to-csv, write the output.

Mutation classes (``<file>:<class>``; counted with hypothesis ``event()`` and
in the summary line ``cli fuzz: N examples, classes: ...`` printed at the end):
truncation, byte flips, UTF-16, latin-1, NUL bytes, random binary, compression
(gzip, bz2, xz; by extension or magic bytes only) for all three files; for the
CSV also the ``;`` and tab separators, decimal comma, huge numbers, NaN,
infinity, empty fields, duplicated and reordered columns, header only, units in
the header; for the model huge numbers, NaN, infinity, empty values, duplicate
keys, reordered tables, unit strings, unknown keys, header only; for the log
time jumps (relative and absolute stamps mixed), NaN or infinite stamps, empty
data fields, reordered and duplicated frames, no frames. ``none`` (the valid
file) is a class too.

Budget: 4000 examples by default, about 55 s on the two-core development VM
with a fuzz campaign on both cores (most of it in the examples that still parse
and simulate); ``GEARSIM_CLI_FUZZ_EXAMPLES=20000`` runs longer, a small value
(``=200``) gives a quick smoke run. Derandomized, so CI sees the same examples
every run; ``GEARSIM_HYPOTHESIS_EXPLORE=1`` draws new ones. The file, the class
and the command come from one drawn integer (so every class gets about its
share; ``fit`` runs in one CSV or model example in five); hypothesis draws the
details (where to cut or flip, which cell, which value, which format).

Violations are collected over all examples (no shrinking: an example costs up
to a second) and the test fails at the end with one line per failing class:
the property broken, the command and a sample of what it printed.
"""

from __future__ import annotations

import bz2
import collections
import contextlib
import ctypes
import gzip
import io
import json
import logging
import lzma
import math
import os
import shutil
import sys
import tempfile
import unicodedata
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, Phase, event, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

pytest.importorskip("gearsim")
can = pytest.importorskip("can")
pytest.importorskip("cantools")

from gearsim.cli import main  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
DEMO_CSV = REPO / "examples" / "data" / "demo_gear.csv"
DEMO_TOML = REPO / "examples" / "data" / "demo_gear_start.toml"
ROWS = 300
LOG_CYCLES = 60

EXAMPLES = int(os.environ.get("GEARSIM_CLI_FUZZ_EXAMPLES", "4000"))
EXPLORE = bool(os.environ.get("GEARSIM_HYPOTHESIS_EXPLORE"))

# ---------------------------------------------------------------- mutation classes

COMMON = ["none", "truncate", "byte_flip", "utf16", "latin1", "nul_bytes", "random_binary"]
COMPRESS = ["gzip", "bz2", "xz"]
CSV_CLASSES = (
    COMMON
    + COMPRESS
    + [
        "sep_semicolon",
        "sep_tab",
        "decimal_comma",
        "huge_number",
        "nan",
        "inf",
        "empty_field",
        "dup_column",
        "reorder_columns",
        "header_only",
        "unit_header",
    ]
)
TOML_CLASSES = (
    COMMON
    + COMPRESS
    + [
        "huge_number",
        "nan",
        "inf",
        "empty_field",
        "dup_key",
        "reorder_tables",
        "unit_string",
        "unknown_key",
        "header_only",
    ]
)
LOG_CLASSES = (
    COMMON
    + COMPRESS
    + [
        "time_jump",
        "nan",
        "inf",
        "empty_field",
        "reorder_frames",
        "dup_frames",
        "no_frames",
    ]
)
# the log mutations that edit the text of an .asc file
LOG_TEXT_CLASSES = {"utf16", "latin1", "nan", "inf", "empty_field"}

COMPRESSORS = {
    "gzip": (".gz", lambda b: gzip.compress(b, mtime=0)),
    "bz2": (".bz2", bz2.compress),
    "xz": (".xz", lzma.compress),
}


# ---------------------------------------------------------------- base inputs


@dataclass
class Base:
    csv_header: list[str]
    csv_rows: list[list[str]]
    toml_text: str
    log_messages: list[Any]
    log_bytes: dict[str, bytes]
    """the valid log in each format, written once (the .asc header holds the
    date of writing: byte-level draws must not depend on it)"""

    @property
    def csv_text(self) -> str:
        return _join(self.csv_header, self.csv_rows, ",")


def _join(header: list[str], rows: list[list[str]], sep: str) -> str:
    return "".join(sep.join(r) + "\n" for r in [header, *rows])


def _log_messages() -> list[Any]:
    """LOG_CYCLES cycles of 10 ms of a speed-driven gear rig: the command
    frame and the two feedback frames to-csv needs, as the bridge sends them."""
    from gearsim.hil import RigDbc

    dbc = RigDbc(block="gear")
    frames = {f.name: f for f in dbc.feedback}
    out = []
    for k in range(LOG_CYCLES):
        t = 0.01 * k
        w = 20.0 + 5.0 * math.sin(2.0 * math.pi * t)
        load = 0.5 * math.cos(2.0 * math.pi * t)
        for m in dbc.encode_command({"cmd.base_speed": w, "cmd.load": load, "cmd.mode": "speed"}):
            m.timestamp = t
            out.append(m)
        values = {
            "out.base_torque": 0.2 + 0.01 * w - load / 3.0,
            "out.base_speed": w,
            "in.load": load,
            "out.follower_speed": -w / 3.0,
            "out.follower_angle": 0.0,
            "out.follower_acceleration": 0.0,
        }
        for name in ("GearFbBase", "GearFbFollower"):
            f = frames[name]
            data, _ = dbc.encode_feedback(f, {s.role: values[s.role] for s in f.signals if s.role})
            out.append(
                can.Message(
                    timestamp=t + 5e-4,
                    arbitration_id=f.frame_id,
                    is_extended_id=f.is_extended,
                    data=data,
                )
            )
    return out


def _base(tmp: Path) -> Base:
    lines = DEMO_CSV.read_text(encoding="utf-8").splitlines()
    header = lines[0].split(",")
    rows = [ln.split(",") for ln in lines[1 : ROWS + 1]]
    messages = _log_messages()
    logs = {}
    for fmt in ("asc", "blf"):
        _write_log(messages, tmp / f"base.{fmt}")
        logs[fmt] = (tmp / f"base.{fmt}").read_bytes()
    return Base(header, rows, DEMO_TOML.read_text(encoding="utf-8"), messages, logs)


def _write_log(messages: list[Any], path: Path) -> None:
    logger = can.Logger(str(path))
    try:
        for m in messages:
            logger.on_message_received(m)
    finally:
        logger.stop()


# ---------------------------------------------------------------- byte-level mutations


def _bytes_mutation(draw, cls: str, raw: bytes, text: str) -> bytes | None:
    """The mutations every file shares; None when cls is not one of them."""
    if cls == "none":
        return raw
    if cls == "truncate":
        return raw[: draw(st.integers(0, max(0, len(raw) - 1)))]
    if cls == "byte_flip":
        out = bytearray(raw)
        for _ in range(draw(st.integers(1, 8))):
            i = draw(st.integers(0, len(out) - 1))
            out[i] ^= draw(st.integers(1, 255))
        return bytes(out)
    if cls == "utf16":
        return text.encode(draw(st.sampled_from(["utf-16", "utf-16-le", "utf-16-be"])))
    if cls == "nul_bytes":
        out = bytearray(raw)
        for _ in range(draw(st.integers(1, 5))):
            i = draw(st.integers(0, len(out)))
            out[i:i] = b"\x00" * draw(st.integers(1, 3))
        return bytes(out)
    if cls == "random_binary":
        return draw(st.binary(min_size=0, max_size=2048))
    return None


def _compress(draw, cls: str, raw: bytes, name: str, note: list[str]) -> tuple[bytes, str]:
    """Compressed bytes and the file name: with the compressor's extension, or
    under the plain name (recognisable by its magic bytes only)."""
    ext, fn = COMPRESSORS[cls]
    by_extension = draw(st.booleans())
    event(f"compression {'by extension' if by_extension else 'by magic bytes'}")
    note.append("by extension" if by_extension else "by magic bytes only")
    return fn(raw), name + ext if by_extension else name


# ---------------------------------------------------------------- CSV


def _cell_value(draw, cls: str) -> str:
    if cls == "huge_number":
        return draw(
            st.sampled_from(
                ["1e308", "-1.7976931348623157e308", "1e309", "-1e400", "9" * 400, "1e-400"]
            )
        )
    if cls == "nan":
        return draw(st.sampled_from(["nan", "NaN", "-nan", "NAN"]))
    if cls == "inf":
        return draw(st.sampled_from(["inf", "-inf", "Infinity", "-Infinity", "+inf"]))
    return draw(st.sampled_from(["", " ", '""']))  # empty_field


def _shared_mutation(
    draw, cls: str, raw: bytes, text: str, name: str, note: list[str]
) -> tuple[bytes, str] | None:
    """The byte-level and compression mutations every file shares, as
    (content, file name); None when cls is neither."""
    out = _bytes_mutation(draw, cls, raw, text)
    if out is not None:
        return out, name
    if cls in COMPRESSORS:
        return _compress(draw, cls, raw, name, note)
    return None


def _mutate_csv(draw, cls: str, base: Base, note: list[str]) -> tuple[bytes, str]:
    header = list(base.csv_header)
    rows = [list(r) for r in base.csv_rows]
    text = base.csv_text
    name = "data.csv"
    shared = _shared_mutation(draw, cls, text.encode("utf-8"), text, name, note)
    if shared is not None:
        return shared
    if cls == "latin1":
        # an extra column whose header is not ASCII, the file in latin-1
        label = draw(st.sampled_from(["Temperatur_°C", "Drehzahl µ", "Moment_Nm_ü"]))
        return _join([*header, label], [[*r, "0"] for r in rows], ",").encode("latin-1"), name
    if cls == "sep_semicolon":
        return _join(header, rows, ";").encode(), name
    if cls == "sep_tab":
        return _join(header, rows, "\t").encode(), name
    if cls == "decimal_comma":
        return _join(header, [[c.replace(".", ",") for c in r] for r in rows], ";").encode(), name
    if cls in ("huge_number", "nan", "inf", "empty_field"):
        r = draw(st.integers(0, len(rows) - 1))
        c = draw(st.integers(0, len(header) - 1))
        rows[r][c] = _cell_value(draw, cls)
        note.append(f"line {r + 2}, {header[c]} = {rows[r][c][:20]!r}")
        return _join(header, rows, ",").encode(), name
    if cls == "dup_column":
        c = draw(st.integers(0, len(header) - 1))
        at = draw(st.integers(0, len(header)))
        header.insert(at, header[c])
        for r in rows:
            r.insert(at, r[c])
        return _join(header, rows, ",").encode(), name
    if cls == "reorder_columns":
        order = draw(st.permutations(range(len(header))))
        text = _join([header[i] for i in order], [[r[i] for i in order] for r in rows], ",")
        return text.encode(), name
    if cls == "header_only":
        text = ",".join(header) + draw(st.sampled_from(["\n", "", "\r\n", "\n\n"]))
        return text.encode(), name
    if cls == "unit_header":
        variant = draw(st.sampled_from(["brackets", "parentheses", "rpm", "ms"]))
        event(f"csv:unit_header {variant}")
        note.append(variant)
        if variant == "brackets":
            units = ["s", "rad/s", "N*m", "N*m", "rad/s", "K"]
            header = [f"{h} [{u}]" for h, u in zip(header, units, strict=True)]
        elif variant == "parentheses":
            units = ["s", "rad/s", "N m", "N m", "rad/s", "K"]
            header = [f"{h} ({u})" for h, u in zip(header, units, strict=True)]
        elif variant == "rpm":
            header[1] = "base_speed (rpm)"
            for r in rows:
                r[1] = repr(float(r[1]) * 60.0 / (2.0 * math.pi))
        else:
            header[0] = "time [ms]"
            for r in rows:
                r[0] = repr(round(float(r[0]) * 1000.0, 6))
        return _join(header, rows, ",").encode(), name
    raise AssertionError(f"unknown csv class {cls}")  # pragma: no cover


# ---------------------------------------------------------------- TOML


def _set_key(text: str, table: str, key: str, literal: str) -> str:
    """text with `key = literal` in [table] (replaced, or added after the header)."""
    lines = text.splitlines()
    current = None
    for i, ln in enumerate(lines):
        s = ln.strip()
        if s.startswith("["):
            current = s.strip("[] ")
        elif current == table and s.split("=")[0].strip() == key:
            lines[i] = f"{key} = {literal}"
            return "\n".join(lines) + "\n"
    i = lines.index(f"[{table}]")
    lines.insert(i + 1, f"{key} = {literal}")
    return "\n".join(lines) + "\n"


_NUMERIC_KEYS = [
    ("rig", "follower_inertia"),
    ("rig", "load_offset"),
    ("rig", "load_coulomb_friction"),
    ("rig", "thermal_resistance"),
    ("block", "teeth_ratio"),
    ("block", "power_threshold"),
]


def _mutate_toml(draw, cls: str, base: Base, note: list[str]) -> tuple[bytes, str]:
    text = base.toml_text
    name = "model.toml"
    shared = _shared_mutation(draw, cls, text.encode("utf-8"), text, name, note)
    if shared is not None:
        return shared
    if cls == "latin1":
        comment = draw(st.sampled_from(["# Prüfstand 3, Öl bei 80 °C", "# µ-Getriebe"]))
        return (comment + "\n" + text).encode("latin-1"), name
    if cls in ("huge_number", "nan", "inf", "empty_field"):
        table, key = draw(st.sampled_from(_NUMERIC_KEYS))
        literal = {
            "huge_number": ["1e308", "-1e308", "1e309", "1e-320", "99999999999999999999999"],
            "nan": ["nan", "-nan", '"nan"', '"NaN m"'],
            "inf": ["inf", "-inf", '"inf"', "+inf"],
            "empty_field": ['""', "", "[]", "{}"],
        }[cls]
        value = draw(st.sampled_from(literal))
        note.append(f"[{table}] {key} = {value}")
        return _set_key(text, table, key, value).encode(), name
    if cls == "dup_key":
        lines = text.splitlines()
        i = draw(st.integers(0, len(lines) - 1))
        lines.insert(i, lines[i])
        return ("\n".join(lines) + "\n").encode(), name
    if cls == "reorder_tables":
        rig, _, block = text.partition("[block]")
        return ("[block]" + block.rstrip("\n") + "\n\n" + rig).encode(), name
    if cls == "unit_string":
        table, key, literal = draw(
            st.sampled_from(
                [
                    ("rig", "follower_inertia", '"0.05 kg*m^2"'),
                    ("rig", "follower_inertia", '"50 g*m**2"'),
                    ("rig", "follower_inertia", '"3000 rpm"'),
                    ("rig", "ambient_temperature", '"20 degC"'),
                    ("rig", "ambient_temperature", '"80 furlong"'),
                    ("block", "teeth_ratio", '"3 rpm"'),
                    ("block", "teeth_ratio", '"100 mm"'),
                    ("block", "base_radius", '"100 mm"'),
                ]
            )
        )
        note.append(f"[{table}] {key} = {literal}")
        return _set_key(text, table, key, literal).encode(), name
    if cls == "unknown_key":
        table, key = draw(
            st.sampled_from([("rig", "frobnicate"), ("block", "teeth_ratios"), ("rig", "mass")])
        )
        return _set_key(text, table, key, "1.0").encode(), name
    if cls == "header_only":
        return draw(st.sampled_from(["[rig]\n", "[rig]\n[block]\n", ""])).encode(), name
    raise AssertionError(f"unknown toml class {cls}")  # pragma: no cover


# ---------------------------------------------------------------- CAN log


def _asc_data_lines(lines: list[str]) -> list[int]:
    return [i for i, ln in enumerate(lines) if " d " in ln and ln.strip()[:1].isdigit()]


def _mutate_log(draw, cls: str, base: Base, tmp: Path, note: list[str]) -> tuple[bytes, str]:
    fmt = "asc" if cls in LOG_TEXT_CLASSES else draw(st.sampled_from(["asc", "blf"]))
    event(f"log format {fmt}")
    note.append(fmt)
    name = f"rec.{fmt}"
    msgs = [m for m in base.log_messages]

    if cls == "time_jump":
        k = draw(st.integers(1, len(msgs) - 1))
        offset = draw(st.sampled_from([30.0, 3600.0, 1.7e9]))
        mode = draw(st.sampled_from(["forward", "absolute_then_relative"]))
        event(f"log:time_jump {mode} {offset:g} s")
        note.append(f"{mode}, {offset:g} s from frame {k}")
        shifted = (lambda i: i >= k) if mode == "forward" else (lambda i: i < k)
        msgs = [_restamp(m, m.timestamp + offset) if shifted(i) else m for i, m in enumerate(msgs)]
    elif cls == "reorder_frames":
        i = draw(st.integers(0, len(msgs) - 2))
        j = draw(st.integers(i + 1, len(msgs) - 1))
        msgs[i], msgs[j] = msgs[j], msgs[i]
    elif cls == "dup_frames":
        for _ in range(draw(st.integers(1, 5))):
            i = draw(st.integers(0, len(msgs) - 1))
            msgs.insert(i, msgs[i])
    elif cls == "no_frames":
        msgs = []

    if cls in ("time_jump", "reorder_frames", "dup_frames", "no_frames"):
        scratch = tmp / ("scratch_" + name)
        _write_log(msgs, scratch)
        raw = scratch.read_bytes()
        scratch.unlink()
        return raw, name
    raw = base.log_bytes[fmt]
    text = raw.decode("latin-1")
    shared = _shared_mutation(draw, cls, raw, text, name, note)
    if shared is not None:
        return shared
    lines = text.splitlines()
    data = _asc_data_lines(lines)
    i = draw(st.sampled_from(data))
    if cls == "latin1":
        lines.insert(i, draw(st.sampled_from(["// Prüfstand µ 3", "// Öltemperatur 80 °C"])))
        return ("\n".join(lines) + "\n").encode("latin-1"), name
    tokens = lines[i].split()
    if cls in ("nan", "inf"):
        stamps = ["nan", "-nan"] if cls == "nan" else ["inf", "-inf", "1e308"]
        tokens[0] = draw(st.sampled_from(stamps))
        note.append(f"stamp {tokens[0]} on line {i + 1}")
    elif cls == "empty_field":
        d = tokens.index("d")
        cut = draw(st.integers(d + 1, len(tokens) - 1))
        tokens = tokens[:cut]
    lines[i] = " " + " ".join(tokens)
    return ("\n".join(lines) + "\n").encode("latin-1"), name


def _restamp(msg: Any, t: float) -> Any:
    return can.Message(
        timestamp=t,
        arbitration_id=msg.arbitration_id,
        is_extended_id=msg.is_extended_id,
        data=bytes(msg.data),
    )


# ---------------------------------------------------------------- running one command


_PY_DEFAULT_FILTERS = [
    ("default", DeprecationWarning, "__main__"),
    ("ignore", DeprecationWarning, None),
    ("ignore", PendingDeprecationWarning, None),
    ("ignore", ImportWarning, None),
    ("ignore", ResourceWarning, None),
]


_libc = ctypes.CDLL(None)


def _flush_all() -> None:
    """Flush Python's and C's standard streams (LAPACK, for one, prints with C stdio)."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    _libc.fflush(None)


@contextlib.contextmanager
def _fd_capture():
    """What is written to file descriptors 1 and 2 (by C code, bypassing
    sys.stdout/sys.stderr): yields a list that receives (stdout, stderr)."""
    got: list[str] = []
    with tempfile.TemporaryFile() as f1, tempfile.TemporaryFile() as f2:
        _flush_all()
        saved = os.dup(1), os.dup(2)
        os.dup2(f1.fileno(), 1)
        os.dup2(f2.fileno(), 2)
        try:
            yield got
        finally:
            _flush_all()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])
            for f in (f1, f2):
                f.seek(0)
                got.append(f.read().decode("utf-8", "backslashreplace"))


def run_cli(argv: list[str]) -> tuple[int | None, str, str, BaseException | None]:
    """(exit status, stdout, stderr, escaped exception) of ``gearsim argv``.

    Both what Python code writes to sys.stdout/sys.stderr and what C code
    writes to the file descriptors are captured. Warnings are filtered as a
    plain interpreter does (pytest's own filters are set aside) and appended
    to stderr in the form the interpreter prints; log records reach stderr as
    they do without logging configured (WARNING and above)."""
    out, err = io.StringIO(), io.StringIO()
    escaped: BaseException | None = None
    status: int | None = None
    saved = os.environ.pop("GEARSIM_DEBUG", None)
    # no logging handlers, as in a plain interpreter: a library's warning goes
    # through logging.lastResort to (the redirected) sys.stderr
    root = logging.getLogger()
    handlers, root.handlers = root.handlers, []
    try:
        with warnings.catch_warnings(record=True) as caught, _fd_capture() as fd:
            warnings.resetwarnings()
            for action, category, module in _PY_DEFAULT_FILTERS:
                if module:
                    warnings.filterwarnings(action, category=category, module=module)
                else:
                    warnings.simplefilter(action, category)
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                try:
                    status = main(argv)
                except SystemExit as exc:
                    if exc.code is None or isinstance(exc.code, int):
                        status = exc.code or 0
                    else:  # SystemExit("text"): the interpreter prints it, exit 1
                        err.write(f"{exc.code}\n")
                        status = 1
                except BaseException as exc:  # noqa: BLE001 - the property under test
                    escaped = exc
    finally:
        root.handlers = handlers
        if saved is not None:
            os.environ["GEARSIM_DEBUG"] = saved
    stdout = out.getvalue() + fd[0]
    stderr = (
        err.getvalue()
        + fd[1]
        + "".join(
            warnings.formatwarning(w.message, w.category, w.filename, w.lineno, w.line)
            for w in caught
        )
    )
    return status, stdout, stderr, escaped


def _controls(text: str) -> list[str]:
    return sorted({repr(ch) for ch in text if ch != "\n" and unicodedata.category(ch) == "Cc"})


def _short(text: str, n: int = 240) -> str:
    """A sample of what a command printed: the whole of one line, else the
    first and the last line (a traceback's last line is its message)."""
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    if len(lines) > 1:
        text = f"[{len(lines)} lines] {lines[0]} ... {lines[-1]}"
    else:
        text = text.strip()
    return repr(text if len(text) <= n else text[: n // 2] + " ... " + text[-n // 2 :])


@dataclass
class Tally:
    examples: int = 0
    classes: collections.Counter = field(default_factory=collections.Counter)
    statuses: collections.Counter = field(default_factory=collections.Counter)
    # class -> {example number: [(property, command, sample), ...]}
    failures: dict[str, dict[int, list[tuple[str, str, str]]]] = field(default_factory=dict)

    def fail(self, cls: str, prop: str, command: str, sample: str) -> None:
        self.failures.setdefault(cls, {}).setdefault(self.examples, []).append(
            (prop, command, sample)
        )

    def summary(self) -> str:
        classes = ", ".join(f"{k}={v}" for k, v in sorted(self.classes.items()))
        statuses = ", ".join(f"exit {k}: {v}" for k, v in sorted(self.statuses.items(), key=str))
        failing = ", ".join(
            f"{k} ({len(v)}/{self.classes[k]})" for k, v in sorted(self.failures.items())
        )
        return (
            f"cli fuzz: {self.examples} examples, classes: {classes}; {statuses}; "
            f"failing classes (failing/run): {failing or 'none'}"
        )

    def report(self) -> str:
        """The summary, then per failing class each property broken: in how
        many examples, and what the first of them printed."""
        lines = [self.summary()]
        for cls, by_example in sorted(self.failures.items()):
            lines.append(f"  {cls}: {len(by_example)} of {self.classes[cls]} examples fail")
            seen: dict[str, list] = {}
            for items in by_example.values():
                for prop, command, sample in items:
                    kind = prop.split(" (")[0]
                    entry = seen.setdefault(kind, [0, prop, command, sample])
                    entry[0] += 1
            for _kind, (n, prop, command, sample) in seen.items():
                lines.append(f"    {prop} ({n}x), e.g. {command}: {sample}")
        return "\n".join(lines)


def _check(
    tally: Tally,
    cls: str,
    command: str,
    result: tuple[int | None, str, str, BaseException | None],
    inputs: dict[Path, bytes],
    in_dir: Path,
    out_dir: Path,
    out_path: Path | None,
) -> None:
    status, stdout, stderr, escaped = result
    tally.statuses[status if escaped is None else "exception"] += 1
    first = _short(stderr)
    if escaped is not None:
        sample = f"{type(escaped).__name__}: {_short(str(escaped))}"
        tally.fail(cls, "exception escaped", command, sample)
    elif status not in (0, 2):
        tally.fail(cls, f"exit {status}", command, first)
    if "Traceback" in stderr or "Traceback" in stdout:
        tally.fail(cls, "traceback", command, first)
    bad = _controls(stderr) + _controls(stdout)
    if bad:
        tally.fail(cls, "control characters", command, f"{', '.join(bad[:6])} in {first}")
    if status != 0:
        if len(stderr.strip("\n").splitlines()) != 1 or not stderr.strip():
            n = len(stderr.strip("\n").splitlines())
            tally.fail(cls, f"not one line on stderr ({n} lines)", command, first)
        left = sorted(p.name for p in out_dir.iterdir())
        if out_path is not None and out_path.exists():
            tally.fail(cls, "output written on failure", command, first)
        elif left:
            tally.fail(cls, "files left on failure", command, f"{left} after {first}")
        extra = sorted(p.name for p in in_dir.iterdir() if p not in inputs)
        if extra:
            tally.fail(cls, "files left on failure", command, f"{extra} after {first}")
        if stdout.strip():
            tally.fail(cls, "stdout written on failure", command, _short(stdout))
    else:
        lines = [ln for ln in stdout.splitlines() if ln.strip()]
        try:
            ok = len(lines) == 1 and isinstance(json.loads(lines[0]), dict)
        except ValueError:
            ok = False
        if not ok:
            tally.fail(cls, "exit 0 without one JSON object", command, _short(stdout))
        if out_path is not None and not out_path.exists():
            tally.fail(cls, "exit 0 without the output", command, _short(stdout))
    for path, data in inputs.items():
        if not path.exists() or path.read_bytes() != data:
            tally.fail(cls, "input modified", command, f"{path.name} after {first}")


# ---------------------------------------------------------------- the test


#: (file, mutation class) pairs
PAIRS = (
    [("csv", c) for c in CSV_CLASSES]
    + [("toml", c) for c in TOML_CLASSES]
    + [("log", c) for c in LOG_CLASSES]
)
#: the commands a CSV or model example runs (fit in one example in five)
CSV_COMMANDS = ["compare", "diagnose", "compare", "diagnose", "fit"]


def test_cli_fuzz(tmp_path_factory: pytest.TempPathFactory, capsys: pytest.CaptureFixture) -> None:
    root = tmp_path_factory.mktemp("cli_fuzz")
    base = _base(root)
    tally = Tally()

    @settings(
        max_examples=EXAMPLES,
        deadline=None,
        derandomize=not EXPLORE,
        database=settings.default.database if EXPLORE else None,
        phases=(Phase.explicit, Phase.generate),
        suppress_health_check=list(HealthCheck),
    )
    @given(data=st.data())
    def one(data: st.DataObject) -> None:
        draw = data.draw
        # file, class and command from one wide integer, so that every class
        # gets about its share of the budget (hypothesis' own choice among a
        # few values favours the first ones); hypothesis draws the details
        pick = (draw(st.integers(0, 2**32 - 1), label="class") * 2654435761) % 2**32
        target, mutation = PAIRS[pick * len(PAIRS) >> 32]
        command = CSV_COMMANDS[pick % len(CSV_COMMANDS)]
        cls = f"{target}:{mutation}"
        event(cls)
        note: list[str] = []
        ex = Path(tempfile.mkdtemp(prefix="ex", dir=root))
        in_dir, out_dir = ex / "in", ex / "out"
        in_dir.mkdir()
        out_dir.mkdir()
        try:
            if target == "log":
                raw, name = _mutate_log(draw, mutation, base, ex, note)
                log = in_dir / name
                log.write_bytes(raw)
                out_path = out_dir / "data.csv"
                command = "hil to-csv"
                argv = ["hil", "to-csv", str(log), "--rig", "gear", "-o", str(out_path), "--json"]
            else:
                if target == "csv":
                    raw, name = _mutate_csv(draw, mutation, base, note)
                    data_path, model_path = in_dir / name, in_dir / "model.toml"
                    data_path.write_bytes(raw)
                    model_path.write_text(base.toml_text, encoding="utf-8")
                else:
                    raw, name = _mutate_toml(draw, mutation, base, note)
                    data_path, model_path = in_dir / "data.csv", in_dir / name
                    data_path.write_text(base.csv_text, encoding="utf-8")
                    model_path.write_bytes(raw)
                argv = [command, str(data_path), "--model", str(model_path), "--json", "--quiet"]
                out_path = None
                if command == "fit":
                    out_path = out_dir / "new.toml"
                    argv += ["--add", "viscous_friction", "--out", str(out_path)]
            event(f"command {command}")
            inputs = {p: p.read_bytes() for p in in_dir.iterdir()}
            result = run_cli(argv)
            tally.examples += 1
            tally.classes[cls] += 1
            what = f"{command} [{'; '.join(note)}]" if note else command
            _check(tally, cls, what, result, inputs, in_dir, out_dir, out_path)
        finally:
            shutil.rmtree(ex, ignore_errors=True)

    one()
    report = tally.report()
    with capsys.disabled():
        print("\n" + tally.summary())
    if tally.failures:
        pytest.fail(report, pytrace=False)
