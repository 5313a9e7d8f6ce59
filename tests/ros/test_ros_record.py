"""`mdle run --record/--rosbag` and `mdle export` on a real run, read back independently.

One run of a boundary-following plan on the Pioneer profile (ladar mounted 17 mm ahead
and 8 mm left, scans at 10 Hz under a 20 Hz control loop, so not every tick has a new
scan), with the trace, an MCAP file and a rosbag2 folder written at once. Every message
type is read with rosbags (Humble and Jazzy type stores) and checked field by field
against the run's trace; the export of the trace must hold the same messages byte for
byte; every file passes the strict validation.
"""

from __future__ import annotations

import json
import math
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mdle.record.load import read_trace
from mdle.record.trace import Trace, decode_ranges

PLAN = """\
atom hug = (follow_boundary(side = right, rc = 1 m, v = 0.6 m/s), never, 12 s)
atom wait = (go(0 m/s), never, 0.5 s)
plan main = ((hug, wait), never, inf)
run main
"""

# the reference `ellipse` with the Pioneer and a 10 Hz LMS-200 (the reference world scans
# at every tick)
WORLD = """name: ellipse-pioneer
seed: 3
start: {x: -9.0, y: 0.3, theta: 0}
robot: pioneer2dx
ladar: {profile: lms200}
obstacles:
  - {type: ellipse, name: ellipse, center: [0, 0], axes: [4, 2], angle: 0}
"""


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    import shutil
    import sys

    exe = Path(sys.executable).with_name("mdle")
    cmd = [str(exe)] if exe.exists() else [str(shutil.which("mdle"))]
    d = tmp_path_factory.mktemp("rec")
    plan = d / "p.mdle"
    plan.write_text(PLAN)
    (d / "w.yaml").write_text(WORLD)
    proc = subprocess.run(
        [*cmd, "run", str(plan), "--world", str(d / "w.yaml"), "--rate", "20",
         "--trace", str(d / "t.jsonl"), "--record", str(d / "r.mcap"), "--rosbag",
         str(d / "bag"), "-q"], capture_output=True, text=True, timeout=120, cwd=d)
    assert proc.returncode == 0, proc.stderr
    exported = subprocess.run([*cmd, "export", str(d / "t.jsonl"), "-o", str(d / "e.mcap")],
                              capture_output=True, text=True, timeout=120, cwd=d)
    assert exported.returncode == 0, exported.stderr
    return {"dir": d, "trace": read_trace(d / "t.jsonl"), "cmd": cmd,
            "export_out": exported.stdout}


def _ns(t: float) -> int:
    return round(t * 1e9)


def _stamp(header: Any) -> int:
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


def _yaw(q: Any) -> float:
    assert q.x == 0.0 and q.y == 0.0
    assert math.isclose(q.z * q.z + q.w * q.w, 1.0, rel_tol=1e-12)
    return 2.0 * math.atan2(q.z, q.w)


def _same_angle(a: float, b: float) -> bool:
    return abs(math.remainder(a - b, math.tau)) < 1e-9


def _compressions(path: Path) -> set[str]:
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None and summary.chunk_indexes
    return {c.compression for c in summary.chunk_indexes}


def test_files_pass_strict_validation(run: dict[str, Any], doctor: Any) -> None:
    d = run["dir"]
    counts = doctor(d / "r.mcap")
    assert doctor(d / "e.mcap") == counts
    assert doctor(d / "bag" / "bag_0.mcap") == counts
    # a live recording's chunks are not compressed by default (the cheapest to write),
    # an export's are (lz4)
    assert _compressions(d / "r.mcap") == {""} == _compressions(d / "bag" / "bag_0.mcap")
    assert _compressions(d / "e.mcap") == {"lz4"}


def test_topic_counts_match_the_trace(run: dict[str, Any], rosbags_read: Any) -> None:
    tr: Trace = run["trace"]
    msgs = rosbags_read(run["dir"] / "r.mcap")
    counts: dict[str, int] = {}
    for m in msgs:
        counts[m.topic] = counts.get(m.topic, 0) + 1
    n = len(tr.samples)
    assert n > 200
    assert len(tr.scans) < n  # 10 Hz scans under a 20 Hz loop
    starts = [r for r in tr.extra if r["type"] == "start"]
    changes = sum(1 for i, s in enumerate(tr.samples)
                  if i == 0 or s["path"] != tr.samples[i - 1]["path"])
    assert counts == {"/scan": len(tr.scans), "/odom": n, "/tf": n, "/tf_static": 1,
                      "/cmd_vel": n, "/ground_truth": n, "/footprint": n,
                      "/path": math.ceil((n - 1) / 10), "/map": 1,
                      "/obstacles": 1, "/mdle/events": len(tr.events) + len(starts) + 1,
                      "/mdle/active": changes, "/mdle/diagnostics": n, "/mdle/state": n}
    assert changes == 3  # main/hug, main/wait, "" at the end


def test_scan_messages(run: dict[str, Any], rosbags_read: Any, store: str) -> None:
    tr: Trace = run["trace"]
    scans = [m for m in rosbags_read(run["dir"] / "r.mcap", store) if m.topic == "/scan"]
    (laser,) = tr.lasers
    assert laser["mount"] == [0.017, 0.008, 0.0]
    assert len(scans) == len(tr.scans)
    for m, rec in zip(scans, tr.scans, strict=True):
        s = m.msg
        assert m.msgtype == "sensor_msgs/msg/LaserScan"
        assert s.header.frame_id == "laser"
        assert _stamp(s.header) == _ns(rec["stamp"]) and m.log_time == _ns(rec["t"])
        assert s.angle_min == np.float32(-math.pi / 2) and s.angle_max == np.float32(math.pi / 2)
        assert s.angle_increment == np.float32(math.radians(1.0))
        assert s.range_min == 0.0 and s.range_max == 10.0
        # scans every 0.1 s (the 10 Hz LMS-200), each taken at one instant (simulated)
        assert s.scan_time == np.float32(laser["scan_time"]) == np.float32(0.1)
        assert s.time_increment == 0.0 == laser["time_increment"] and len(s.intensities) == 0
        ranges = np.asarray(s.ranges)
        assert ranges.dtype == np.float32 and len(ranges) == 181
        np.testing.assert_array_equal(ranges, decode_ranges(rec["ranges"]))
        # no return: +inf (REP-117); a return: within the sensor's range
        finite = np.isfinite(ranges)
        assert np.all(np.isposinf(ranges[~finite]))
        assert np.all((ranges[finite] >= 0) & (ranges[finite] <= 10.0))
    # the robot follows the ellipse: some beams hit it, some see nothing
    all_ranges = np.concatenate([np.asarray(m.msg.ranges) for m in scans])
    assert np.isfinite(all_ranges).any() and np.isinf(all_ranges).any()


def test_scan_hits_lie_on_the_ellipse(run: dict[str, Any], rosbags_read: Any) -> None:
    """A beam's hit, placed with /ground_truth, /tf_static and the scan angles, is on it."""
    msgs = rosbags_read(run["dir"] / "r.mcap")
    truth = {m.log_time: m.msg.pose for m in msgs if m.topic == "/ground_truth"}
    (static,) = [m.msg.transforms[0] for m in msgs if m.topic == "/tf_static"]
    mx, my = static.transform.translation.x, static.transform.translation.y
    checked = 0
    for m in msgs:
        if m.topic != "/scan" or m.log_time not in truth:
            continue
        s = m.msg
        p = truth[m.log_time]
        th = _yaw(p.orientation)
        a = s.angle_min + s.angle_increment * np.arange(len(s.ranges))
        r = np.asarray(s.ranges, dtype=float)
        ok = np.isfinite(r)
        ox = p.position.x + math.cos(th) * mx - math.sin(th) * my
        oy = p.position.y + math.sin(th) * mx + math.cos(th) * my
        x = ox + r[ok] * np.cos(th + a[ok])
        y = oy + r[ok] * np.sin(th + a[ok])
        # ellipse x^2/16 + y^2/4 = 1; ranges carry 0.8 % noise
        rho = np.sqrt(x ** 2 / 16 + y ** 2 / 4)
        assert np.all(np.abs(rho - 1.0) < 0.06), float(np.abs(rho - 1).max())
        checked += int(ok.sum())
    assert checked > 1000


def test_odometry_transforms_command_truth(run: dict[str, Any], rosbags_read: Any,
                                           store: str) -> None:
    tr: Trace = run["trace"]
    msgs = rosbags_read(run["dir"] / "r.mcap", store)
    by = {t: [m for m in msgs if m.topic == t]
          for t in ("/odom", "/tf", "/cmd_vel", "/ground_truth", "/mdle/state")}
    for i, s in enumerate(tr.samples):
        ns = _ns(s["t"])
        odom, tf, cmd, truth, state = (by[t][i] for t in by)
        assert {odom.log_time, tf.log_time, cmd.log_time, truth.log_time,
                state.log_time} == {ns}
        o = odom.msg
        assert (o.header.frame_id, o.child_frame_id) == ("odom", "base_link")
        assert _stamp(o.header) == ns
        assert (o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z) == (
            s["x"], s["y"], 0.0)
        assert _same_angle(_yaw(o.pose.pose.orientation), s["theta"])
        assert o.pose.pose.orientation.z == math.sin(s["theta"] / 2)
        assert o.twist.twist.linear.x == s["v"] and o.twist.twist.angular.z == s["omega"]
        # the pioneer2dx's odometry has no noise model: exact, and 0 says so
        assert not np.any(o.pose.covariance) and len(o.pose.covariance) == 36
        assert not np.any(o.twist.covariance)
        c = cmd.msg
        assert (c.linear.x, c.linear.y, c.angular.z) == (s["cmd_v"], 0.0, s["cmd_omega"])
        g = truth.msg
        assert g.header.frame_id == "map" and _stamp(g.header) == ns
        assert (g.pose.position.x, g.pose.position.y) == (s["true_x"], s["true_y"])
        assert _same_angle(_yaw(g.pose.orientation), s["true_theta"])
        base, fix = tf.msg.transforms
        assert (base.header.frame_id, base.child_frame_id) == ("odom", "base_link")
        assert (fix.header.frame_id, fix.child_frame_id) == ("map", "odom")
        assert _stamp(base.header) == _stamp(fix.header) == ns
        assert (base.transform.translation.x, base.transform.translation.y) == (s["x"], s["y"])
        # map -> odom composed with odom -> base_link is the true pose
        phi = _yaw(fix.transform.rotation)
        c_, s_ = math.cos(phi), math.sin(phi)
        x = fix.transform.translation.x + c_ * s["x"] - s_ * s["y"]
        y = fix.transform.translation.y + s_ * s["x"] + c_ * s["y"]
        assert math.isclose(x, s["true_x"], abs_tol=1e-9)
        assert math.isclose(y, s["true_y"], abs_tol=1e-9)
        assert _same_angle(phi + s["theta"], s["true_theta"])
        assert json.loads(state.msg.data) == s


def test_diagnostics_active_element_and_footprint(run: dict[str, Any], rosbags_read: Any,
                                                  store: str) -> None:
    from mdle.record.describe import diagnostic_names

    tr: Trace = run["trace"]
    msgs = rosbags_read(run["dir"] / "r.mcap", store)
    diags = [m for m in msgs if m.topic == "/mdle/diagnostics"]
    assert diags[0].msgtype == "mdle_msgs/msg/Diagnostics"
    names = diagnostic_names()
    assert {"side_curvature", "side_range", "mode", "predicted_clearance"} <= set(names)
    followed = 0
    for m, s in zip(diags, tr.samples, strict=True):
        assert m.log_time == _ns(s["t"]) == _stamp(m.msg.header)
        assert m.msg.header.frame_id == "base_link"
        for name in names:  # typed numbers: the trace's, NaN where the law has none
            value = getattr(m.msg, name)
            want = (s.get("diag") or {}).get(name)
            assert (math.isnan(value) if want is None else value == float(want)), name
        followed += bool(s.get("diag"))
    assert followed > 200
    active = [(m.log_time, m.msg.data) for m in msgs if m.topic == "/mdle/active"]
    assert [a for _, a in active] == ["main/hug", "main/wait", ""]
    assert active[1][0] == _ns(next(s["t"] for s in tr.samples if s["path"] == "main/wait"))
    prints = [m for m in msgs if m.topic == "/footprint"]
    assert len(prints) == len(tr.samples)
    poly = prints[0].msg
    assert poly.header.frame_id == "base_link"
    pts = np.array([(p.x, p.y, p.z) for p in poly.polygon.points])
    # the pioneer2dx's disc of 0.25 m, drawn as a polygon around it
    r = np.hypot(pts[:, 0], pts[:, 1])
    assert len(pts) == 24 and np.all(pts[:, 2] == 0) and np.all(r >= 0.25 - 1e-6)
    assert np.all(r < 0.26)


def test_the_path_in_pieces(run: dict[str, Any], rosbags_read: Any) -> None:
    tr: Trace = run["trace"]
    pieces = [m for m in rosbags_read(run["dir"] / "r.mcap") if m.topic == "/path"]
    assert pieces[0].msgtype == "visualization_msgs/msg/Marker"
    points: list[tuple[float, float]] = []
    for k, m in enumerate(pieces):
        marker = m.msg
        assert (marker.header.frame_id, marker.ns, marker.id, marker.type) == (
            "odom", "path", k, 4)
        pts = [(p.x, p.y) for p in marker.points]
        if points:  # a piece goes on from the last point of the one before
            assert pts[0] == points[-1]
            pts = pts[1:]
        points += pts
        assert m.log_time == _stamp(marker.header)
    # every tick's odometry position, in order
    assert points == [(s["x"], s["y"]) for s in tr.samples]
    assert pieces[-1].log_time == _ns(tr.samples[-1]["t"])


def test_static_transform_map_and_events(run: dict[str, Any], rosbags_read: Any,
                                         store: str) -> None:
    tr: Trace = run["trace"]
    msgs = rosbags_read(run["dir"] / "r.mcap", store)
    (static,) = [m for m in msgs if m.topic == "/tf_static"]
    (t,) = static.msg.transforms
    assert (t.header.frame_id, t.child_frame_id) == ("base_link", "laser")
    assert (t.transform.translation.x, t.transform.translation.y,
            t.transform.translation.z) == (0.017, 0.008, 0.0)
    assert (t.transform.rotation.z, t.transform.rotation.w) == (0.0, 1.0)
    (grid,) = [m for m in msgs if m.topic == "/map"]
    assert grid.log_time == 0 and grid.msg.header.frame_id == "map"
    info = grid.msg.info
    cells = np.asarray(grid.msg.data, np.int8).reshape(info.height, info.width)
    assert info.resolution == np.float32(0.05) and set(np.unique(cells)) == {0, 100}
    # a cell is occupied where the ellipse's outline passes: its centre's distance to the
    # outline is under half a cell's diagonal... and free well away from it
    cx = info.origin.position.x + (np.arange(info.width) + 0.5) * info.resolution
    cy = info.origin.position.y + (np.arange(info.height) + 0.5) * info.resolution
    gx, gy = np.meshgrid(cx, cy)
    level = gx ** 2 / 16 + gy ** 2 / 4
    assert np.all(cells[level < 0.8] == 100) and np.all(cells[level > 1.2] == 0)
    (world,) = [m for m in msgs if m.topic == "/obstacles"]
    assert world.log_time == 0
    (marker,) = world.msg.markers
    assert marker.header.frame_id == "map" and marker.type == 4 and marker.action == 0
    assert marker.pose.orientation.w == 1.0 and marker.color.a == 1.0
    pts = np.array([(p.x, p.y, p.z) for p in marker.points])
    assert len(pts) > 30 and np.all(pts[:, 2] == 0.0)
    np.testing.assert_allclose(pts[:, 0] ** 2 / 16 + pts[:, 1] ** 2 / 4, 1.0, atol=0.02)
    assert np.allclose(pts[0], pts[-1])  # a closed outline
    events = [m for m in msgs if m.topic == "/mdle/events"]
    records = [json.loads(m.msg.data) for m in events]
    assert records[0]["type"] == "start" and records[-1] == tr.end
    assert records[1:-1] == list(tr.events)
    for m, rec in zip(events[1:], records[1:], strict=True):
        assert m.log_time == _ns(rec["t"])
    assert events[0].log_time == _ns(tr.events[0]["t"])


def test_export_writes_the_same_messages(run: dict[str, Any]) -> None:
    from mcap.reader import make_reader

    def messages(p: Path) -> list[tuple[str, int, int, bytes]]:
        # each topic's messages in the file's order (a /path piece goes after the batch
        # of ticks that completes it, and the two batch their ticks differently)
        with open(p, "rb") as f:
            found = [(c.topic, m.log_time, m.sequence, m.data)
                     for _, c, m in make_reader(f).iter_messages(log_time_order=False)]
        return sorted(found, key=lambda m: (m[0], m[2]))

    recorded = messages(run["dir"] / "r.mcap")
    assert messages(run["dir"] / "e.mcap") == recorded
    assert messages(run["dir"] / "bag" / "bag_0.mcap") == recorded
    assert f"{len(recorded)} messages on 14 topics" in run["export_out"]


def test_rosbag_folder_reads_as_ros2_bag_record_writes_it(run: dict[str, Any],
                                                          rosbags_read: Any) -> None:
    import yaml
    from rosbags.interfaces import QosDurability
    from rosbags.rosbag2 import Reader

    bag = run["dir"] / "bag"
    assert sorted(p.name for p in bag.iterdir()) == ["bag_0.mcap", "metadata.yaml"]
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert info["version"] == 9 and info["storage_identifier"] == "mcap"
    assert info["ros_distro"] == "jazzy" and info["custom_data"] == {}
    assert info["relative_file_paths"] == ["bag_0.mcap"]
    direct = rosbags_read(run["dir"] / "r.mcap")
    with Reader(bag) as reader:
        assert reader.message_count == len(direct) == info["message_count"]
        assert reader.start_time == 0
        assert reader.duration == direct[-1].log_time + 1
        topics = {c.topic: c for c in reader.connections}
        latched = {t for t, c in topics.items()
                   if getattr(c.ext, "offered_qos_profiles")[0].durability  # noqa: B009
                   == QosDurability.TRANSIENT_LOCAL}
        assert latched == {"/tf_static", "/map", "/obstacles", "/mdle/active"}
    assert [(m.topic, m.log_time) for m in rosbags_read(bag)] == [
        (m.topic, m.log_time) for m in direct]


def test_plot_and_trace_reader_take_the_recording(run: dict[str, Any]) -> None:
    d = run["dir"]
    tr: Trace = run["trace"]
    back = read_trace(d / "r.mcap")
    assert back.samples == tr.samples and back.events == tr.events and back.end == tr.end
    assert not back.truncated and back.header["world"] == tr.header["world"]
    assert len(back.scans) == len(tr.scans)
    for a, b in zip(back.scans, tr.scans, strict=True):
        np.testing.assert_array_equal(decode_ranges(a["ranges"]), decode_ranges(b["ranges"]))
    assert read_trace(d / "bag").samples == tr.samples
    proc = subprocess.run([*run["cmd"], "plot", str(d / "r.mcap"), "-o", str(d / "p.png")],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert (d / "p.png").read_bytes()[:4] == b"\x89PNG"


def test_repl_load_takes_the_recording(run: dict[str, Any]) -> None:
    d = run["dir"]
    tr: Trace = run["trace"]
    script = (f":load {d / 'r.mcap'}\n:pose\n:where 60\n:trace {d / 'back.jsonl'}\n"
              f":plot {d / 'back.png'}\n:load {d / 'bag'}\n:load {d / 'nothing.mcap'}\n")
    repl = [run["cmd"][0], "repl", "--echo"]
    proc = subprocess.run(repl, input=script, capture_output=True, text=True, timeout=120,
                          cwd=d)
    assert proc.returncode == 1, proc.stderr  # the last :load fails
    out = proc.stdout
    last = tr.samples[-1]
    assert (f"loaded {d / 'r.mcap'}: a run of `main` in world `ellipse-pioneer`, "
            f"{len(tr.samples)} ticks") in out
    assert f"x {last['true_x']:.2f} m  y {last['true_y']:.2f} m" in out
    assert f"trace written to {d / 'back.jsonl'} ({len(tr.samples)} samples)" in out
    assert (d / "back.png").read_bytes()[:4] == b"\x89PNG"
    assert out.count("loaded ") == 2
    assert "cannot read" in proc.stderr and "Traceback" not in proc.stderr
    back = read_trace(d / "back.jsonl")
    assert back.samples == tr.samples and back.events == tr.events
    assert len(back.scans) == len(tr.scans)
    for a, b in zip(back.scans, tr.scans, strict=True):
        np.testing.assert_array_equal(decode_ranges(a["ranges"]), decode_ranges(b["ranges"]))
