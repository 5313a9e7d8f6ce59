"""A user's own control laws and sensor functions, from a file: `--laws FILE.py` (end to end)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from mdle.cli import main

#: A user's laws module (also the installed package's, tests/test_user_laws_installed.py)
LAWS = (Path(__file__).parent / "data" / "spiral_laws.txt").read_text(encoding="utf-8")

PLAN = "atom out = (spiral(v = 0.3 m/s), from_start > 1.5 m, 1 min)\nrun out\n"


@pytest.fixture
def files(tmp_path: Path) -> tuple[Path, Path]:
    (tmp_path / "mylaws.py").write_text(LAWS)
    (tmp_path / "out.mdle").write_text(PLAN)
    return tmp_path / "mylaws.py", tmp_path / "out.mdle"


def test_check_and_run_use_the_user_s_laws(files: tuple[Path, Path],
                                           capsys: pytest.CaptureFixture[str]) -> None:
    laws, plan = files
    assert main(["check", str(plan)]) == 1  # without them: unknown names
    capsys.readouterr()
    assert main(["check", "--laws", str(laws), str(plan)]) == 0
    assert "0 errors" in capsys.readouterr().out
    assert main(["run", "--laws", str(laws), str(plan)]) == 0
    out = capsys.readouterr().out
    assert "ended: out ended by interrupt (from_start > 1.5 m)" in out


def test_the_repl_uses_the_user_s_laws(files: tuple[Path, Path]) -> None:
    laws, plan = files
    done = subprocess.run([sys.executable, "-m", "mdle", "repl", "--laws", str(laws)],
                          input="(spiral(v = 0.3 m/s), from_start > 1 m, 1 min)\n:quit\n",
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "interrupt" in done.stdout and "Traceback" not in done.stderr + done.stdout


@pytest.mark.parametrize("text, message, line", [
    ("def broken(:\n", "the laws of `{f}` could not be loaded: SyntaxError", 1),
    ("from mdle.atoms.registry import Param, sensor\n\n@sensor(Param('d', 'metres'), "
     "result=None)\ndef d(args, ctx):\n    return 0.0\n",
     "parameter `d` of `d`: its dimension is `'metres'`", 3),
    ("import nothing_like_this\n", "could not be loaded: ModuleNotFoundError", 1),
    ("x = 1\n", "`{f}` declares no control law or sensor function", None),
    ("from mdle.atoms.registry import sensor\nfrom mdle.core.units import LENGTH\n\n"
     "@sensor(result=LENGTH)\ndef x(args, ctx):\n    return 0.0\n",
     "`x` of `{f}` is already a shipped sensor function", None),
])
def test_a_wrong_laws_file_is_a_located_error(tmp_path: Path, text: str, message: str,
                                              line: int | None,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.py"
    bad.write_text(text)
    (tmp_path / "p.mdle").write_text("atom a = (stop, never, 1 s)\nrun a\n")
    assert main(["check", "--laws", str(bad), str(tmp_path / "p.mdle")]) == 1
    captured = capsys.readouterr()
    err = captured.err + captured.out
    assert message.format(f=bad) in err and "Traceback" not in err
    if line is not None:
        assert f"{bad}:{line}:" in err


def test_a_missing_laws_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "p.mdle").write_text("atom a = (stop, never, 1 s)\nrun a\n")
    assert main(["run", "--laws", str(tmp_path / "no.py"), str(tmp_path / "p.mdle")]) == 1
    assert "no.py: no such file" in capsys.readouterr().err
