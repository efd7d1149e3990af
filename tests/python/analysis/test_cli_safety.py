"""Safety of ``gearsim compare|diagnose|fit|report``.

Run in process through :func:`gearsim.cli.main` on copies of the bundled demo
data (the first 2000 samples) under tmp_path, or as a subprocess where a real
pipe matters. Every refusal: exit status 2, exactly one line on stderr naming
the file or option, nothing on stdout, and the directory holding the inputs
and outputs byte for byte as it was (no output written, inputs unchanged).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from gearsim.cli import EXIT_BROKEN_PIPE, main

REPO = Path(__file__).resolve().parents[3]
DEMO_CSV = REPO / "examples" / "data" / "demo_gear.csv"
DEMO_MODEL = REPO / "examples" / "data" / "demo_gear_start.toml"
GEARSIM = Path(sys.executable).with_name("gearsim")
ROWS = 2000  # dt = 1 ms: 2 s of data, Nyquist 500 Hz


@pytest.fixture(autouse=True)
def _no_debug(monkeypatch):
    monkeypatch.delenv("GEARSIM_DEBUG", raising=False)


@pytest.fixture
def demo(tmp_path):
    """(data.csv, model.toml) in tmp_path: the demo truncated to ROWS samples."""
    with open(DEMO_CSV, encoding="utf-8") as fh:
        head = [next(fh) for _ in range(ROWS + 1)]
    data = tmp_path / "data.csv"
    data.write_text("".join(head), encoding="utf-8")
    model = tmp_path / "model.toml"
    shutil.copyfile(DEMO_MODEL, model)
    return data, model


def tree(root: Path) -> dict[str, bytes | None]:
    """Every file (bytes) and directory (None) under root."""
    out: dict[str, bytes | None] = {}
    for dirpath, dirnames, filenames in os.walk(root):
        for d in dirnames:
            out[os.path.relpath(os.path.join(dirpath, d), root)] = None
        for f in filenames:
            p = os.path.join(dirpath, f)
            out[os.path.relpath(p, root)] = Path(p).read_bytes()
    return out


def gearsim(capsys, *argv) -> tuple[int, str, str]:
    capsys.readouterr()
    status = main([str(a) for a in argv])
    cap = capsys.readouterr()
    return status, cap.out, cap.err


def one_line(err: str, *needles: str) -> str:
    lines = err.strip("\n").splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    for n in needles:
        assert n in lines[0], (n, lines[0])
    return lines[0]


def refused(capsys, root: Path, *argv, needles=()) -> str:
    """Runs argv, expects a refusal: exit 2, one line, stdout empty, root unchanged."""
    before = tree(root)
    status, out, err = gearsim(capsys, *argv)
    assert status == 2, (status, err)
    line = one_line(err, *needles)
    assert out == ""
    assert tree(root) == before, "a refusal wrote or changed a file"
    return line


def cmd_args(name: str, data: Path, model: Path) -> list:
    """gearsim NAME DATA --model MODEL, with the effect fit needs."""
    extra = ["--add", "viscous_friction"] if name == "fit" else []
    return [name, data, "--model", model, *extra]


# ---------------------------------------------------------------- 1. outputs never overwrite inputs


@pytest.mark.parametrize("which", ["data", "model"])
def test_fit_out_naming_an_input_is_refused(capsys, tmp_path, demo, which):
    data, model = demo
    target = data if which == "data" else model
    refused(
        capsys,
        tmp_path,
        *cmd_args("fit", data, model),
        "--out",
        target,
        needles=("--out", target.name, "input"),
    )


def test_fit_out_naming_an_input_through_another_path_is_refused(capsys, tmp_path, demo):
    data, model = demo
    (tmp_path / "sub").mkdir()
    other = tmp_path / "sub" / ".." / "model.toml"
    refused(
        capsys, tmp_path, *cmd_args("fit", data, model), "--out", other, needles=("--out", "input")
    )


@pytest.mark.parametrize("which", ["data", "model"])
def test_report_out_naming_an_input_is_refused(capsys, tmp_path, demo, which):
    data, model = demo
    target = data if which == "data" else model
    refused(
        capsys,
        tmp_path,
        *cmd_args("report", data, model),
        "--out",
        target,
        needles=("--out", target.name, "input"),
    )


def test_report_out_dir_holding_an_input_under_a_report_name_is_refused(capsys, tmp_path, demo):
    data, model = demo
    rep = tmp_path / "rep"
    rep.mkdir()
    inside = rep / "report.html"  # the data file happens to bear the page's name
    shutil.copyfile(data, inside)
    refused(
        capsys,
        tmp_path,
        "report",
        inside,
        "--model",
        model,
        "--out",
        rep,
        needles=("--out", "report.html", "input"),
    )


def test_fit_out_empty_is_refused(capsys, tmp_path, demo):
    data, model = demo
    refused(
        capsys, tmp_path, *cmd_args("fit", data, model), "--out", "", needles=("--out", "empty")
    )


def test_report_out_empty_is_refused(capsys, tmp_path, demo):
    data, model = demo
    refused(capsys, tmp_path, "report", data, "--model", model, "--out", "", needles=("--out",))


def test_fit_out_directory_is_refused(capsys, tmp_path, demo):
    data, model = demo
    (tmp_path / "models").mkdir()
    refused(
        capsys,
        tmp_path,
        *cmd_args("fit", data, model),
        "--out",
        tmp_path / "models",
        needles=("--out", "models", "directory"),
    )


@pytest.mark.parametrize("command", ["fit", "report"])
def test_out_dash_is_refused(capsys, tmp_path, demo, command):
    data, model = demo
    refused(
        capsys,
        tmp_path,
        *cmd_args(command, data, model),
        "--out",
        "-",
        needles=("--out -", "standard output"),
    )


@pytest.mark.parametrize("command", ["fit", "report"])
def test_out_in_a_missing_directory_fails_before_any_work(capsys, tmp_path, demo, command):
    data, model = demo
    out = tmp_path / "nowhere" / ("new.toml" if command == "fit" else "rep")
    # no --quiet: a single line on stderr proves no progress line (no work) came before it
    refused(
        capsys,
        tmp_path,
        *cmd_args(command, data, model),
        "--out",
        out,
        needles=("--out", "nowhere", "does not exist"),
    )


@pytest.mark.parametrize("command", ["fit", "report"])
def test_out_in_an_unwritable_directory_fails_before_any_work(capsys, tmp_path, demo, command):
    import tempfile

    try:  # /proc takes no new files, even from root
        fd, probe = tempfile.mkstemp(dir="/proc")
    except OSError:
        pass
    else:  # pragma: no cover
        os.close(fd)
        os.unlink(probe)
        pytest.skip("/proc is writable here")
    if not os.path.isdir("/proc"):  # pragma: no cover
        pytest.skip("no /proc")
    data, model = demo
    out = "/proc/gearsim-new.toml" if command == "fit" else "/proc/gearsim-report"
    refused(
        capsys,
        tmp_path,
        *cmd_args(command, data, model),
        "--out",
        out,
        needles=("--out", "/proc", "cannot write"),
    )


def test_fit_out_is_written_atomically_with_ordinary_permissions(capsys, tmp_path, demo):
    data, model = demo
    new = tmp_path / "new.toml"
    new.write_text("old content\n")
    os.chmod(new, 0o640)
    status, out, err = gearsim(
        capsys, "fit", data, "--model", model, "--add", "viscous_friction", "--out", new, "--quiet"
    )
    assert status == 0, err
    assert "viscous" in new.read_text()
    assert (new.stat().st_mode & 0o777) == 0o640  # the replaced file's permissions kept
    fresh = tmp_path / "fresh.toml"
    status, _, err = gearsim(capsys, *cmd_args("fit", data, model), "--out", fresh, "--quiet")
    assert status == 0, err
    umask = os.umask(0)
    os.umask(umask)
    assert (fresh.stat().st_mode & 0o777) == 0o666 & ~umask  # not mkstemp's 0600
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "data.csv",
        "fresh.toml",
        "model.toml",
        "new.toml",
    ]  # no temporary file left


def test_failed_fit_leaves_the_old_out_file(capsys, tmp_path, demo, monkeypatch):
    import gearsim.analysis as analysis

    def broken(*args, **kwargs):
        raise RuntimeError("solver \x1b[31mexploded")

    monkeypatch.setattr(analysis, "fit", broken)
    data, model = demo
    new = tmp_path / "new.toml"
    new.write_text("keep me\n")
    before = tree(tmp_path)
    status, out, err = gearsim(
        capsys, "fit", data, "--model", model, "--add", "viscous_friction", "--out", new, "--quiet"
    )
    assert status == 1
    line = one_line(err, "internal error", "GEARSIM_DEBUG", "\\x1b")
    assert "\x1b" not in line
    assert tree(tmp_path) == before


# ---------------------------------------------------------------- 2. report --out over a file


def test_report_out_existing_file_is_refused(capsys, tmp_path, demo):
    data, model = demo
    existing = tmp_path / "notes.txt"
    existing.write_text("my notes\n")
    refused(
        capsys,
        tmp_path,
        *cmd_args("report", data, model),
        "--out",
        existing,
        needles=("--out", "notes.txt", "not a directory"),
    )


def test_report_out_existing_directory_writes_into_it(capsys, tmp_path, demo):
    data, model = demo
    rep = tmp_path / "rep"
    rep.mkdir()
    (rep / "keep.txt").write_text("mine\n")
    before = {k: v for k, v in tree(tmp_path).items() if not k.startswith("rep")}
    status, out, err = gearsim(capsys, "report", data, "--model", model, "--out", rep, "--quiet")
    assert status == 0, err
    assert err == ""
    assert (rep / "keep.txt").read_text() == "mine\n"
    html = (rep / "report.html").read_text()
    assert "docs/measurement-format.md" in html and "measurement-contract" not in html
    assert {p.name for p in rep.iterdir()} >= {"report.html", "overlay.png", "keep.txt"}
    assert not [p for p in rep.iterdir() if p.name.startswith(".")]  # no temporary file left
    after = {k: v for k, v in tree(tmp_path).items() if not k.startswith("rep")}
    assert after == before  # the inputs


# ------------------------------------------------------------ 3. no traceback, quiet broken pipe


def test_internal_error_is_one_line_and_the_traceback_needs_gearsim_debug(
    capsys, tmp_path, demo, monkeypatch
):
    import importlib

    cmp = importlib.import_module("gearsim.analysis.compare")  # the module, not the function

    def broken(*args, **kwargs):
        raise ZeroDivisionError("boom")

    monkeypatch.setattr(cmp, "compare", broken)
    data, model = demo
    status, out, err = gearsim(capsys, "compare", data, "--model", model, "--quiet")
    assert status == 1
    one_line(err, "gearsim compare", "internal error", "ZeroDivisionError", "GEARSIM_DEBUG")
    assert out == ""
    monkeypatch.setenv("GEARSIM_DEBUG", "1")
    with pytest.raises(ZeroDivisionError):
        main(["compare", str(data), "--model", str(model), "--quiet"])


@pytest.mark.parametrize(
    "argv, needles",
    [
        (["fit", "{data}", "--model", "{model}"], ["--add"]),
        (
            ["report", "{data}", "--model", "{model}", "--out", "{tmp}/r", "--rounds", "-1"],
            ["--rounds", "-1"],
        ),
        (
            ["report", "{data}", "--model", "{model}", "--out", "{tmp}/r", "--rounds", "1.5"],
            ["--rounds", "1.5"],
        ),
        (
            ["report", "{data}", "--model", "{model}", "--out", "{tmp}/r", "--rounds", "x"],
            ["--rounds"],
        ),
        (["diagnose", "{data}", "--model", "{model}", "--top", "0"], ["--top"]),
        (
            [
                "fit",
                "{data}",
                "--model",
                "{model}",
                "--add",
                "viscous_friction",
                "--max-samples",
                "-5",
            ],
            ["--max-samples"],
        ),
        (
            ["compare", "{data}", "--model", "{model}", "--resample", "--max-gap", "-1"],
            ["--max-gap"],
        ),
        (["compare", "{data}", "--model", "{model}", "--no-such-option"], ["--no-such-option"]),
        (["frobnicate"], ["frobnicate"]),
        (["compare", "{data}", "--model", "{model}", "--bad\x1b[2J"], ["\\x1b"]),
    ],
)
def test_usage_errors_are_one_line_exit_2(capsys, tmp_path, demo, argv, needles):
    data, model = demo
    fmt = {"data": data, "model": model, "tmp": tmp_path}
    line = refused(capsys, tmp_path, *[a.format(**fmt) for a in argv], needles=needles)
    assert "\x1b" not in line


def _closed_pipe_run(*argv: str, cwd: Path) -> subprocess.CompletedProcess:
    """gearsim with a stdout whose reader has already gone."""
    r, w = os.pipe()
    os.close(r)
    env = {k: v for k, v in os.environ.items() if k != "GEARSIM_DEBUG"}
    try:
        return subprocess.run(
            [str(GEARSIM), *argv],
            stdout=w,
            stderr=subprocess.PIPE,
            cwd=cwd,
            env=env,
            timeout=120,
        )
    finally:
        os.close(w)


@pytest.mark.parametrize(
    "argv",
    [
        ["compare", "data.csv", "--model", "model.toml", "--json", "--quiet"],
        ["compare", "data.csv", "--model", "model.toml", "--quiet"],  # the table, block-buffered
        ["--help"],
    ],
    ids=["compare-json", "compare-table", "help"],
)
def test_closed_stdout_ends_quietly_with_the_sigpipe_status(tmp_path, demo, argv):
    p = _closed_pipe_run(*argv, cwd=tmp_path)
    assert p.stderr == b""  # no traceback, no "Exception ignored ... BrokenPipeError"
    assert p.returncode == EXIT_BROKEN_PIPE == 141


def test_head_c_1_pipeline_is_quiet(tmp_path, demo):
    env = {k: v for k, v in os.environ.items() if k != "GEARSIM_DEBUG"}
    p = subprocess.run(
        [
            "bash",
            "-o",
            "pipefail",
            "-c",
            f"'{GEARSIM}' compare data.csv --model model.toml --json | head -c 1",
        ],
        capture_output=True,
        cwd=tmp_path,
        env=env,
        timeout=120,
    )
    # the reader may have left before or after the last write: 141 or 0, never noise
    assert p.returncode in (0, 141), p.stderr
    assert p.stdout == b"{"
    assert b"Traceback" not in p.stderr and b"BrokenPipe" not in p.stderr
    assert p.stderr.decode().startswith("[") or p.stderr == b""  # progress lines only


# ---------------------------------------------------------------- 4. printable messages


def test_control_characters_in_file_names_are_escaped(capsys, tmp_path, demo):
    _, model = demo
    evil = tmp_path / "no\x1b[31mpe\x07.csv"
    line = refused(capsys, tmp_path, "compare", evil, "--model", model, needles=("\\x1b", "\\x07"))
    assert "\x1b" not in line and "\x07" not in line


def test_control_characters_in_header_cells_are_escaped(capsys, tmp_path, demo):
    data, model = demo
    raw = data.read_bytes().replace(b"load_torque", b"lo\x1b]0;pwned\x07ad", 1)
    bad = tmp_path / "bad.csv"
    bad.write_bytes(raw)
    line = refused(capsys, tmp_path, "compare", bad, "--model", model, needles=("bad.csv",))
    assert "\x1b" not in line and "\x07" not in line and "\\x1b" in line


def test_control_characters_in_option_values_are_escaped(capsys, tmp_path, demo):
    data, model = demo
    line = refused(
        capsys,
        tmp_path,
        "compare",
        data,
        "--model",
        model,
        "--input-filter",
        "12\x1b[2J",
        needles=("--input-filter", "\\x1b"),
    )
    assert "\x1b" not in line


def test_missing_model_name_is_escaped(capsys, tmp_path, demo):
    data, _ = demo
    line = refused(
        capsys, tmp_path, "compare", data, "--model", tmp_path / "m\x1b.toml", needles=("\\x1b",)
    )
    assert "\x1b" not in line


# ---------------------------------------------------------------- 5. the silently wrong


@pytest.mark.parametrize("hz", ["500", "501", "1e6"])
def test_input_filter_at_or_above_nyquist_is_refused(capsys, tmp_path, demo, hz):
    data, model = demo
    refused(
        capsys,
        tmp_path,
        "compare",
        data,
        "--model",
        model,
        "--input-filter",
        hz,
        needles=("--input-filter", hz, "Nyquist", "500 Hz"),
    )


def test_input_filter_at_nyquist_is_refused_before_a_fit_writes(capsys, tmp_path, demo):
    data, model = demo
    refused(
        capsys,
        tmp_path,
        *cmd_args("fit", data, model),
        "--input-filter",
        "500",
        "--out",
        tmp_path / "new.toml",
        needles=("Nyquist",),
    )


def test_input_filter_below_nyquist_runs(capsys, tmp_path, demo):
    data, model = demo
    status, out, err = gearsim(
        capsys, "compare", data, "--model", model, "--input-filter", "499", "--quiet", "--json"
    )
    assert status == 0, err
    assert err == ""


def _with_gap(data: Path, dest: Path, first: int, missing: int) -> Path:
    """data with `missing` samples removed after data row `first` (1-based)."""
    lines = data.read_text().splitlines(keepends=True)
    dest.write_text("".join(lines[: first + 1] + lines[first + 1 + missing :]))
    return dest


def test_resample_says_what_it_filled_even_with_quiet(capsys, tmp_path, demo):
    data, model = demo
    gap = _with_gap(data, tmp_path / "gap.csv", 1000, 3)
    status, out, err = gearsim(
        capsys,
        "compare",
        gap,
        "--model",
        model,
        "--resample",
        "--max-gap",
        "0",
        "--quiet",
        "--json",
    )
    assert status == 0, err
    assert "resampled" in err and "Traceback" not in err
    assert out.count("\n") == 1  # the JSON alone on stdout


def test_a_refusal_after_a_loader_note_is_still_one_line(capsys, tmp_path, demo):
    data, model = demo
    gap = _with_gap(data, tmp_path / "gap.csv", 1000, 3)  # resampling makes a note
    refused(
        capsys,
        tmp_path,
        "compare",
        gap,
        "--model",
        model,
        "--resample",
        "--max-gap",
        "0",
        "--input-filter",
        "500",
        needles=("Nyquist",),
    )


def test_resample_refuses_a_long_gap(capsys, tmp_path, demo):
    data, model = demo
    gap = _with_gap(data, tmp_path / "gap.csv", 1000, 50)
    refused(
        capsys,
        tmp_path,
        "compare",
        gap,
        "--model",
        model,
        "--resample",
        "--max-gap",
        "10",
        needles=("gap.csv", "0.999"),
    )


def test_sampling_gaps():
    import numpy as np

    from gearsim.analysis.signals import describe_gap, sampling_gaps

    t = np.r_[np.arange(10) * 1e-3, 0.060 + np.arange(10) * 1e-3, 0.0715 + np.arange(5) * 1e-3]
    gaps = sampling_gaps(t)
    assert [(g.index, g.missing) for g in gaps] == [(9, 50), (19, 1)]
    assert sampling_gaps(t, longer_than=10) == gaps[:1]
    assert describe_gap(gaps[0]) == "0.051 s (50 samples) missing after t = 0.009 s"
    assert sampling_gaps(np.arange(100) * 1e-3) == []


# ---------------------------------------------------------------- 6. help


def test_top_level_help_starts_with_the_start_here_example(capsys):
    status, out, err = gearsim(capsys, "--help")
    assert status == 0 and err == ""
    first = out.splitlines()[:3]
    assert first[0].startswith("start here:")
    for line, command in zip(first, ("compare", "diagnose", "fit"), strict=True):
        assert f"gearsim {command}" in line and "--model" in line
    assert "docs/measurement-format.md" in out


@pytest.mark.parametrize("command", ["compare", "diagnose", "fit", "report"])
def test_command_help_points_to_the_measurement_format(capsys, command):
    status, out, err = gearsim(capsys, command, "--help")
    assert status == 0 and err == ""
    assert "docs/measurement-format.md" in out
    assert "measurement-contract" not in out and "contract section" not in out
    assert "--max-gap" in out and "Nyquist" in out
