"""``mdle run --foxglove``: a real run watched by a WebSocket client of our own.

The client speaks Foxglove's WebSocket protocol (``foxglove.websocket.v1``, which the
foxglove-sdk now names ``foxglove.sdk.v1``) with the ``websockets`` package, not the
SDK that serves it: it reads the server's channel advertisement, subscribes, and
decodes the binary message frames with mcap-ros2-support from the advertised schemas.
"""

from __future__ import annotations

import asyncio
import json
import math
import os
import struct
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("foxglove")
websockets = pytest.importorskip("websockets")

PLAN = """\
atom cruise = (go(0.3 m/s), min_range(-30 deg, 30 deg) < 0.8 m, 3 s)
atom hug = (follow_boundary(side = right, rc = 0.6 m, v = 0.3 m/s), never, inf)
plan main = ((cruise, hug), never, inf)
run main
"""

#: The subprotocol foxglove-sdk 0.30 serves: foxglove.websocket.v1's ops and frames, renamed.
PROTOCOL = "foxglove.sdk.v1"

WANTED = ("/scan", "/footprint", "/mdle/active", "/mdle/state", "/mdle/diagnostics", "/map",
          "/mdle/events")


def _mdle() -> list[str]:
    exe = Path(sys.executable).with_name("mdle")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "mdle"]


async def _watch(url: str, wanted: tuple[str, ...], seconds: float,
                 until: Any = None) -> tuple[dict[str, Any], dict[str, list[Any]]]:
    """Subscribe to ``wanted`` on every advertisement and decode what comes.

    Return the advertised channels and the decoded messages, after ``seconds`` or as soon
    as ``until(got)`` is true, or when the server closes.
    """
    from mcap.records import Schema
    from mcap_ros2.decoder import DecoderFactory

    factory = DecoderFactory()
    got: dict[str, list[Any]] = {t: [] for t in wanted}
    channels: dict[str, Any] = {}
    async with websockets.connect(url, subprotocols=[PROTOCOL],
                                  proxy=None) as ws:  # loopback, never a proxy
        assert ws.subprotocol == PROTOCOL
        subscribed: dict[int, tuple[str, Any]] = {}
        loop = asyncio.get_running_loop()
        end = loop.time() + seconds
        while loop.time() < end and not (until is not None and until(got)):
            try:
                frame = await asyncio.wait_for(ws.recv(),
                                               timeout=max(0.05, min(1.0, end - loop.time())))
            except asyncio.TimeoutError:
                continue
            except websockets.ConnectionClosed:
                break
            if isinstance(frame, str):
                op = json.loads(frame)
                if op.get("op") != "advertise":
                    continue
                subs = []
                for ch in op["channels"]:
                    channels[ch["topic"]] = ch
                    if ch["topic"] in wanted:
                        sub = len(subscribed) + 1
                        schema = Schema(id=sub, name=ch["schemaName"],
                                        encoding=ch["schemaEncoding"],
                                        data=ch["schema"].encode())
                        subscribed[sub] = (ch["topic"],
                                           factory.decoder_for(ch["encoding"], schema))
                        subs.append({"id": sub, "channelId": ch["id"]})
                if subs:
                    await ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
            else:
                opcode, sub, _ = struct.unpack_from("<BIQ", frame)
                if opcode == 1 and sub in subscribed:  # message data
                    topic, decode = subscribed[sub]
                    got[topic].append(decode(frame[13:]))
    return channels, got


def test_a_client_subscribes_and_decodes_a_live_run(tmp_path: Path) -> None:
    plan = tmp_path / "p.mdle"
    plan.write_text(PLAN)
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(
        [*_mdle(), "run", str(plan), "--world", "default", "--rate", "10", "--realtime",
         "--until", "8", "--foxglove", "0", "--record", str(tmp_path / "r.mcap")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=tmp_path)
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        while line and not line.startswith("live view:"):
            line = proc.stdout.readline()
        assert line.startswith("live view: ws://127.0.0.1:"), line  # loopback by default
        url = line.split()[2]
        time.sleep(1.0)  # the run is under way: /map and /tf_static went out already
        channels, got = asyncio.run(_watch(url, WANTED, 6.0))
    finally:
        out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert channels["/scan"]["schemaName"] == "sensor_msgs/msg/LaserScan"
    assert channels["/scan"]["encoding"] == "cdr"
    assert channels["/scan"]["schemaEncoding"] == "ros2msg"
    # the scan: a 181-beam LMS-200 in the robot's laser frame
    assert len(got["/scan"]) >= 10
    scan = got["/scan"][-1]
    assert scan.header.frame_id == "laser" and len(scan.ranges) == 181
    assert np.isclose(scan.angle_min, -np.pi / 2) and np.isclose(scan.angle_max, np.pi / 2)
    ranges = np.asarray(scan.ranges)
    hits = ranges[np.isfinite(ranges)]  # +inf: no return (REP-117)
    assert len(hits) > 90 and np.all((hits >= scan.range_min) & (hits <= scan.range_max))
    # the footprint: the pioneer2dx's disc of 0.25 m in base_link
    poly = got["/footprint"][-1]
    assert poly.header.frame_id == "base_link"
    r = np.hypot([p.x for p in poly.polygon.points], [p.y for p in poly.polygon.points])
    assert len(r) == 24 and np.all((r >= 0.25 - 1e-6) & (r < 0.26))
    # the state: the running element, and the trace's sample line
    states = [json.loads(m.data) for m in got["/mdle/state"]]
    assert len(states) >= 10 and all(s["type"] == "sample" for s in states)
    assert [s["t"] for s in states] == sorted(s["t"] for s in states)
    active = [m.data for m in got["/mdle/active"]]
    assert active and set(active) <= {"main/cruise", "main/hug", ""}
    assert {s["path"] for s in states} <= {"main/cruise", "main/hug", ""}
    # one diagnostics message per state line: each channel counts from its own subscription
    # (the views subscribe as the channels are advertised), so over the times both saw
    diag_t = [round(d.header.stamp.sec + d.header.stamp.nanosec * 1e-9, 6)
              for d in got["/mdle/diagnostics"]]
    state_t = [round(s["t"], 6) for s in states]
    first, last = max(diag_t[0], state_t[0]), min(diag_t[-1], state_t[-1])
    assert last - first > 2.0
    assert [t for t in diag_t if first <= t <= last] == [t for t in state_t if first <= t <= last]
    # the events: cruise's timer ends it at 3 s and hug starts, two seconds after we came
    events = [json.loads(m.data) for m in got["/mdle/events"]]
    assert {(e["kind"], e["path"], e["cause"]) for e in events if e["type"] == "event"} >= {
        ("end", "main/cruise", "timer"), ("start", "main/hug", None)}
    diag = got["/mdle/diagnostics"][-1]  # hug's law records its numbers
    assert diag.rc == 0.6 and math.isfinite(diag.side_range)
    # /map was published once, at the first tick, before the client came (it connected
    # a second into the run): it is sent again when the client subscribes
    (grid,) = got["/map"]
    assert grid.info.width > 0 and 100 in set(grid.data)


def test_bad_addresses_are_refused_with_a_message(tmp_path: Path) -> None:
    plan = tmp_path / "p.mdle"
    plan.write_text(PLAN)
    for bad, words in (("localhost:http", "expected [HOST:]PORT"),
                       ("70000", "the port must be 0-65535")):
        proc = subprocess.run([*_mdle(), "run", str(plan), "--until", "1", "--foxglove", bad],
                              capture_output=True, text=True, timeout=60, cwd=tmp_path)
        assert proc.returncode == 1 and words in proc.stderr and "Traceback" not in proc.stderr


def _changes(active: list[Any]) -> list[str]:
    """The states of ``/mdle/active`` messages, a repeated one once."""
    states = [m.data for m in active]
    return [s for i, s in enumerate(states) if i == 0 or s != states[i - 1]]


def test_a_team_and_a_repl_session_are_shown_live(tmp_path: Path) -> None:
    team = Path(__file__).resolve().parents[2] / "plans" / "team" / "pair.team.yaml"
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    # a team: every robot's topics under its name, on one server
    proc = subprocess.Popen(
        [*_mdle(), "run", "--team", str(team), "--realtime", "--until", "4",
         "--foxglove", "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env=env, cwd=tmp_path)
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert line.startswith("live view: ws://127.0.0.1:"), line
        wanted = ("/leader/footprint", "/follower/footprint", "/leader/scan",
                  "/follower/mdle/active")
        _, got = asyncio.run(_watch(line.split()[2], wanted, 60.0,
                                    lambda g: all(len(g[t]) >= 3 for t in wanted[:3])))
    finally:
        proc.communicate(timeout=60)
    assert proc.returncode == 0
    assert {m.header.frame_id for m in got["/leader/footprint"]} == {"leader/base_link"}
    assert {m.header.frame_id for m in got["/follower/footprint"]} == {"follower/base_link"}
    assert {m.header.frame_id for m in got["/leader/scan"]} == {"leader/laser"}
    # a REPL session: each run advertises its topics, and its element is the state
    repl = subprocess.Popen(
        [*_mdle(), "repl", "--plain", "--realtime", "--foxglove", "0"], stdin=subprocess.PIPE,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=tmp_path)
    try:
        assert repl.stdout is not None and repl.stdin is not None
        line = repl.stdout.readline()
        while line and not line.startswith("live view:"):
            line = repl.stdout.readline()
        assert line.startswith("live view: ws://127.0.0.1:"), line
        # spin lasts 6 s: on a loaded machine the client's subscription to a run's scan can
        # come a second or two after the run advertised it (the latched state never misses)
        repl.stdin.write("atom cruise = (go(0.2 m/s), never, 2 s)\n"
                         "atom spin = (turn(20 deg/s), never, 6 s)\ncruise\nspin\n")
        repl.stdin.flush()
        _, got = asyncio.run(_watch(
            line.split()[2], ("/mdle/active", "/scan"), 60.0,
            lambda g: len(_changes(g["/mdle/active"])) >= 4 and bool(g["/scan"])))
    finally:
        repl.communicate("", timeout=60)
    assert repl.returncode == 0
    # the state as it changes (latched: a client that subscribed late gets it too; a
    # subscription at the very moment it changes may get it twice)
    assert _changes(got["/mdle/active"])[:4] == ["cruise", "", "spin", ""]
    assert got["/scan"]
