"""Replay throughput (docs/hil.md, "Figures").

Records a session of the given simulated length into a log (host commands every
10 ms plus the rig's feedback, as a bench recording would hold them; made with
Bridge.advance, no wall clock), then replays it with `gearsim.hil.replay` and
prints the input frames per wall-clock second and the simulated seconds per
wall-clock second.

    python examples/hil/replay_throughput.py [--seconds 60] [--suffix .blf] [--period 0.001]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import tempfile

import can

import gearsim
from gearsim.hil import Bridge, RigDbc, replay


def record(model: gearsim.Model, dbc: RigDbc, path: str, seconds: float, period: float) -> int:
    """The session log: commands every 10 ms and the feedback, stamped with simulated time."""
    n = 0
    with can.Logger(path) as logger:

        def log(msg: can.Message) -> None:
            nonlocal n
            n += 1
            logger.on_message_received(msg)

        bridge = Bridge.from_model(model, dbc, period=period, send=log, stamp=lambda t: t)
        every = round(0.01 / period)
        for k in range(round(seconds / period)):
            if k % every == 0:
                t = k * period
                speed = 20.0 * math.sin(2 * math.pi * 0.5 * t)
                for msg in dbc.encode_command(
                    {"cmd.base_speed": speed, "cmd.load": 0.3 * math.cos(2 * math.pi * 0.2 * t)}
                ):
                    msg.timestamp = t
                    log(msg)
                    bridge.handle(msg)
            bridge.advance(1)
    return n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--suffix", default=".blf")
    ap.add_argument("--period", type=float, default=1e-3)
    ap.add_argument("--substeps", type=int, default=1)
    ap.add_argument("--model", default=os.path.join(os.path.dirname(__file__), "gear_model.toml"))
    args = ap.parse_args()
    model = gearsim.Model.load(args.model)
    dbc = RigDbc(block=model.block)
    with tempfile.TemporaryDirectory() as tmp:
        log = os.path.join(tmp, "session" + args.suffix)
        frames = record(model, dbc, log, args.seconds, args.period)
        out = os.path.join(tmp, "answers" + args.suffix)
        res = replay(model, log, out, period=args.period, substeps=args.substeps)
    print(
        json.dumps(
            {
                "log_frames": frames,
                "suffix": args.suffix,
                "simulated_seconds": args.seconds,
                "period_s": args.period,
                "substeps": args.substeps,
                "frames_in": res.frames_in,
                "frames_out": res.frames_out,
                "wall_time_s": res.wall_time,
                "input_frames_per_s": res.frames_per_second,
                "frames_in_and_out_per_s": (res.frames_in + res.frames_out) / res.wall_time,
                "simulated_s_per_wall_s": args.seconds / res.wall_time,
                "load_average": os.getloadavg(),
            },
            indent=2,
        )
    )


if __name__ == "__main__":
    main()
