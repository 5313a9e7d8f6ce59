"""A team run recorded in one file: per-robot topics and frames, read back by rosbags."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from mdle.record.load import read_trace

TEAM = Path(__file__).resolve().parents[2] / "plans" / "team" / "pair.team.yaml"


def _mdle() -> list[str]:
    exe = Path(sys.executable).with_name("mdle")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "mdle"]


@pytest.fixture(scope="module")
def team(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("team")
    proc = subprocess.run(
        [*_mdle(), "run", "--team", str(TEAM), "--until", "8", "-q", "--trace",
         str(d / "t.jsonl"), "--record", str(d / "r.mcap"), "--rosbag", str(d / "bag")],
        capture_output=True, text=True, timeout=180, cwd=d)
    assert proc.returncode == 0, proc.stderr
    return d


def _yaw(q: Any) -> float:
    return 2.0 * math.atan2(q.z, q.w)


def test_one_file_holds_every_robot_under_its_name(team: Path, doctor: Any) -> None:
    counts = doctor(team / "r.mcap")
    assert doctor(team / "bag" / "bag_0.mcap") == counts
    for name in ("leader", "follower"):
        n = len(read_trace(team / f"t.{name}.jsonl").samples)
        for topic in ("odom", "tf", "cmd_vel", "ground_truth", "footprint",
                      "mdle/diagnostics", "mdle/state"):
            assert counts[f"/{name}/{topic}"] == n, topic
        assert counts[f"/{name}/tf_static"] == 1
    # the world's, once for the team
    assert counts["/map"] == counts["/obstacles"] == 1
    assert not [t for t in counts if t.startswith(("/scan", "/odom", "/tf", "/mdle"))]


@pytest.mark.parametrize("source", ["r.mcap", "bag"])
def test_rosbags_reads_per_robot_frames(team: Path, rosbags_read: Any, store: str,
                                        source: str) -> None:
    msgs = rosbags_read(team / source, store)
    for name in ("leader", "follower"):
        trace = read_trace(team / f"t.{name}.jsonl")
        odoms = [m.msg for m in msgs if m.topic == f"/{name}/odom"]
        assert {(o.header.frame_id, o.child_frame_id) for o in odoms} == {
            (f"{name}/odom", f"{name}/base_link")}
        tfs = [m.msg for m in msgs if m.topic == f"/{name}/tf"]
        assert len(tfs) == len(trace.samples)
        for tf, s in zip(tfs, trace.samples, strict=True):
            base, fix = tf.transforms
            assert (base.header.frame_id, base.child_frame_id) == (f"{name}/odom",
                                                                   f"{name}/base_link")
            assert (fix.header.frame_id, fix.child_frame_id) == ("map", f"{name}/odom")
            # map -> NAME/odom -> NAME/base_link is the robot's true pose in the world
            phi = _yaw(fix.transform.rotation)
            x = fix.transform.translation.x + math.cos(phi) * s["x"] - math.sin(phi) * s["y"]
            y = fix.transform.translation.y + math.sin(phi) * s["x"] + math.cos(phi) * s["y"]
            assert math.isclose(x, s["true_x"], abs_tol=1e-9)
            assert math.isclose(y, s["true_y"], abs_tol=1e-9)
        (static,) = [m.msg for m in msgs if m.topic == f"/{name}/tf_static"]
        (mount,) = static.transforms
        assert (mount.header.frame_id, mount.child_frame_id) == (f"{name}/base_link",
                                                                 f"{name}/laser")
        scans = [m.msg for m in msgs if m.topic == f"/{name}/scan"]
        assert scans and {s.header.frame_id for s in scans} == {f"{name}/laser"}
        prints = [m.msg for m in msgs if m.topic == f"/{name}/footprint"]
        assert {p.header.frame_id for p in prints} == {f"{name}/base_link"}
        states = [json.loads(m.msg.data) for m in msgs if m.topic == f"/{name}/mdle/state"]
        assert states == list(trace.samples)


def test_each_robot_header_is_in_the_file(team: Path) -> None:
    from mcap.reader import make_reader

    with open(team / "r.mcap", "rb") as f:
        meta = {m.name: json.loads(m.metadata["header"]) for m in make_reader(f).iter_metadata()}
    assert set(meta) == {"mdle/leader", "mdle/follower"}
    assert meta["mdle/leader"]["team"]["robot"] == "leader"
    assert meta["mdle/follower"]["radius"] > 0


def test_mdle_plot_says_what_a_team_recording_is(team: Path) -> None:
    proc = subprocess.run([*_mdle(), "plot", str(team / "r.mcap"), "-o",
                           str(team / "p.png")], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1 and "Traceback" not in proc.stderr
    assert "a team's recording (robots follower, leader)" in proc.stderr
    assert "--trace run.jsonl gives run.NAME.jsonl" in proc.stderr
