"""`mdle export` on damaged traces, and the messages when the MCAP extra is missing."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from mdle.trace import read_trace

PLAN = "atom hug = (follow_boundary(side = right, rc = 1 m, v = 1 m/s), never, 6 s)\nrun hug\n"


@pytest.fixture(scope="module")
def trace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from mdle.cli import main

    d = tmp_path_factory.mktemp("exp")
    (d / "p.mdle").write_text(PLAN)
    assert main(["run", str(d / "p.mdle"), "--world", "ellipse", "--trace",
                 str(d / "t.jsonl"), "-q"]) == 0
    return d / "t.jsonl"


def _export(tmp_path: Path, text: bytes, capsys: pytest.CaptureFixture[str],
            *extra: str) -> tuple[int, str, str, Path]:
    from mdle.cli import main

    src = tmp_path / "in.jsonl"
    src.write_bytes(text)
    out = tmp_path / "out.mcap"
    code = main(["export", str(src), "-o", str(out), *extra])
    cap = capsys.readouterr()
    return code, cap.out, cap.err, out


def test_a_whole_trace(trace: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
                       doctor: Any) -> None:
    code, out, err, mcap = _export(tmp_path, trace.read_bytes(), capsys)
    assert code == 0 and err == ""
    n = len(read_trace(trace).samples)
    counts = doctor(mcap)
    assert counts["/odom"] == counts["/mdle/state"] == n
    assert f"wrote {mcap}: {sum(counts.values())} messages on 13 topics" in out


@pytest.mark.parametrize("cut", [0.3, 0.61, 0.97])
def test_a_trace_cut_short_exports_up_to_its_last_whole_line(
        trace: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], doctor: Any,
        rosbags_read: Any, cut: float) -> None:
    data = trace.read_bytes()
    part = data[:int(len(data) * cut)]
    if part.endswith(b"\n"):
        part = part[:-1]
    whole = part.count(b"\n")
    code, out, err, mcap = _export(tmp_path, part, capsys)
    assert code == 0
    assert f"in.jsonl:{whole + 1}: the last line is cut short" in err
    assert f"exported up to line {whole}" in err
    kept = [json.loads(line) for line in part.split(b"\n")[1:whole]]
    samples = [r for r in kept if r["type"] == "sample"]
    counts = doctor(mcap)
    assert counts["/mdle/state"] == len(samples)
    states = [json.loads(m.msg.data) for m in rosbags_read(mcap) if m.topic == "/mdle/state"]
    assert states == samples
    # the partial file plots too
    assert read_trace(mcap).end is None


@pytest.mark.parametrize("damage, why", [
    (b"{not json}\n", "not JSON"),
    (b'{"type":"sample","t":"soon","x":0}\n', "`t` must be a number"),
    (b'{"type":"sample","t":1.0}\n', "the record has no `x`"),
    (b'{"type":"scan","t":1.0,"stamp":1.0,"ranges":"%%%"}\n', "bad `scan` record"),
    (b'{"type":"scan","t":1.0,"stamp":1.0,"ranges":"AAAA"}\n', "bad `scan` record"),
    (b'{"type":"laser","count":-3}\n', "the record has no `angle_min`"),
    (b"\xff\xfe garbage\n", "not UTF-8"),
    (b"[1, 2]\n", "a JSON object with a `type`"),
    (b'{"type":"header","format":"mdle-trace"}\n', "a second `header`"),
])
def test_a_damaged_record_stops_the_export_there(
        trace: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], doctor: Any,
        damage: bytes, why: str) -> None:
    lines = trace.read_bytes().split(b"\n")
    at = len(lines) // 2
    text = b"\n".join(lines[:at]) + b"\n" + damage + b"\n".join(lines[at:])
    code, out, err, mcap = _export(tmp_path, text, capsys)
    assert code == 1, err
    assert f"in.jsonl:{at + 1}: " in err and why in err
    assert f"the file holds the records of lines 1-{at}" in err
    samples = sum(1 for line in lines[:at] if b'"type":"sample"' in line)
    assert doctor(mcap)["/mdle/state"] == samples


def test_not_a_trace(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err, mcap = _export(tmp_path, b'{"hello": 1}\n', capsys)
    assert code == 1 and "in.jsonl:1:1: error: not an mdle trace" in err
    assert not mcap.exists()
    code, out, err, mcap = _export(tmp_path, b"", capsys)
    assert code == 1 and "not an mdle trace" in err
    from mdle.cli import main

    assert main(["export", str(tmp_path / "missing.jsonl"), "-o", str(mcap)]) == 1
    assert "cannot read trace" in capsys.readouterr().err


def test_a_world_that_does_not_load_only_drops_the_map(
        trace: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], doctor: Any) -> None:
    lines = trace.read_bytes().split(b"\n")
    head = json.loads(lines[0])
    head["world"]["spec"] = str(tmp_path / "gone.yaml")
    text = json.dumps(head).encode() + b"\n" + b"\n".join(lines[1:])
    code, out, err, mcap = _export(tmp_path, text, capsys)
    assert code == 0 and "no /map written (give it with --world)" in err
    assert "/map" not in doctor(mcap)
    code, out, err, mcap = _export(tmp_path, text, capsys, "--world", "ellipse")
    assert code == 0 and doctor(mcap)["/map"] == 1


def test_rosbag_folder_must_be_new(trace: Path, tmp_path: Path,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    from mdle.cli import main

    (tmp_path / "bag").mkdir()
    (tmp_path / "bag" / "x").write_text("keep me")
    assert main(["export", str(trace), "--rosbag", str(tmp_path / "bag")]) == 1
    assert "the folder is not empty" in capsys.readouterr().err
    assert (tmp_path / "bag" / "x").read_text() == "keep me"


def test_without_the_extra_the_message_says_how_to_install_it(
        tmp_path: Path) -> None:
    """A real `mdle` whose `import mcap` fails (as on a base install)."""
    (tmp_path / "p.mdle").write_text(PLAN)
    blocker = ("import sys\nfor m in ('mcap', 'mcap.records', 'mcap_ros2', 'mcap_ros2.decoder'):"
               "\n    sys.modules[m] = None\nfrom mdle.cli import main\nsys.exit(main())\n")
    for args in (["run", str(tmp_path / "p.mdle"), "--world", "ellipse", "--record",
                  str(tmp_path / "r.mcap"), "-q"],
                 ["run", str(tmp_path / "p.mdle"), "--world", "ellipse", "--rosbag",
                  str(tmp_path / "bag"), "-q"],
                 ["export", str(tmp_path / "t.jsonl"), "-o", str(tmp_path / "r.mcap")]):
        proc = subprocess.run([sys.executable, "-c", blocker, *args], capture_output=True,
                              text=True, timeout=120, cwd=tmp_path)
        assert proc.returncode == 1, proc.stderr
        assert "needs the MCAP libraries, which are not installed (missing: mcap, " \
               "mcap_ros2)" in proc.stderr
        assert "pip install 'mdle[mcap]'" in proc.stderr
        assert "Traceback" not in proc.stderr
    assert not (tmp_path / "r.mcap").exists() and not (tmp_path / "bag").exists()
