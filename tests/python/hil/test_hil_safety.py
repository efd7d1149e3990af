"""Safety of `gearsim hil ...`: outputs never replace inputs and are
written atomically; no traceback; a closed pipe ends quietly; logs whose time
jumps are refused instead of exhausting memory; compressed logs; a replay that
drives nothing fails; messages escape user data.

Every test runs the gearsim command (in process through gearsim.cli.main, or as
a subprocess where pipes matter) on logs written here with python-can."""

from __future__ import annotations

import gzip
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from hil_helpers import RigDbc, can, gear_model, rack_model, record_session

from gearsim.cli import main
from gearsim.hil import cli as hil_cli
from gearsim.hil import shipped_dbc

EPOCH = 1_795_598_728.0  # an absolute (epoch) time base, as a live bus stamps frames


def _profile(k: int) -> dict[str, Any]:
    return {"base_speed": 12.0 * math.sin(k / 40.0), "load": 0.2}


@pytest.fixture
def work(tmp_path: Path, gear_dbc: RigDbc) -> dict[str, Path]:
    """A gear model and rack model file, a recorded gear session (.blf)."""
    model = gear_model()
    model.save(tmp_path / "gear.toml")
    rack_model().save(tmp_path / "rack.toml")
    log = tmp_path / "rec.blf"
    record_session(model, gear_dbc, log, _profile, periods=300)
    return {
        "dir": tmp_path,
        "model": tmp_path / "gear.toml",
        "rack": tmp_path / "rack.toml",
        "log": log,
    }


def _run(capsys: pytest.CaptureFixture, *argv: Any) -> tuple[int, str, str]:
    capsys.readouterr()
    rc = main([str(a) for a in argv])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


def _one_error_line(err: str, *needles: str) -> str:
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err and "Exception ignored" not in err
    assert "\x1b" not in err and "\r" not in err
    for needle in needles:
        assert needle in lines[0], lines[0]
    return lines[0]


def _snapshot(directory: Path) -> dict[str, bytes]:
    """Every file under directory (hidden ones too) and its bytes."""
    return {
        str(p.relative_to(directory)): p.read_bytes()
        for p in sorted(directory.rglob("*"))
        if p.is_file() and not p.is_symlink()
    }


def _rewrite(src: Path, dst: Path, stamp: Any) -> None:
    """Copy the frames of src to dst (python-can Logger, format from dst's
    suffix) with timestamp stamp(index, t)."""
    msgs = list(can.LogReader(str(src)))
    with can.Logger(str(dst)) as out:
        for i, m in enumerate(msgs):
            m.timestamp = stamp(i, m.timestamp)
            out.on_message_received(m)


def _gearsim(*argv: Any, **kwargs: Any) -> subprocess.Popen:
    env = dict(os.environ)
    env.pop("GEARSIM_DEBUG", None)
    env["PYTHONPATH"] = os.pathsep.join(p for p in sys.path if p)
    return subprocess.Popen(
        [sys.executable, "-m", "gearsim.cli", *map(str, argv)], env=env, **kwargs
    )


# -- 1. outputs never replace inputs; checked before work; written atomically --------------
def test_to_csv_refuses_to_overwrite_its_recording(
    work: dict[str, Path], capsys: pytest.CaptureFixture
) -> None:
    d = work["dir"]
    (d / "link.blf").symlink_to(work["log"])
    before = _snapshot(d)
    for out in (work["log"], d / "sub" / ".." / "rec.blf", d / "link.blf"):
        (d / "sub").mkdir(exist_ok=True)
        rc, out_text, err = _run(capsys, "hil", "to-csv", work["log"], "--rig", "gear", "-o", out)
        assert rc == 2 and out_text == ""
        _one_error_line(err, "gearsim hil to-csv: error: --out", "input of this command")
        (d / "sub").rmdir()
        assert _snapshot(d) == before
    # the model given with --model is an input too
    rc, _, err = _run(
        capsys, "hil", "to-csv", work["log"], "--model", work["model"], "-o", work["model"]
    )
    assert rc == 2
    _one_error_line(err, "input of this command")
    assert _snapshot(d) == before


def test_replay_refuses_to_overwrite_its_log_or_model(
    work: dict[str, Path], capsys: pytest.CaptureFixture
) -> None:
    d = work["dir"]
    before = _snapshot(d)
    for out in (work["log"], work["model"]):
        rc, out_text, err = _run(
            capsys, "hil", "replay", work["log"], "--model", work["model"], "-o", out
        )
        assert rc == 2 and out_text == ""
        _one_error_line(err, "gearsim hil replay: error: --out", "input of this command")
        assert _snapshot(d) == before


def test_run_refuses_a_recording_over_its_model(
    work: dict[str, Path], capsys: pytest.CaptureFixture
) -> None:
    before = _snapshot(work["dir"])
    rc, _, err = _run(
        capsys,
        "hil",
        "run",
        "-i",
        "virtual",
        "-c",
        "safety-run-refusal",
        "--model",
        work["model"],
        "--duration",
        "0.01",
        "--log",
        work["model"],
    )
    assert rc == 2
    _one_error_line(err, "--log", "input of this command")
    assert _snapshot(work["dir"]) == before


def test_dbc_copy_refuses_the_shipped_file(capsys: pytest.CaptureFixture) -> None:
    shipped = shipped_dbc("gear")
    data = shipped.read_bytes()
    rc, _, err = _run(capsys, "hil", "dbc", "gear", "-o", shipped)
    assert rc == 2
    _one_error_line(err, "input of this command")
    assert shipped.read_bytes() == data


@pytest.mark.parametrize(
    "command, out, message",
    [
        ("to-csv", "{dir}/missing/x.csv", "does not exist"),
        ("to-csv", "{dir}", "is a directory"),
        ("to-csv", "", "empty path"),
        ("replay", "{dir}/missing/a.asc", "does not exist"),
        ("replay", "{dir}", "is a directory"),
        ("replay", "{dir}/a.xyz", "no write support for .xyz"),
        ("replay", "{dir}/a.blf.gz", "cannot write .blf compressed"),
        ("replay", "-", "no suffix naming the log format"),
    ],
)
def test_bad_output_paths_are_refused_before_any_work(
    work: dict[str, Path], capsys: pytest.CaptureFixture, command: str, out: str, message: str
) -> None:
    before = _snapshot(work["dir"])
    rig = ["--rig", "gear"] if command == "to-csv" else ["--model", work["model"]]
    rc, _, err = _run(capsys, "hil", command, work["log"], *rig, "-o", out.format(dir=work["dir"]))
    assert rc == 2
    _one_error_line(err, message)
    assert _snapshot(work["dir"]) == before


def test_outputs_are_replaced_whole_and_leave_no_temporary_file(
    work: dict[str, Path], capsys: pytest.CaptureFixture
) -> None:
    d = work["dir"]
    csv_path, answers = d / "data.csv", d / "answers.asc"
    csv_path.write_text("old\n")
    answers.write_text("old\n")
    assert _run(capsys, "hil", "to-csv", work["log"], "--rig", "gear", "-o", csv_path)[0] == 0
    rc, _, err = _run(capsys, "hil", "replay", work["log"], "--model", work["model"], "-o", answers)
    assert rc == 0, err
    assert csv_path.read_text().splitlines()[1].startswith("time,base_speed,")
    assert len(list(can.LogReader(str(answers)))) == 72
    assert sorted(p.name for p in d.iterdir()) == sorted(
        ["gear.toml", "rack.toml", "rec.blf", "data.csv", "answers.asc"]
    )
    # a replaced file keeps its permissions; a new one gets those of open()
    answers.chmod(0o640)
    rc, _, err = _run(capsys, "hil", "replay", work["log"], "--model", work["model"], "-o", answers)
    assert rc == 0, err
    assert (answers.stat().st_mode & 0o777) == 0o640
    fresh = d / "fresh.blf"
    rc, _, err = _run(capsys, "hil", "replay", work["log"], "--model", work["model"], "-o", fresh)
    mask = os.umask(0)
    os.umask(mask)
    assert rc == 0, err
    assert (fresh.stat().st_mode & 0o777) == 0o666 & ~mask


def test_a_failed_replay_leaves_the_previous_answers(
    work: dict[str, Path], capsys: pytest.CaptureFixture
) -> None:
    d = work["dir"]
    log = d / "jump.blf"
    _rewrite(work["log"], log, lambda i, t: t + (EPOCH if i >= 60 else 0.0))
    answers = d / "answers.blf"
    answers.write_bytes(b"previous answers")
    before = _snapshot(d)
    rc, _, err = _run(capsys, "hil", "replay", log, "--model", work["model"], "-o", answers)
    assert rc == 2
    _one_error_line(err, "frame 61")
    assert _snapshot(d) == before  # old answers intact, no temporary file left


# -- 2. no traceback; a closed pipe ends quietly -------------------------------------------
def test_internal_error_is_one_line_and_the_traceback_needs_gearsim_debug(
    work: dict[str, Path], capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    import gearsim.hil.recording as recording

    def boom(*args: Any, **kwargs: Any) -> None:
        raise RuntimeError("boom\nsecond line")

    monkeypatch.setattr(recording, "log_to_measurement", boom)
    monkeypatch.delenv("GEARSIM_DEBUG", raising=False)
    out = work["dir"] / "x.csv"
    rc, _, err = _run(capsys, "hil", "to-csv", work["log"], "--rig", "gear", "-o", out)
    assert rc == 1 and not out.exists()
    _one_error_line(err, "internal error: RuntimeError: boom second line", "GEARSIM_DEBUG")
    monkeypatch.setenv("GEARSIM_DEBUG", "1")
    with pytest.raises(RuntimeError, match="boom"):
        main(["hil", "to-csv", str(work["log"]), "--rig", "gear", "-o", str(out)])


def test_usage_errors_are_one_line_also_standalone(capsys: pytest.CaptureFixture) -> None:
    for call in (
        lambda: main(["hil", "to-csv", "x.blf", "--bogus"]),
        lambda: hil_cli.main(["to-csv", "x.blf", "--bogus"]),
        lambda: hil_cli.main(["replay"]),
    ):
        capsys.readouterr()
        try:
            rc = call()
        except SystemExit as exc:
            rc = exc.code
        assert rc == 2
        _one_error_line(capsys.readouterr().err, "error:")


def test_broken_pipe_ends_quietly(work: dict[str, Path]) -> None:
    # about 2 MB of CSV: far more than a pipe holds, so the writer meets the closed pipe
    proc = _gearsim(
        "hil",
        "to-csv",
        work["log"],
        "--rig",
        "gear",
        "--dt",
        "1e-5",
        "-o",
        "-",
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    try:
        # what `head -n 3` does: the time-base line, the header, one row
        head = [proc.stdout.readline() for _ in range(3)]
        proc.stdout.close()
        err = proc.stderr.read().decode()
        rc = proc.wait(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert head[0] == b"# gearsim hil to-csv: time_base=wall\n"  # --dt resamples
    assert head[1] == b"time,base_speed,load_torque,base_torque,follower_speed\n"
    assert head[2].count(b",") == 4
    # no traceback, no "Exception ignored ... BrokenPipeError": only the one line
    # saying that a resampled CSV cannot reproduce the run
    assert err.count("\n") == 1 and "warning: --dt 1e-05 s is not the feedback cycle" in err, err
    assert rc == hil_cli.EXIT_BROKEN_PIPE


def test_broken_pipe_through_head(work: dict[str, Path]) -> None:
    if shutil.which("head") is None or shutil.which("sh") is None:
        pytest.skip("no head or sh")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    env.pop("GEARSIM_DEBUG", None)
    cmd = (
        f'"{sys.executable}" -m gearsim.cli hil to-csv "{work["log"]}" --rig gear '
        f'--dt 1e-5 -o - 2>"{work["dir"] / "err.txt"}" | head -n 2'
    )
    res = subprocess.run(["sh", "-c", cmd], capture_output=True, env=env, timeout=120)
    assert res.stdout.decode().splitlines()[1].startswith("time,")
    assert len(res.stdout.decode().splitlines()) == 2
    err = (work["dir"] / "err.txt").read_text()  # the resampling warning, nothing else
    assert err.count("\n") == 1 and "warning:" in err, err


# -- 3. time jumps, mixed absolute and relative timestamps ---------------------------------
def test_logconvert_asc_mixing_relative_and_absolute_time_is_refused(
    work: dict[str, Path], capsys: pytest.CaptureFixture
) -> None:
    """A reported failure, reproduced: a .blf whose first frames are relative and
    the rest absolute, converted by python-can's own can.logconvert; to-csv
    tried to allocate 1.31 TiB, replay 65 TiB."""
    d = work["dir"]
    blf = d / "mixed.blf"
    _rewrite(work["log"], blf, lambda i, t: t + (EPOCH if i >= 40 else 0.0))
    asc = d / "mixed.asc"
    subprocess.run(
        [sys.executable, "-m", "can.logconvert", str(blf), str(asc)],
        check=True,
        capture_output=True,
        timeout=120,
    )
    before = _snapshot(d)
    for log in (asc, blf):
        rc, out, err = _run(capsys, "hil", "to-csv", log, "--rig", "gear", "-o", d / "m.csv")
        assert rc == 2 and out == ""
        line = _one_error_line(err, "frame 41", "jumps forward by 1.7956e+09 s", "--max-gap")
        assert line.startswith(f"gearsim hil to-csv: error: {log}: ")
        rc, out, err = _run(
            capsys, "hil", "replay", log, "--model", work["model"], "-o", d / "m.asc"
        )
        assert rc == 2 and out == ""
        _one_error_line(err, "frame 41", "jumps forward", "--max-gap")
    assert _snapshot(d) == before


def test_time_going_back_is_refused(work: dict[str, Path], capsys: pytest.CaptureFixture) -> None:
    log = work["dir"] / "back.csv"  # (python-can's .asc, .log and .blf writers clamp it)
    _rewrite(work["log"], log, lambda i, t: t + (EPOCH if i < 10 else 0.0))
    for argv in (
        ["to-csv", log, "--rig", "gear", "-o", work["dir"] / "b.csv"],
        ["replay", log, "--model", work["model"]],
    ):
        rc, _, err = _run(capsys, "hil", *argv)
        assert rc == 2
        _one_error_line(err, "frame 11", "goes back by")


def test_a_long_pause_needs_max_gap_and_replays_in_bounded_chunks(
    work: dict[str, Path], capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    from gearsim.hil import bridge as bridge_mod
    from gearsim.hil.bridge import CHUNK_STEPS

    log = work["dir"] / "pause.log"
    _rewrite(work["log"], log, lambda i, t: t + (70.0 if i >= 50 else 0.0))
    rc, _, err = _run(capsys, "hil", "replay", log, "--model", work["model"])
    assert rc == 2
    _one_error_line(err, "frame 51", "jumps forward by 70", "limit of 60 s")

    calls: list[int] = []
    original = bridge_mod.Bridge._run_c

    def spy(self: Any, periods: int) -> None:
        calls.append(periods)
        original(self, periods)

    monkeypatch.setattr(bridge_mod.Bridge, "_run_c", spy)
    rc, out, err = _run(
        capsys,
        "hil",
        "replay",
        log,
        "--model",
        work["model"],
        "--max-gap",
        "100",
        "--substeps",
        "4",
        "--json",
    )
    assert rc == 0, err
    # 70 s at 1 ms x 4 sub-steps is 280 000 rig steps: never one C call (Ctrl-C waits
    # for the call to return)
    assert sum(calls) >= 70_000 and max(calls) * 4 <= CHUNK_STEPS
    # to-csv holds the last values across the pause, within the sample limit
    rc, out, err = _run(
        capsys,
        "hil",
        "to-csv",
        log,
        "--rig",
        "gear",
        "--max-gap",
        "100",
        "-o",
        work["dir"] / "p.csv",
    )
    assert rc == 0, err
    assert out.startswith("wrote ")


def test_grids_over_the_sample_limit_are_refused(
    work: dict[str, Path], capsys: pytest.CaptureFixture
) -> None:
    out = work["dir"] / "g.csv"
    for extra, needle in (
        (["--dt", "1e-9"], "limit of 5000000"),
        (["--max-samples", "10"], "limit of 10"),
        (["--dt", "1e-320"], "inf samples"),
    ):
        rc, _, err = _run(capsys, "hil", "to-csv", work["log"], "--rig", "gear", *extra, "-o", out)
        assert rc == 2
        _one_error_line(err, needle, "--max-samples")
        assert not out.exists()


def test_non_finite_timestamps_are_refused(
    work: dict[str, Path], capsys: pytest.CaptureFixture
) -> None:
    log = work["dir"] / "nan.csv"
    _rewrite(work["log"], log, lambda i, t: t)
    lines = log.read_text().splitlines()
    head, fields = lines[0], lines[6].split(",")
    assert head.startswith("timestamp,")
    fields[0] = "nan"
    lines[6] = ",".join(fields)
    log.write_text("\n".join(lines) + "\n")
    for argv in (
        ["to-csv", log, "--rig", "gear", "-o", work["dir"] / "n.csv"],
        ["replay", log, "--model", work["model"]],
    ):
        rc, _, err = _run(capsys, "hil", *argv)
        assert rc == 2
        _one_error_line(err, "frame 6", "not a finite number")


@pytest.mark.parametrize(
    "option, value",
    [("--max-gap", "0"), ("--max-gap", "nan"), ("--max-gap", "-1"), ("--tail", "inf")],
)
def test_bad_limits_are_refused(
    work: dict[str, Path], capsys: pytest.CaptureFixture, option: str, value: str
) -> None:
    rc, _, err = _run(capsys, "hil", "replay", work["log"], "--model", work["model"], option, value)
    assert rc == 2
    _one_error_line(err, option)


# -- 4. compressed logs ----------------------------------------------------------------------
def _gz(src: Path, dst: Path) -> None:
    with open(src, "rb") as fi, gzip.open(dst, "wb") as fo:
        shutil.copyfileobj(fi, fo)


@pytest.mark.parametrize(
    "name",
    ["s.asc.gz", "s.log.gz", "s.csv.gz", "s.trc.gz", "s.blf", "s.blf.gz", "bench.run.1.asc.gz"],
)
def test_compressed_logs_work_for_to_csv_and_replay(
    work: dict[str, Path], capsys: pytest.CaptureFixture, name: str
) -> None:
    d = work["dir"]
    plain = d / "plain.asc"
    _rewrite(work["log"], plain, lambda i, t: t)
    log = d / name
    if name == "s.blf.gz":
        _gz(work["log"], log)  # python-can reads it; it does not write it
    elif name.count(".") > 2:
        _gz(plain, log)  # python-can's Logger wants exactly two suffixes
    else:
        _rewrite(work["log"], log, lambda i, t: t)
    if name.endswith(".gz"):
        with gzip.open(log) as fh:
            fh.read(1)  # really compressed

    results = {}
    for src in (plain, log):
        csv_path = d / f"{src.name}.csv"
        answers = d / f"{src.name}.answers.log"
        rc, _, err = _run(capsys, "hil", "to-csv", src, "--rig", "gear", "-o", csv_path)
        assert rc == 0, err
        rc, out, err = _run(capsys, "hil", "replay", src, "--model", work["model"], "-o", answers)
        assert rc == 0, err
        assert "replayed 102 frames, answered 72 frames" in out
        results[src] = (csv_path.read_text(), answers.read_text())
    assert results[log] == results[plain]


@pytest.mark.parametrize("suffix", [".asc.gz", ".log.gz", ".csv.gz"])
def test_replay_writes_compressed_answers(
    work: dict[str, Path], capsys: pytest.CaptureFixture, suffix: str
) -> None:
    d = work["dir"]
    plain, packed = d / ("a" + suffix[:-3]), d / ("a" + suffix)
    for out in (plain, packed):
        rc, _, err = _run(capsys, "hil", "replay", work["log"], "--model", work["model"], "-o", out)
        assert rc == 0, err
    with gzip.open(packed) as fh:
        fh.read(1)

    def frames(p: Path) -> list[tuple[float, int, bytes]]:
        return [
            (round(m.timestamp, 6), m.arbitration_id, bytes(m.data)) for m in can.LogReader(str(p))
        ]

    assert frames(packed) == frames(plain) and len(frames(plain)) == 72
    assert not [p for p in d.iterdir() if p.name.startswith(".")]


@pytest.mark.parametrize("kind", ["truncated.asc.gz", "garbage.blf", "garbage.log.gz"])
def test_corrupt_logs_are_bad_input(
    work: dict[str, Path], capsys: pytest.CaptureFixture, kind: str
) -> None:
    d = work["dir"]
    log = d / kind
    if kind == "truncated.asc.gz":
        full = d / "full.asc.gz"
        _rewrite(work["log"], full, lambda i, t: t)
        log.write_bytes(full.read_bytes()[:500])
    else:
        log.write_bytes(b"\x00\x01 this is not a log \xff" * 20)
    for argv in (
        ["to-csv", log, "--rig", "gear", "-o", d / "c.csv"],
        ["replay", log, "--model", work["model"], "-o", d / "c.asc"],
    ):
        rc, _, err = _run(capsys, "hil", *argv)
        assert rc == 2
        _one_error_line(err, kind)
        assert not (d / "c.csv").exists() and not (d / "c.asc").exists()


# -- 5. a replay that drives nothing fails ---------------------------------------------------
def test_replay_with_every_frame_rejected_fails(
    work: dict[str, Path], capsys: pytest.CaptureFixture
) -> None:
    d = work["dir"]
    before = _snapshot(d)
    rc, out, err = _run(
        capsys, "hil", "replay", work["log"], "--model", work["rack"], "-o", d / "r.asc", "--json"
    )
    assert rc == 2 and out == ""
    _one_error_line(
        err,
        "all 102 frames were rejected",
        "rejected.unknown_id 102",
        "rack_pinion",
        "rack_rig.dbc",
    )
    assert _snapshot(d) == before


def test_replay_of_a_log_without_commands_fails(
    work: dict[str, Path], capsys: pytest.CaptureFixture
) -> None:
    log = work["dir"] / "feedback-only.asc"
    msgs = [m for m in can.LogReader(str(work["log"])) if m.arbitration_id != 0x100]
    with can.Logger(str(log)) as out:
        for m in msgs:
            out.on_message_received(m)
    rc, _, err = _run(capsys, "hil", "replay", log, "--model", work["model"])
    assert rc == 2
    _one_error_line(err, f"none of the {len(msgs)} frames", f"ignored.feedback_id {len(msgs)}")


# -- 6. user data is escaped -----------------------------------------------------------------
def test_messages_escape_user_data(work: dict[str, Path], capsys: pytest.CaptureFixture) -> None:
    d = work["dir"]
    evil = d / "evil\x1b[31m\rname.blf"
    rc, _, err = _run(capsys, "hil", "replay", evil, "--model", work["model"])
    assert rc == 2
    _one_error_line(err, "evil\\x1b[31m\\rname", "no such log file")
    rc, _, err = _run(capsys, "hil", "to-csv", evil, "--rig", "gear", "-o", d / "x.csv")
    assert rc == 2
    _one_error_line(err, "evil\\x1b[31m\\rname")

    shutil.copyfile(work["log"], d / "ok\x1b.blf")
    out = d / "new\nline.csv"
    rc, text, err = _run(capsys, "hil", "to-csv", d / "ok\x1b.blf", "--rig", "gear", "-o", out)
    assert rc == 0, err
    assert "\x1b" not in text and "new\\nline.csv" in text.splitlines()[0]
    assert out.read_text().splitlines()[1].startswith("time,")
    # a bad DBC path is echoed escaped as well
    rc, _, err = _run(
        capsys, "hil", "to-csv", work["log"], "--dbc", d / "no\x07such.dbc", "-o", d / "y.csv"
    )
    assert rc == 2
    _one_error_line(err, "no\\x07such.dbc")
