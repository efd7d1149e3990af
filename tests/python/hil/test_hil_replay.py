"""Replay: a log recorded with python-can's Logger drives the model in log time,
deterministically."""

from __future__ import annotations

import math
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from hil_helpers import RigDbc, can, gear_model, rack_model, read_frames, record_session

from gearsim.hil import replay


def _gear_profile(k: int) -> dict[str, Any]:
    return {
        "base_speed": 30.0 * math.sin(2 * math.pi * k / 250),
        "load": 0.5 * math.cos(k / 40.0),
        "mode": "speed",
    }


def _silent(k: int) -> bool:
    return 300 <= k < 420  # 120 ms without commands: the 50 ms timeout fires once


@pytest.mark.parametrize("suffix", [".asc", ".blf", ".log", ".csv", ".trc"])
def test_replay_gives_the_live_answers_twice(tmp_path: Path, suffix: str, gear_dbc: RigDbc) -> None:
    model = gear_model()
    log = tmp_path / f"session{suffix}"
    live, live_summary = record_session(
        model, gear_dbc, log, _gear_profile, periods=600, silent=_silent
    )
    assert live_summary["timeouts"] == 1 and live_summary["recoveries"] == 1
    answers = []
    for run in range(2):
        out = tmp_path / f"answers{run}{suffix}"
        res = replay(model, log, out, period=1e-3, timeout=0.05)
        assert res.frames_in == len(live) + live_summary["rx_total"]
        c = res.summary
        # the recorded feedback is ignored; every command is used again, in log time
        assert c["rx_used"] == live_summary["rx_used"] and c["rx_rejected"] == 0
        assert c["reasons"] == {"ignored.feedback_id": len(live)}
        assert (c["timeouts"], c["recoveries"]) == (1, 1)
        assert res.frames_out == len(live)
        answers.append(read_frames(out))
    assert answers[0] == answers[1]
    # and they are the live answers (times relative to the log's first frame, t = 0), except
    # that the replay also counts the recorded feedback it ignores
    assert [t for t, _, _ in answers[0]] == pytest.approx(
        [t - live[0][0] for t, _, _ in live], abs=2e-6
    )
    assert _values(gear_dbc, answers[0]) == _values(gear_dbc, live)
    assert _values(gear_dbc, answers[0], keep_ignored=True) != _values(
        gear_dbc, live, keep_ignored=True
    )


def _values(dbc: RigDbc, frames: list, keep_ignored: bool = False) -> list:
    out = []
    for _, i, data in frames:
        values = dbc.decode_feedback(dbc.by_key[(i, False)], data)
        if not keep_ignored:
            values.pop("status.count.rx_ignored", None)
        out.append((i, values))
    return out


def test_replay_rack_with_substeps_and_input_copy(tmp_path: Path, rack_dbc: RigDbc) -> None:
    model = rack_model()
    log = tmp_path / "rack.asc"
    live, summary = record_session(
        model,
        rack_dbc,
        log,
        lambda k: {"base_speed": 10.0 * math.sin(k / 50.0), "load": 40.0},
        periods=400,
        period=2e-3,
        substeps=5,
    )
    out = tmp_path / "rack-answers.blf"
    res = replay(model, log, out, period=2e-3, substeps=5, with_input=True)
    frames = read_frames(out)
    # the answers plus a copy of every input frame
    assert (
        len(frames) == res.frames_out + res.frames_in == len(live) + len(live) + summary["rx_total"]
    )
    # every recorded feedback frame twice (copy and answer), but for the RackCounters frame,
    # whose RxIgnored differs (the replay ignores the recorded feedback)
    ids = {f.frame_id for f in rack_dbc.feedback} - {0x311}
    copied = Counter((i, d) for _, i, d in frames if i in ids)
    assert copied == Counter(
        {k: 2 * n for k, n in Counter((i, d) for _, i, d in live if i in ids).items()}
    )


def test_replay_runs_a_tail_and_needs_no_output(tmp_path: Path, gear_dbc: RigDbc) -> None:
    model = gear_model()
    log = tmp_path / "s.log"
    record_session(model, gear_dbc, log, _gear_profile, periods=100)
    seen: list[can.Message] = []
    res = replay(model, log, None, tail=0.5, on_answer=seen.append)
    assert res.summary["periods"] == 101 + 500
    assert len(seen) == res.frames_out > 0
    assert res.summary["timeouts"] == 1  # the commands stop at the end of the log
