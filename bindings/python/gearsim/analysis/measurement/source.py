"""The source stage: the bytes of a measurement file (or of standard input),
decompressed by their magic bytes, and refused with one line when they are not
a text CSV (binary data, NUL bytes, UTF-16/32, an archive or a document)."""

from __future__ import annotations

import bz2
import gzip
import lzma
import os
import re
import sys
from dataclasses import dataclass

from ..._outputs import printable
from ..errors import MeasurementError
from .record import Notes

#: The path that reads standard input.
STDIN = "-"

_COMPRESSIONS = {  # name -> extensions
    "gzip": (".gz", ".gzip", ".tgz"),
    "bzip2": (".bz2", ".bzip2"),
    "xz": (".xz", ".txz"),
    "zstd": (".zst", ".zstd"),
}
_ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"

# Files that are surely not a CSV: (signature, what it is, what to do)
_NOT_CSV = (
    (b"PK\x03\x04", "a ZIP archive (or an .xlsx workbook)", "extract or export the CSV first"),
    (b"PK\x05\x06", "an empty ZIP archive", "extract or export the CSV first"),
    (
        b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1",
        "an OLE document (an old .xls workbook?)",
        "export the sheet as CSV",
    ),
    (b"%PDF-", "a PDF document", "export the data as CSV"),
    (b"\x89HDF\r\n\x1a\n", "an HDF5 file (MATLAB v7.3 .mat?)", "export the signals as CSV"),
    (b"MATLAB 5.0 MAT-file", "a MATLAB .mat file", "export the signals as CSV"),
    (b"SQLite format 3\x00", "an SQLite database", "export the table as CSV"),
    (b"PAR1", "a Parquet file", "export it as CSV"),
    (b"\x89PNG\r\n\x1a\n", "a PNG image", "give the measurement CSV"),
    (b"7z\xbc\xaf\x27\x1c", "a 7-Zip archive", "extract the CSV first"),
    (b"\x7fELF", "an executable (ELF)", "give the measurement CSV"),
)
_CONTROL = re.compile(rb"[\x01-\x08\x0b\x0c\x0e-\x1f\x7f]")
_NOT_CONTROL = bytes(sorted(set(range(256)) - {*range(1, 9), 11, 12, *range(14, 32), 127}))
_EOL = re.compile(rb"\r\n|\r|\n")


@dataclass(frozen=True)
class Text:
    """The text bytes of a measurement (BOM and DOS end-of-file mark removed)
    and the compressions undone to reach them, outermost first."""

    data: bytes
    kinds: tuple[str, ...] = ()

    @property
    def inside(self) -> str:
        """Where a message's finding lies: " (after gzip decompression)" or ""."""
        return f" (after {' and '.join(self.kinds)} decompression)" if self.kinds else ""


def read_text(path: str, shown: str, notes: Notes) -> Text:
    """The text of `path` ("-": standard input), checked to be a text CSV."""
    data, kinds = _decompress(read_source(path, shown), path, shown, notes)
    return Text(_check_text(data, shown, kinds), tuple(kinds))


def read_source(path: str, shown: str) -> bytes:
    """All bytes of the file, or of standard input for "-"."""
    if path == STDIN:
        if sys.stdin is None:
            raise MeasurementError("there is no standard input to read", file=shown)
        stream = getattr(sys.stdin, "buffer", None) or sys.stdin
        try:
            tty = bool(sys.stdin.isatty())
        except (AttributeError, OSError, ValueError):
            tty = False
        if tty:
            raise MeasurementError(
                "standard input is a terminal; pipe or redirect the CSV into it "
                "(e.g. gearsim compare - --model M.toml < data.csv)",
                file=shown,
            )
        try:
            data = stream.read()
        except (OSError, ValueError) as exc:
            raise MeasurementError(
                f"cannot read standard input ({printable(getattr(exc, 'strerror', None) or exc)})",
                file=shown,
            ) from None
        return data.encode("utf-8") if isinstance(data, str) else bytes(data)
    try:
        with open(path, "rb") as fh:
            return fh.read()
    except FileNotFoundError:
        raise MeasurementError("no such file", file=shown) from None
    except IsADirectoryError:
        raise MeasurementError("is a directory, not a CSV file", file=shown) from None
    except OSError as exc:
        raise MeasurementError(
            f"cannot read ({printable(exc.strerror or exc)})", file=shown
        ) from None


def _compression_of(data: bytes) -> str | None:
    if data[:3] == b"\x1f\x8b\x08":
        return "gzip"
    if re.match(rb"BZh[1-9]1AY&SY", data[:10]) or re.fullmatch(rb"BZh[1-9]\x17rE8P\x90", data[:10]):
        return "bzip2"
    if data[:6] == b"\xfd7zXZ\x00":
        return "xz"
    if data[:4] == _ZSTD_MAGIC:
        return "zstd"
    return None


def _decompress_one(data: bytes, kind: str, shown: str) -> bytes:
    try:
        if kind == "gzip":
            return gzip.decompress(data)
        if kind == "bzip2":
            return bz2.decompress(data)
        if kind == "xz":
            return lzma.decompress(data)
        return _zstd_decompress(data, shown)
    except MeasurementError:
        raise
    except MemoryError:
        raise MeasurementError(
            f"{kind} data too large to decompress in memory", file=shown
        ) from None
    except Exception as exc:  # EOFError, OSError, zlib.error, LZMAError, ZstdError, ...
        reason = printable(str(exc) or type(exc).__name__, 90)
        raise MeasurementError(
            f"corrupt or truncated {kind} file, cannot decompress it ({reason})", file=shown
        ) from None


def _zstd_decompress(data: bytes, shown: str) -> bytes:
    try:
        import zstandard
    except ImportError:
        raise MeasurementError(
            "is zstd-compressed; reading it needs the Python package 'zstandard' of the "
            "analysis extra (pip install 'gearsim[analysis]'), or decompress it first (zstd -d)",
            file=shown,
        ) from None
    dctx = zstandard.ZstdDecompressor()
    out: list[bytes] = []
    rest = data
    while rest:
        obj = dctx.decompressobj()
        out.append(obj.decompress(rest))
        if not obj.eof:
            raise EOFError("compressed data ended before the end of the zstd frame")
        rest = obj.unused_data
    return b"".join(out)


def _decompress(data: bytes, path: str, shown: str, notes: Notes) -> tuple[bytes, list[str]]:
    """Decompressed content (by magic bytes, nested at most 3 deep) and the
    compressions found."""
    kinds: list[str] = []
    for _ in range(3):
        kind = _compression_of(data)
        if kind is None:
            break
        data = _decompress_one(data, kind, shown)
        kinds.append(kind)
    ext = os.path.splitext(path)[1].lower() if path != STDIN else ""
    named = next((k for k, exts in _COMPRESSIONS.items() if ext in exts), None)
    if named and not kinds:
        if not data or _looks_binary(data[:65536]):
            raise MeasurementError(
                f"corrupt {named} file: the name ends in {printable(ext)} but the content "
                f"does not start with the {named} signature",
                file=shown,
            )
        notes.info(f"named {printable(ext)} but not compressed; read as plain text")
    elif named and kinds and kinds[0] != named:
        notes.info(f"named {printable(ext)} but {kinds[0]}-compressed; read as {kinds[0]}")
    return data, kinds


def _looks_binary(head: bytes) -> bool:
    if b"\x00" in head:
        return True
    ctrl = len(head.translate(None, _NOT_CONTROL))  # the control bytes only
    return ctrl > max(4, len(head) // 100)


def _check_text(data: bytes, shown: str, kinds: list[str]) -> bytes:
    """Refuses what is not a text CSV (one line saying what it is); returns the
    text bytes (a trailing DOS end-of-file mark removed)."""
    inside = f" (after {' and '.join(kinds)} decompression)" if kinds else ""
    of = f" of the {'+'.join(kinds)}-decompressed content" if kinds else ""
    if data.startswith(b"\xef\xbb\xbf"):  # UTF-8 BOM
        data = data[3:]
    for magic, what, todo in _NOT_CSV:
        if data.startswith(magic):
            raise MeasurementError(f"not a text CSV: {what}{inside}; {todo}", file=shown)
    if data[257:262] == b"ustar":
        raise MeasurementError(
            f"not a text CSV: a tar archive{inside}; extract the CSV first", file=shown
        )
    if data.startswith((b"\xff\xfe\x00\x00", b"\x00\x00\xfe\xff")):
        raise MeasurementError(
            f"UTF-32 text{inside}: save the file as UTF-8 (or plain ASCII) CSV", file=shown
        )
    head = data[:4096]
    if data.startswith((b"\xff\xfe", b"\xfe\xff")) or _utf16_without_bom(head):
        raise MeasurementError(
            f"UTF-16 text{inside}: save the file as UTF-8 (or plain ASCII) CSV", file=shown
        )
    nul = data.find(b"\x00")
    if nul >= 0:
        raise MeasurementError(
            f"not a text CSV: NUL byte at offset {nul}{of} "
            f"(it starts with '{printable(data[:16], 48)}')",
            file=shown,
        )
    if data.endswith(b"\x1a"):  # DOS end-of-file mark
        data = data[:-1]
    head = data[:65536]
    m = _CONTROL.search(head)
    if m is not None and _looks_binary(head):
        raise MeasurementError(
            f"not a text CSV: binary data (control byte 0x{m.group()[0]:02x} at offset "
            f"{m.start()}{of}) (it starts with '{printable(data[:16], 48)}')",
            file=shown,
        )
    high = len(head) - len(head.translate(None, bytes(range(128, 256))))
    if high > 0.3 * len(head):
        try:
            head.decode("utf-8")
        except UnicodeDecodeError as exc:
            if exc.start < len(head) - 4:
                raise MeasurementError(
                    f"not a text CSV: binary data (byte 0x{head[exc.start]:02x} at offset "
                    f"{exc.start}{of}) (it starts with '{printable(data[:16], 48)}')",
                    file=shown,
                ) from None
    return data


def _utf16_without_bom(head: bytes) -> bool:
    if len(head) < 8:
        return False
    head = head[: len(head) // 2 * 2]
    even, odd = head[0::2], head[1::2]
    return (odd.count(0) >= 0.9 * len(odd) and even.count(0) == 0) or (
        even.count(0) >= 0.9 * len(even) and odd.count(0) == 0
    )


def decode(raw: bytes) -> str:
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def iter_lines(data: bytes, pos: int = 0, lineno: int = 0):
    """(line number, start offset, line bytes without EOL, offset of the next line)."""
    n = len(data)
    while pos < n:
        m = _EOL.search(data, pos)
        end, nxt = (m.start(), m.end()) if m else (n, n)
        lineno += 1
        yield lineno, pos, data[pos:end], nxt
        pos = nxt
