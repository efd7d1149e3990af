"""A test host for the bridge (or a real rig): sends a command profile on a
python-can bus and records both directions into a log.

Run the bridge in one shell and this in another, on an interface both
processes share (SocketCAN `vcan0`/`can0`, or `udp_multicast` without AF_CAN):

    gearsim hil run --model examples/hil/gear_model.toml -i socketcan -c vcan0 --log rig.blf
    python examples/hil/host.py -i socketcan -c vcan0 --seconds 20 --log host.blf

or against the C runner's socketcand server, with no kernel CAN at all
(docs/hil.md, "A test campaign"):

    build/hil/gearsim-hil --params gear.params --transport socketcand --wait-client &
    python examples/hil/host.py -i socketcand --host 127.0.0.1 --port 29536 -c can0 --log host.log

    gearsim hil to-csv rig.blf --rig gear -o bench.csv
    gearsim compare bench.csv --model examples/hil/gear_model.toml

Convert the bridge's own recording (rig.blf: stamped in rig time, so the CSV
says at which step every command acted). This host's recording (host.blf) is
stamped with its wall clock: to-csv resamples it and warns that the model
cannot reproduce it step for step.

The profile: base speed 20 sin(2 pi 0.25 t) + 5 rad/s (pinion: the same), load
a slow square wave (gear 0.4 N*m, rack 40 N), a command every 10 ms. This host
does not watch the feedback (it reacts to no fault); when the rig goes away
(the runner ended its scenario) it stops and keeps its recording.
"""

from __future__ import annotations

import argparse
import math
import time

import can

from gearsim.hil import RigDbc


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-i", "--interface", default="socketcan")
    ap.add_argument("-c", "--channel", default="vcan0")
    ap.add_argument("--host", default="127.0.0.1", help="-i socketcand: the server's address")
    ap.add_argument("--port", type=int, default=29536, help="-i socketcand: its port")
    ap.add_argument("--rig", choices=("gear", "rack"), default="gear")
    ap.add_argument("--dbc", help="DBC (default: the shipped one for --rig)")
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--log", default="bench.blf")
    args = ap.parse_args()
    dbc = RigDbc(args.dbc, block=args.rig)
    load_amp = 0.4 if args.rig == "gear" else 40.0
    where = {"host": args.host, "port": args.port} if args.interface == "socketcand" else {}
    with (
        can.Bus(interface=args.interface, channel=args.channel, **where) as bus,
        can.Logger(args.log) as logger,
    ):
        try:
            sent, received = _drive(args, dbc, bus, logger, load_amp)
        except (can.CanError, OSError):  # the rig went away: the recording so far is kept
            sent = received = -1
    if sent < 0:
        print(f"the rig went away; the recording is in {args.log}")
        return
    print(f"sent {sent} commands, recorded {received} frames from the rig into {args.log}")


def _drive(
    args: argparse.Namespace, dbc: RigDbc, bus: can.BusABC, logger: can.Logger, load_amp: float
) -> tuple[int, int]:
    """The command profile for args.seconds; returns (commands sent, frames received)."""
    sent = received = 0
    start = time.perf_counter()
    k = 0
    while (now := time.perf_counter() - start) < args.seconds:
        t = k * 0.01
        if now >= t:
            values = {
                "cmd.base_speed": 20.0 * math.sin(2 * math.pi * 0.25 * t) + 5.0,
                "cmd.load": load_amp if int(t / 2.0) % 2 == 0 else -load_amp,
                "cmd.mode": "speed",
            }
            for msg in dbc.encode_command(values):
                msg.timestamp = time.time()
                msg.is_rx = False
                bus.send(msg)
                logger.on_message_received(msg)
                sent += 1
            k += 1
        msg = bus.recv(timeout=max(0.0, min(0.002, start + k * 0.01 - time.perf_counter())))
        if msg is not None:
            logger.on_message_received(msg)
            received += 1
    return sent, received


if __name__ == "__main__":
    main()
