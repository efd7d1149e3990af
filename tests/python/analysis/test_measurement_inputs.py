"""Measurement inputs as loggers write them: compressed files,
binary or mis-encoded files, CSV dialects, units in the header, column
mappings with any header text, time in ms/us, standard input, header-only.

Every file is built under tmp_path from the bundled examples/data/demo_gear.csv;
a file that can be read must give the same data as the plain CSV, a file that
cannot must give one MeasurementError line naming the file and what is wrong."""

from __future__ import annotations

import bz2
import gzip
import io
import lzma
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from gearsim.analysis import MeasurementError, load_measurement
from gearsim.analysis.measurement import MeasurementWarning, parse_column_map

DEMO = Path(__file__).resolve().parents[3] / "examples" / "data" / "demo_gear.csv"
MODEL = DEMO.with_name("demo_gear_start.toml")
HEADER = ["time", "base_speed", "load_torque", "base_torque", "follower_speed", "temperature"]
BLOCK = "simple_gear"


def _zstd(data: bytes) -> bytes:
    zstandard = pytest.importorskip("zstandard")
    return zstandard.ZstdCompressor().compress(data)


COMPRESSORS = {
    "gz": ("gzip", gzip.compress),
    "bz2": ("bzip2", bz2.compress),
    "xz": ("xz", lzma.compress),
    "zst": ("zstd", _zstd),
}


@pytest.fixture(scope="module")
def demo_bytes() -> bytes:
    data = DEMO.read_bytes()
    assert data.decode().splitlines()[0].split(",") == HEADER
    return data


@pytest.fixture(scope="module")
def ref():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return load_measurement(DEMO, BLOCK)


def _rows(data: bytes) -> list[list[str]]:
    return [ln.split(",") for ln in data.decode().splitlines()[1:]]


def assert_same(m, ref, exact: bool = True) -> None:
    assert m.n == ref.n and set(m.data) == set(ref.data)
    check = np.testing.assert_array_equal if exact else _close
    check(m.time, ref.time)
    assert m.dt == pytest.approx(ref.dt, rel=1e-12)
    for k in ref.data:
        check(m[k], ref[k])


def _close(a, b):
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


def load_quiet(path, **kw):
    """load_measurement with every warning turned into an error."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return load_measurement(path, BLOCK, **kw)


def one_line(msg: str, limit: int = 600) -> str:
    assert msg and len(msg) <= limit, msg
    assert all(ch.isprintable() for ch in msg), repr(msg)
    return msg


def bad(path, *needles: str, **kw) -> MeasurementError:
    with pytest.raises(MeasurementError) as exc:
        load_quiet(path, **kw)
    msg = one_line(str(exc.value))
    assert os.path.basename(str(path)) in msg, msg
    for n in needles:
        assert n in msg, msg
    return exc.value


def run_cli(*args, stdin: bytes | None = None) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env.pop("GEARSIM_DEBUG", None)
    return subprocess.run(
        [sys.executable, "-m", "gearsim.cli", *map(str, args)],
        input=stdin if stdin is not None else b"",
        capture_output=True,
        env=env,
        timeout=300,
    )


def cli_bad(p: subprocess.CompletedProcess, *needles: str) -> str:
    err = p.stderr.decode("utf-8", "replace")
    assert p.returncode == 2, (p.returncode, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    one_line(lines[0])
    for n in needles:
        assert n in lines[0], lines[0]
    assert p.stdout == b""
    return lines[0]


# ---------------------------------------------------------------- 1. compression


@pytest.mark.parametrize("ext", list(COMPRESSORS))
def test_compressed_by_extension(tmp_path, demo_bytes, ref, ext):
    f = tmp_path / f"demo.csv.{ext}"
    f.write_bytes(COMPRESSORS[ext][1](demo_bytes))
    assert_same(load_quiet(f), ref)


@pytest.mark.parametrize("ext", list(COMPRESSORS))
def test_compressed_by_magic_bytes(tmp_path, demo_bytes, ref, ext):
    f = tmp_path / "logger_output.csv"  # the name says nothing about compression
    f.write_bytes(COMPRESSORS[ext][1](demo_bytes))
    assert_same(load_quiet(f), ref)


def test_compressed_under_the_wrong_extension(tmp_path, demo_bytes, ref):
    f = tmp_path / "demo.csv.bz2"
    f.write_bytes(gzip.compress(demo_bytes))
    m = load_quiet(f)
    assert_same(m, ref)
    assert any("gzip" in n for n in m.notes)


def test_plain_text_named_gz_is_read(tmp_path, demo_bytes, ref):
    f = tmp_path / "demo.csv.gz"
    f.write_bytes(demo_bytes)
    m = load_quiet(f)
    assert_same(m, ref)
    assert any("not compressed" in n for n in m.notes)


def test_concatenated_streams(tmp_path, demo_bytes, ref):
    half = demo_bytes.index(b"\n", len(demo_bytes) // 2) + 1
    for ext in COMPRESSORS:
        comp = COMPRESSORS[ext][1]
        f = tmp_path / f"multi.{ext}"
        f.write_bytes(comp(demo_bytes[:half]) + comp(demo_bytes[half:]))
        assert_same(load_quiet(f), ref)


@pytest.mark.parametrize("ext", list(COMPRESSORS))
@pytest.mark.parametrize("damage", ["truncated", "flipped"])
def test_corrupt_compressed_file(tmp_path, demo_bytes, ext, damage):
    kind, comp = COMPRESSORS[ext]
    z = comp(demo_bytes)
    if damage == "truncated":
        z = z[: len(z) // 2]
    else:
        z = z[:40] + bytes(b ^ 0xFF for b in z[40:120]) + z[120:]
    f = tmp_path / f"broken.csv.{ext}"
    f.write_bytes(z)
    bad(f, kind, "corrupt")


def test_garbage_behind_a_compression_extension(tmp_path):
    f = tmp_path / "noise.csv.xz"
    f.write_bytes(np.random.default_rng(1).bytes(3000))
    bad(f, "xz", "corrupt")


def test_zstd_without_the_package(tmp_path, demo_bytes, monkeypatch):
    f = tmp_path / "demo.csv.zst"
    f.write_bytes(_zstd(demo_bytes))
    monkeypatch.setitem(sys.modules, "zstandard", None)  # import fails
    bad(f, "zstandard", "pip install")


def test_cli_corrupt_compressed(tmp_path, demo_bytes):
    f = tmp_path / "cut.csv.gz"
    f.write_bytes(gzip.compress(demo_bytes)[:3000])
    cli_bad(run_cli("compare", f, "--model", MODEL), "cut.csv.gz", "gzip", "corrupt")


# ---------------------------------------------------------------- 2. not a text CSV


def _binary(tmp_path, name: str, data: bytes, *needles: str) -> str:
    f = tmp_path / name
    f.write_bytes(data)
    err = bad(f, *needles)
    assert len(str(err)) < 300, str(err)  # a short excerpt at most, never the content
    return str(err)


def test_random_binary(tmp_path):
    rng = np.random.default_rng(7)
    _binary(tmp_path, "random.csv", rng.bytes(20000), "not a text CSV")
    # no NUL byte at all, still binary
    noise = bytes(b if b else 1 for b in rng.bytes(20000))
    _binary(tmp_path, "noise.csv", noise, "not a text CSV", "binary data")


def test_utf16_text(tmp_path, demo_bytes):
    text = demo_bytes.decode()
    _binary(tmp_path, "u16.csv", text.encode("utf-16"), "UTF-16", "UTF-8")
    _binary(tmp_path, "u16le.csv", text.encode("utf-16-le"), "UTF-16", "UTF-8")  # no BOM
    _binary(tmp_path, "u16be.csv", text.encode("utf-16-be"), "UTF-16")
    _binary(tmp_path, "u32.csv", text.encode("utf-32"), "UTF-32")


def test_nul_bytes(tmp_path, demo_bytes):
    data = demo_bytes[:500] + b"\x00\x00" + demo_bytes[500:]
    _binary(tmp_path, "nul.csv", data, "not a text CSV", "NUL byte at offset 500")


def test_compressed_content_that_is_not_csv(tmp_path):
    rng = np.random.default_rng(3)
    msg = _binary(tmp_path, "bin.csv.gz", gzip.compress(rng.bytes(5000)), "not a text CSV")
    assert "gzip" in msg
    readme = b"This archive holds the logger firmware notes.\nNothing else.\n" * 50
    f = tmp_path / "notes.bz2"
    f.write_bytes(bz2.compress(readme))
    msg = str(bad(f, "missing column", "line 1"))
    assert len(msg) < 400


def test_known_non_csv_formats(tmp_path, demo_bytes):
    import zipfile

    z = tmp_path / "export.zip"
    with zipfile.ZipFile(z, "w") as zf:
        zf.writestr("demo.csv", demo_bytes)
    f = tmp_path / "export.csv"
    f.write_bytes(z.read_bytes())
    bad(f, "ZIP archive")
    _binary(tmp_path, "run.mat", b"MATLAB 5.0 MAT-file, Platform: x" + bytes(200), "MATLAB")


def test_control_characters_in_the_header_are_escaped(tmp_path, demo_bytes):
    data = demo_bytes.replace(b"base_torque", b"Moment\x1b[31m\x07", 1)
    f = tmp_path / "esc.csv"
    f.write_bytes(data)
    msg = str(bad(f, "missing column", "'base_torque'", "\\x1b"))
    assert "\x1b" not in msg


def test_a_bad_cell_is_escaped(tmp_path, demo_bytes):
    lines = demo_bytes.split(b"\n")
    lines[6] = b"0.005\x1b[2J" + lines[6][5:]
    f = tmp_path / "cell.csv"
    f.write_bytes(b"\n".join(lines))
    err = bad(f, "line 7", "'time'", "not a number", "\\x1b")
    assert err.line == 7


def test_a_long_single_line_is_cut(tmp_path):
    f = tmp_path / "long.csv"
    f.write_bytes(b"x" * 100000 + b"\n1\n")
    assert len(str(bad(f, "missing column"))) < 400


@pytest.mark.parametrize(
    "name,data",
    [
        ("random.csv", np.random.default_rng(5).bytes(4000)),
        ("u16.csv", "time,base_speed\n1,2\n".encode("utf-16")),
    ],
)
def test_cli_binary_is_one_line(tmp_path, name, data):
    f = tmp_path / name
    f.write_bytes(data)
    cli_bad(run_cli("compare", f, "--model", MODEL), name)


# ---------------------------------------------------------------- 3. dialects and units


def _dialect(demo_bytes: bytes, sep: str, decimal: str = ".", eol: str = "\n") -> bytes:
    """The demo CSV with another separator, decimal mark and line end."""
    out = []
    for ln in demo_bytes.decode().splitlines():
        cells = ln.split(",")
        if decimal == ",":
            cells = [c.replace(".", ",") for c in cells]
        out.append(sep.join(cells))
    return (eol.join(out) + eol).encode()


@pytest.mark.parametrize(
    "sep,decimal,note",
    [
        (";", ".", "separator ';'"),
        (";", ",", "decimal comma"),
        ("\t", ".", "separator tab"),
        ("\t", ",", "decimal comma"),
        (",", ".", None),
    ],
)
def test_separator_and_decimal_comma(tmp_path, demo_bytes, ref, sep, decimal, note):
    f = tmp_path / "dialect.csv"
    f.write_bytes(_dialect(demo_bytes, sep, decimal))
    seen: list[str] = []
    m = load_quiet(f, note=seen.append)
    assert_same(m, ref)
    if note is None:
        assert not seen and not m.notes
    else:
        assert any(note in n for n in m.notes), m.notes
        assert len(seen) == len(m.notes) and all("dialect.csv" in s for s in seen)
        for s in seen:
            one_line(s)


def test_excel_sep_line_and_crlf(tmp_path, demo_bytes, ref):
    f = tmp_path / "excel.csv"
    f.write_bytes(b"sep=;\r\n" + _dialect(demo_bytes, ";", ",", "\r\n"))
    assert_same(load_quiet(f), ref)
    f.write_bytes(demo_bytes.replace(b"\n", b"\r"))  # old Mac line ends
    assert_same(load_quiet(f), ref)


def test_commented_preamble_and_header(tmp_path, demo_bytes, ref):
    f = tmp_path / "c.csv"
    f.write_bytes(b"# logger XY-3, firmware 2.1\n# rig 4\n" + demo_bytes)
    assert_same(load_quiet(f), ref)
    f.write_bytes(b"# logged 2026-11-23\n# " + demo_bytes)  # np.savetxt(header=...) style
    m = load_quiet(f)
    assert_same(m, ref)
    assert any("comment line 2" in n for n in m.notes)


def test_bom_latin1_and_no_header(tmp_path, demo_bytes, ref):
    f = tmp_path / "bom.csv"
    f.write_bytes(b"\xef\xbb\xbf" + demo_bytes)
    assert_same(load_quiet(f), ref)
    # a Windows logger: Latin-1 header with a degree sign, the temperature in degC
    head, _, body = demo_bytes.partition(b"\n")
    rows = [r.split(b",") for r in body.splitlines()]
    celsius = [b",".join([*r[:5], repr(float(r[5]) - 273.15).encode()]) for r in rows]
    head = head.replace(b"temperature", "temperature [°C]".encode("latin-1"))
    f.write_bytes(head + b"\n" + b"\n".join(celsius) + b"\n")
    assert_same(load_quiet(f), ref, exact=False)
    f.write_bytes(body)  # no header row
    bad(f, "missing column", "no header row?")


def test_bad_cell_error_says_the_dialect(tmp_path, demo_bytes):
    data = _dialect(demo_bytes, ";", ",").replace(b"\n0,005;", b"\n0,005x;", 1)
    f = tmp_path / "semi.csv"
    f.write_bytes(data)
    bad(f, "line 7", "'0,005x' is not a number", "separator ';'", "decimal comma")


def _with_units(demo_bytes: bytes, header: list[str], scale) -> bytes:
    rows = []
    for cells in _rows(demo_bytes):
        v = [float(c) for c in cells]
        rows.append(",".join(repr(float(x)) for x in scale(v)))
    return (",".join(header) + "\n" + "\n".join(rows) + "\n").encode()


def test_units_in_the_header_are_converted(tmp_path, demo_bytes, ref):
    header = [
        "time [ms]",
        "base_speed (rpm)",
        "load_torque [N*m]",
        "base_torque [mN*m]",
        "follower_speed (rad/s)",
        "temperature [degC]",
    ]

    def scale(v):
        return [v[0] * 1e3, v[1] * 60 / (2 * np.pi), v[2], v[3] * 1e3, v[4], v[5] - 273.15]

    f = tmp_path / "units.csv"
    f.write_bytes(_with_units(demo_bytes, header, scale))
    m = load_quiet(f)
    assert_same(m, ref, exact=False)
    note = next(n for n in m.notes if "converted to SI" in n)
    for part in ("time [ms]", "rpm", "mN*m", "degC"):
        assert part in note
    assert "follower_speed" not in note  # already SI: nothing said


def test_more_unit_spellings(tmp_path, demo_bytes, ref):
    header = [
        "time[us]",
        "base_speed [U/min]",
        "load_torque [Nm]",
        "base_torque [kN·m]",
        "follower_speed [deg/s]",
        "temperature [K]",
    ]

    def scale(v):
        return [v[0] * 1e6, v[1] * 60 / (2 * np.pi), v[2], v[3] / 1e3, np.degrees(v[4]), v[5]]

    f = tmp_path / "units2.csv"
    f.write_bytes(_with_units(demo_bytes, header, scale))
    assert_same(load_quiet(f), ref, exact=False)


def test_si_units_change_nothing(tmp_path, demo_bytes, ref):
    header = [
        f"{h} [{u}]"
        for h, u in zip(HEADER, ["s", "rad/s", "N*m", "N*m", "rad/s", "K"], strict=True)
    ]
    data = demo_bytes.replace(demo_bytes.split(b"\n")[0], ",".join(header).encode(), 1)
    f = tmp_path / "si.csv"
    f.write_bytes(data)
    m = load_quiet(f)
    assert_same(m, ref)
    assert not m.notes


@pytest.mark.parametrize(
    "unit,needles",
    [
        ("Hz", ["'base_speed [Hz]'", "no angle", "--column base_speed='base_speed [Hz]*FACTOR'"]),
        ("N*m", ["'base_speed [N*m]'", "cannot be converted to rad/s", "--column base_speed="]),
        ("foobars", ["unknown unit 'foobars'", "--column base_speed="]),
    ],
)
def test_unconvertible_unit_says_how_to_map(tmp_path, demo_bytes, unit, needles):
    data = demo_bytes.replace(b"base_speed", f"base_speed [{unit}]".encode(), 1)
    f = tmp_path / "u.csv"
    f.write_bytes(data)
    err = bad(f, "line 1", *needles)
    assert err.column == f"base_speed [{unit}]"


def test_explicit_factor_replaces_the_header_unit(tmp_path, demo_bytes, ref):
    data = demo_bytes.replace(b"base_speed", b"omega [whatever]", 1)
    f = tmp_path / "f.csv"
    f.write_bytes(data)
    m = load_quiet(f, columns=parse_column_map(["base_speed=omega [whatever]*1"]))
    assert_same(m, ref)
    assert any("factor" in n for n in m.notes)


def test_two_columns_could_be_time(tmp_path, demo_bytes):
    data = demo_bytes.replace(b"time,", b"time [s],", 1).replace(b"temperature", b"time [ms]", 1)
    f = tmp_path / "two.csv"
    f.write_bytes(data)
    bad(f, "'time [s]'", "'time [ms]'", "--column time=")


# ---------------------------------------------------------------- 4. column mapping


@pytest.mark.parametrize(
    "header",
    [
        "Drehmoment [N*m] (ü) *raw*",
        "torque*2",
        "T_in   N·m  «filtered»",
        "a=b [N*m]",
        "  leading and trailing  ",
    ],
)
def test_mapping_accepts_any_header_text(tmp_path, demo_bytes, ref, header):
    data = demo_bytes.replace(b"base_torque", header.encode(), 1)
    f = tmp_path / "map.csv"
    f.write_bytes(data)
    cols = parse_column_map([f"base_torque={header}"])
    m = load_quiet(f, columns=cols)
    assert_same(m, ref)
    bad(f, "missing column", "'base_torque'")  # not found without the mapping


def test_mapping_with_factor_or_unit_on_a_header_with_star_and_brackets(tmp_path, demo_bytes, ref):
    def scale(v):
        return [v[0], v[1], v[2], v[3] / 1000.0, v[4], v[5]]

    header = ["time", "base_speed", "load_torque", "moment [kN*m]", "follower_speed", "temperature"]
    f = tmp_path / "k.csv"
    f.write_bytes(_with_units(demo_bytes, header, scale))
    for mapping in (
        "base_torque=moment [kN*m]",  # the header's unit converts it
        'base_torque="moment [kN*m]"',  # quoted on the command line
        "base_torque=moment",  # the name without its unit
        "base_torque=moment [kN*m]*1000",  # an explicit factor instead of the unit
        "base_torque=moment [kN*m] * 1e3",
    ):
        m = load_quiet(f, columns=parse_column_map([mapping]))
        assert_same(m, ref, exact=False)


def test_mapping_errors_name_the_file(tmp_path, demo_bytes):
    data = demo_bytes.replace(b"base_torque", b"Moment", 1)
    f = tmp_path / "m.csv"
    f.write_bytes(data)
    bad(f, "scale factor 'abc'", columns=parse_column_map(["base_torque=Moment*abc"]))
    bad(f, "mapped from 'Mom\\x1bent'", columns=parse_column_map(["base_torque=Mom\x1bent"]))
    with pytest.raises(MeasurementError) as exc:
        parse_column_map(["base_torque"])
    one_line(str(exc.value))


def test_cli_mapping_with_brackets_and_star(tmp_path, demo_bytes):
    data = demo_bytes.replace(b"base_torque", "Moment [N*m] ü".encode(), 1)
    f = tmp_path / "m.csv"
    f.write_bytes(data)
    p = run_cli(
        "compare",
        f,
        "--model",
        MODEL,
        "--json",
        "--quiet",
        "--column",
        "base_torque=Moment [N*m] ü",
    )
    assert p.returncode == 0, p.stderr.decode()


# ---------------------------------------------------------------- 5. time in ms / us


def _time_as(demo_bytes: bytes, factor: float, name: str = "time") -> bytes:
    def scale(v):
        return [round(v[0] * factor, 6)] + v[1:]

    return _with_units(demo_bytes, [name] + HEADER[1:], scale)


@pytest.mark.parametrize("factor,unit", [(1e3, "ms"), (1e6, "us")])
def test_time_without_unit_that_looks_like_ms(tmp_path, demo_bytes, factor, unit):
    f = tmp_path / "t.csv"
    f.write_bytes(_time_as(demo_bytes, factor))
    with pytest.warns(MeasurementWarning) as rec:
        m = load_measurement(f, BLOCK)
    assert len(rec) == 1
    msg = one_line(str(rec[0].message))
    assert "t.csv" in msg and "time [ms]" in msg and "time [us]" in msg and "1 kHz" in msg
    assert m.dt == pytest.approx(1e-3 * factor)  # read as given, only warned
    assert any(n.startswith("warning:") for n in m.notes)
    # with a note callback: one line there, no Python warning
    seen: list[str] = []
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_measurement(f, BLOCK, note=seen.append)
    assert len(seen) == 1 and "warning:" in seen[0]
    # the unit in the header converts it
    f.write_bytes(_time_as(demo_bytes, factor, f"time [{unit}]"))
    m = load_quiet(f)
    assert m.dt == pytest.approx(1e-3, rel=1e-9)
    assert m.time[-1] == pytest.approx(7.999, rel=1e-12)


def test_time_in_seconds_is_not_warned(tmp_path, demo_bytes):
    f = tmp_path / "s.csv"
    f.write_bytes(demo_bytes)
    load_quiet(f)  # warnings are errors here
    f.write_bytes(_time_as(demo_bytes, 1e3, "time [s]"))  # said to be s: believed
    assert load_quiet(f).dt == pytest.approx(1.0)


# ---------------------------------------------------------------- 6. standard input


class _FakeStdin:
    def __init__(self, data: bytes, tty: bool = False) -> None:
        self.buffer = io.BytesIO(data)
        self._tty = tty

    def isatty(self) -> bool:
        return self._tty


@pytest.mark.parametrize("comp", [None, "gz", "zst"])
def test_stdin(monkeypatch, demo_bytes, ref, comp):
    data = demo_bytes if comp is None else COMPRESSORS[comp][1](demo_bytes)
    monkeypatch.setattr(sys, "stdin", _FakeStdin(data))
    m = load_quiet("-")
    assert_same(m, ref)
    assert m.path == "<stdin>"


def test_stdin_errors(monkeypatch):
    monkeypatch.setattr(sys, "stdin", _FakeStdin(b""))
    with pytest.raises(MeasurementError, match="<stdin>: is empty"):
        load_quiet("-")
    monkeypatch.setattr(sys, "stdin", _FakeStdin(b"", tty=True))
    with pytest.raises(MeasurementError, match="terminal"):
        load_quiet("-")
    monkeypatch.setattr(sys, "stdin", _FakeStdin(np.random.default_rng(2).bytes(3000)))
    with pytest.raises(MeasurementError) as exc:
        load_quiet("-")
    assert "<stdin>" in one_line(str(exc.value)) and "not a text CSV" in str(exc.value)


def test_cli_reads_stdin(demo_bytes):
    p = run_cli(
        "compare", "-", "--model", MODEL, "--json", "--quiet", stdin=gzip.compress(demo_bytes)
    )
    assert p.returncode == 0, p.stderr.decode()
    assert p.stdout.strip().startswith(b"{")
    cli_bad(run_cli("compare", "-", "--model", MODEL, stdin=b"\x00\x01\x02" * 100), "<stdin>")


# ---------------------------------------------------------------- 7. header only


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize(
    "name,tail",
    [("h.csv", b""), ("hb.csv", b"\n\n   \n"), ("h.csv.gz", b""), ("hs.csv", None)],
)
def test_header_only(tmp_path, demo_bytes, name, tail):
    head = demo_bytes.split(b"\n")[0] + b"\n"
    if tail is None:  # semicolon dialect, CRLF
        data = head.replace(b",", b";").replace(b"\n", b"\r\n")
    else:
        data = head + tail
    if name.endswith(".gz"):
        data = gzip.compress(data)
    f = tmp_path / name
    f.write_bytes(data)
    bad(f, "no data rows")


@pytest.mark.filterwarnings("error")
def test_too_few_rows_and_empty_file(tmp_path, demo_bytes):
    f = tmp_path / "few.csv"
    f.write_bytes(b"\n".join(demo_bytes.split(b"\n")[:4]) + b"\n")
    bad(f, "at least 20")
    f.write_bytes(b"")
    bad(f, "empty")
    f.write_bytes(b"# only a comment\n")
    bad(f, "no header row")


def test_cli_header_only(tmp_path, demo_bytes):
    f = tmp_path / "h.csv"
    f.write_bytes(demo_bytes.split(b"\n")[0] + b"\n")
    p = run_cli("compare", f, "--model", MODEL)
    cli_bad(p, "h.csv", "no data rows")
    assert b"Warning" not in p.stderr


# ------------------------------------------------- input conditioning: held inputs


def _held_staircase(n: int, hold: int, seed: int) -> np.ndarray:
    """A command held for `hold` samples at a time, at 0.01 resolution (as a
    DBC signal): a smooth profile sampled every `hold` samples."""
    k = np.arange(n) // hold * hold
    smooth = 20.0 * np.sin(2 * np.pi * k / 400.0) + 5.0 + np.random.default_rng(seed).normal(0, 0.3)
    return np.round(smooth, 2)


def test_a_held_input_is_fed_as_it_is_and_matches_its_own_model():
    """A zero-order-hold command (a CSV converted from a HIL log) must reach the
    rig unfiltered under the default input filter: the model that made the
    record then compares to within rounding."""
    import gearsim
    from gearsim.analysis import Measurement, compare, prepare_inputs

    dt, n = 1e-3, 1200
    speed = _held_staircase(n, 10, 1)
    load = np.round(0.4 * np.sin(2 * np.pi * (np.arange(n) // 10 * 10) / 230.0), 3)
    model = gearsim.Model("simple_gear", {"teeth_ratio": 2.0}, {"follower_inertia": 0.02})
    out = model.rig(dt=dt).run(base_speed=speed, load=load)
    meas = Measurement.from_arrays(
        "simple_gear",
        np.arange(n) * dt,
        base_speed=speed,
        load_torque=load,
        base_torque=np.asarray(out.base_torque),
        follower_speed=np.asarray(out.follower_speed),
    )
    inputs = prepare_inputs(meas)
    assert inputs.cutoffs == {"base_speed": None, "load_torque": None}
    assert np.array_equal(inputs.base_speed, speed)
    assert compare(model, meas).nrmse < 1e-9


def test_a_quantized_encoder_speed_is_not_taken_for_a_held_input():
    """An encoder speed at low speed toggles between neighbouring counts: many
    repeats, but the changes are single counts. It is filtered."""
    from gearsim.analysis.signals import is_held

    quantum = 0.1  # rad/s per count and sample
    t = np.arange(5000) * 1e-3
    true_angle = 0.01 * t + 0.001 * np.sin(2 * np.pi * 0.5 * t)  # rad: ~0.1 count a sample
    counts = np.floor(true_angle / (quantum * 1e-3))
    speed = np.diff(counts, prepend=counts[0]) * quantum
    assert np.mean(np.diff(speed) == 0) > 0.5  # it repeats as much as a held input
    assert not is_held(speed)
    assert is_held(_held_staircase(5000, 10, 2))
    assert not is_held(np.sin(t))  # a smooth signal never repeats


def _encoder_measurement():
    """A gear record whose base speed comes from a 16-bit encoder at 1 kHz."""
    from gearsim.analysis import Measurement

    dt, n = 1e-3, 8000
    t = np.arange(n) * dt
    angle = 3.0 * (1 - np.cos(2 * np.pi * 0.4 * t)) + 0.5 * np.sin(2 * np.pi * 7.0 * t)
    quantum = 2 * np.pi / 65536
    counts = np.floor(angle / quantum)
    speed = np.diff(counts, prepend=counts[0]) * quantum / dt
    load = np.sin(2 * np.pi * 0.3 * t)
    return Measurement.from_arrays(
        "simple_gear",
        t,
        base_speed=speed,
        load_torque=load,
        base_torque=0.1 * load,
        follower_speed=-speed / 2,
    )


def test_a_backlash_contact_or_a_compliant_shaft_gets_its_own_wider_speed_filter():
    """A contact or a compliant shaft integrates the speed, the rigid rig
    differentiates it: on an encoder speed their cut-off is wider (at most
    fs/4), listed with the others, and only a model with backlash or a shaft
    stiffness is driven by it."""
    import gearsim
    from gearsim.analysis import prepare_inputs
    from gearsim.analysis.signals import auto_cutoff, contact_cutoff

    meas = _encoder_measurement()
    rigid_hz = auto_cutoff(meas["base_speed"], 1000.0)
    contact_hz = contact_cutoff(meas["base_speed"], 1000.0)
    assert rigid_hz < contact_hz <= 250.0
    inputs = prepare_inputs(meas)
    assert inputs.cutoffs["base_speed"] == rigid_hz
    assert inputs.cutoffs["base_speed (backlash contact or compliant shaft)"] == contact_hz
    rigid = gearsim.Model("simple_gear", {"teeth_ratio": 2.0}, {"follower_inertia": 0.05})
    with_backlash = rigid.replace(block_params={"backlash_enabled": True})
    with_shaft = rigid.replace(
        rig_params={"compliance_stiffness": 600.0, "compliance_damping": 0.2, "base_inertia": 1e-3}
    )
    assert inputs.speed_for(rigid) is inputs.base_speed
    assert inputs.speed_for(with_backlash) is inputs.contact_speed
    assert inputs.speed_for(with_shaft) is inputs.contact_speed
    # the wider filter keeps more of the 7 Hz wobble's derivative and more noise
    assert np.std(np.diff(inputs.contact_speed)) > np.std(np.diff(inputs.base_speed))
    for fixed in (None, 25.0):
        assert prepare_inputs(meas, fixed).contact_speed is None


def test_compare_drives_a_compliant_shaft_with_the_wider_filtered_speed():
    """The choice reaches the simulation: a record made by running a model
    with a compliant shaft (sqrt(600/(0.001 + 0.05/4)) = 210.8 rad/s, 33.6 Hz
    with the motor held) on the encoder speed low-passed at the contact
    cut-off compares to within rounding; the same record driven at the
    rigid cut-off, which is lower on this encoder, does not."""
    import gearsim
    from gearsim.analysis import Measurement, compare
    from gearsim.analysis.signals import auto_cutoff, contact_cutoff, zero_phase_lowpass

    encoder = _encoder_measurement()
    speed, load = encoder["base_speed"], encoder["load_torque"]
    model = gearsim.Model(
        "simple_gear",
        {"teeth_ratio": 2.0},
        {
            "follower_inertia": 0.05,
            "compliance_stiffness": 600.0,
            "compliance_damping": 0.2,
            "base_inertia": 1e-3,
        },
    )

    def record(cutoff_hz: float) -> Measurement:
        import dataclasses

        from gearsim.analysis import prepare_inputs
        from gearsim.analysis.simulate import simulate_outputs

        # the record the analysis' own stepping makes from the speed
        # low-passed at cutoff_hz (the load as prepare_inputs conditions
        # it, so only the speed differs)
        driven = zero_phase_lowpass(speed, cutoff_hz, 1000.0)
        inputs = dataclasses.replace(prepare_inputs(encoder), base_speed=driven, contact_speed=None)
        out = simulate_outputs(model, encoder, inputs)
        return Measurement.from_arrays(
            "simple_gear",
            encoder.time,
            base_speed=speed,
            load_torque=load,
            base_torque=out["base_torque"],
            follower_speed=out["follower_speed"],
        )

    assert compare(model, record(contact_cutoff(speed, 1000.0))).nrmse < 1e-9
    assert compare(model, record(auto_cutoff(speed, 1000.0))).nrmse > 1e-2
