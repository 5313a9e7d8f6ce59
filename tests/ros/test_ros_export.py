"""`mdle export` on damaged traces, and the messages when the MCAP extra is missing."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from mdle.record.load import read_trace

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


def _records(trace: Path) -> list[str]:
    return trace.read_text().splitlines()


def test_deeply_nested_json_is_a_damaged_record(trace: Path, tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    lines = _records(trace)
    deep = '{"type": "sample", "t": 0.1, "x": ' + "[" * 100_000 + "]" * 100_000 + "}"
    code, _, err, out = _export(tmp_path, "\n".join([*lines[:3], deep, *lines[3:]]).encode()
                                + b"\n", capsys)
    assert code == 1, err
    assert "in.jsonl:4: not a trace record (JSON nested too deeply)" in err
    assert "internal error" not in err and out.exists()
    code, _, err, _ = _export(tmp_path, ("[" * 100_000).encode(), capsys)  # as the header
    assert code == 1 and "not an mdle trace" in err


@pytest.mark.parametrize("t", ["1e19", "-1e19", "1e300"])
def test_a_time_past_what_ros_stamps_hold_is_a_damaged_record(
        trace: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], t: str) -> None:
    lines = _records(trace)
    at = next(i for i, line in enumerate(lines) if json.loads(line)["type"] == "sample")
    lines[at] = json.dumps({**json.loads(lines[at]), "t": float(t)})
    code, _, err, _ = _export(tmp_path, ("\n".join(lines) + "\n").encode(), capsys)
    assert code == 1, err
    assert f"in.jsonl:{at + 1}: `t` is {float(t):g} s; a ROS time holds at most 1e+09 s" in err
    assert "internal error" not in err and "RuntimeWarning" not in err


def test_a_failed_export_leaves_the_old_file_and_no_partial_one(
        trace: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    import errno

    from mdle.cli import main
    from mdle.record.topics import RosRecording

    out = tmp_path / "out.mcap"
    out.write_bytes(b"the old file")

    def full(self: Any) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(RosRecording, "finish", full)
    assert main(["export", str(trace), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"cannot export `{trace}`" in err and "the disk is full" in err
    assert out.read_bytes() == b"the old file"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.mcap"]


def test_an_unreadable_trace_is_a_message(trace: Path, tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str],
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    import errno
    import io

    from mdle.cli import main

    class Failing(io.BytesIO):
        def __iter__(self) -> Any:
            raise OSError(errno.EIO, "Input/output error")

    real = __import__("mdle.record.export", fromlist=["open_user_file"]).open_user_file

    def failing_open(path: Any, limit: int) -> Any:
        with real(path, limit) as f:
            return Failing(f.read())

    monkeypatch.setattr("mdle.record.export.open_user_file", failing_open)
    assert main(["export", str(trace), "-o", str(tmp_path / "o.mcap")]) == 1
    err = capsys.readouterr().err
    assert "input/output error" in err and "internal error" not in err
    assert not (tmp_path / "o.mcap").exists()


@pytest.mark.parametrize("target", ["/dev/full", "/dev/null"])
def test_export_never_replaces_a_device(trace: Path, target: str,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    from mdle.cli import main

    assert main(["export", str(trace), "-o", target]) == 1
    assert f"cannot write `{target}`: it is a character device" in capsys.readouterr().err
    assert Path(target).is_char_device()


def test_a_damaged_schema_prints_only_mdles_message(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    from mcap.writer import Writer

    from mdle.cli import main

    path = tmp_path / "bad.mcap"
    with path.open("wb") as f:
        w = Writer(f)
        w.start(profile="ros2", library="test")
        sid = w.register_schema(name="std_msgs/msg/String", encoding="ros2msg",
                                data=b"strin$g data\n")
        cid = w.register_channel(topic="/mdle/state", message_encoding="cdr", schema_id=sid)
        w.add_message(channel_id=cid, log_time=0, publish_time=0,
                      data=b"\x00\x01\x00\x00\x02\x00\x00\x00a\x00")
        w.finish()
    assert main(["plot", str(path), "-o", str(tmp_path / "b.png")]) == 1
    err = capsys.readouterr().err
    # the library printed "Error processing 'strin$g data' ..." before mdle's own line
    assert err.startswith(f"{path}:1:1: error: not a readable MCAP file"), err
    assert "Error processing" not in err and len(err.strip().splitlines()) == 1
