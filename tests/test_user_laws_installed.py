"""Laws of an installed package, an ``mdle.laws`` entry point, used by check/run/repl.

Each test lays out a real package and its ``.dist-info`` (METADATA, entry_points.txt,
RECORD) in a folder of its own and puts that folder on ``PYTHONPATH`` of a fresh
``python -m mdle``: importlib.metadata finds it as it finds a package pip installed.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

#: The package's laws module (the same as a file's, tests/test_user_laws.py)
LAWS = (Path(__file__).parent / "data" / "spiral_laws.txt").read_text(encoding="utf-8")

PLAN = "atom out = (spiral(v = 0.3 m/s), from_start > 1.5 m, 1 min)\nrun out\n"


def install(site: Path, laws: str = LAWS, point: str = "spiral = mdle_spiral.laws") -> Path:
    """Lay out the package mdle-spiral 0.1 with its laws module and one entry point."""
    package = site / "mdle_spiral"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text('"""mdle-spiral."""\n')
    (package / "laws.py").write_text(laws)
    info = site / "mdle_spiral-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: mdle-spiral\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[mdle.laws]\n{point}\n")
    files = ["mdle_spiral/__init__.py", "mdle_spiral/laws.py",
             *(f"mdle_spiral-0.1.dist-info/{n}" for n in ("METADATA", "entry_points.txt",
                                                         "RECORD"))]
    (info / "RECORD").write_text("".join(f"{f},,\n" for f in files))
    return site


def mdle(site: Path | None, *args: str, stdin: str | None = None,
         cwd: Path) -> subprocess.CompletedProcess[str]:
    """Run ``python -m mdle ARGS`` with ``site`` on its path, as a user would."""
    env = dict(os.environ)
    if site is not None:
        env["PYTHONPATH"] = str(site)
    else:
        env.pop("PYTHONPATH", None)
    return subprocess.run([sys.executable, "-m", "mdle", *args], input=stdin, cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=120)


def test_check_run_and_repl_use_an_installed_package_s_laws(tmp_path: Path) -> None:
    (tmp_path / "out.mdle").write_text(PLAN)
    without = mdle(None, "check", "out.mdle", cwd=tmp_path)
    assert without.returncode == 1 and "unknown name `spiral`" in without.stdout
    site = install(tmp_path / "site")
    checked = mdle(site, "check", "out.mdle", cwd=tmp_path)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    assert "0 errors" in checked.stdout
    ran = mdle(site, "run", "out.mdle", cwd=tmp_path)
    assert ran.returncode == 0, ran.stdout + ran.stderr
    assert "ended: out ended by interrupt (from_start > 1.5 m)" in ran.stdout
    repl = mdle(site, "repl", cwd=tmp_path,
                stdin="(spiral(v = 0.3 m/s), from_start > 1 m, 1 min)\n:quit\n")
    assert repl.returncode == 0, repl.stderr
    assert "interrupt" in repl.stdout and "Traceback" not in repl.stderr + repl.stdout


def test_an_entry_point_naming_one_decorated_function(tmp_path: Path) -> None:
    (tmp_path / "p.mdle").write_text("atom a = (stop, from_start > 1 m, 1 s)\nrun a\n")
    site = install(tmp_path / "site", point="start = mdle_spiral.laws:from_start")
    assert mdle(site, "check", "p.mdle", cwd=tmp_path).returncode == 0
    (tmp_path / "q.mdle").write_text(PLAN)  # spiral is not declared by this one
    assert "unknown name `spiral`" in mdle(site, "check", "q.mdle", cwd=tmp_path).stdout


def test_laws_file_beside_installed_laws_and_a_clash_between_them(tmp_path: Path) -> None:
    site = install(tmp_path / "site")
    (tmp_path / "mine.py").write_text(
        "from mdle.atoms.registry import sensor\nfrom mdle.core.units import TIME\n\n\n"
        "@sensor(result=TIME)\ndef clock(args, ctx):\n    return ctx.t\n")
    (tmp_path / "p.mdle").write_text(
        "atom a = (spiral(v = 0.3 m/s), from_start > 5 m or clock > 2 s, 1 min)\nrun a\n")
    both = mdle(site, "run", "--laws", "mine.py", "p.mdle", cwd=tmp_path)
    assert both.returncode == 0, both.stdout + both.stderr
    assert "ended by interrupt (clock > 2 s)" in both.stdout
    (tmp_path / "mine.py").write_text(LAWS)  # the same names as the package's
    clash = mdle(site, "check", "--laws", "mine.py", "p.mdle", cwd=tmp_path)
    assert clash.returncode == 1
    assert ("`spiral` of `mine.py` is already an installed package's control law"
            in clash.stdout + clash.stderr)


@pytest.mark.parametrize("laws, point, message, where", [
    (LAWS.replace("import math\n", "import math\n\nraise RuntimeError('no licence')\n"),
     "spiral = mdle_spiral.laws",
     "the entry point `spiral = mdle_spiral.laws` of mdle-spiral 0.1 (group mdle.laws) "
     "could not be loaded: RuntimeError: no licence", "laws.py:5:"),
    (LAWS.replace('"""Drive', ')\n"""Drive'), "spiral = mdle_spiral.laws",
     "could not be loaded: SyntaxError", "laws.py:12:"),
    (LAWS, "spiral = mdle_spiral.nowhere",
     "the entry point `spiral = mdle_spiral.nowhere` of mdle-spiral 0.1 (group mdle.laws) "
     "could not be loaded: ModuleNotFoundError", "entry_points.txt:2:"),
    ("x = 1\n", "spiral = mdle_spiral.laws",
     "the entry point `spiral = mdle_spiral.laws` of mdle-spiral 0.1 (group mdle.laws) "
     "declares no control law or sensor function", "entry_points.txt:2:"),
    (LAWS.replace("def from_start", "def x").replace("@sensor(result", "@sensor(name='x', "
                                                                      "result"),
     "spiral = mdle_spiral.laws",
     "`x` of the entry point `spiral = mdle_spiral.laws` of mdle-spiral 0.1 (group "
     "mdle.laws) is already a shipped sensor function", "entry_points.txt:2:"),
    (LAWS.replace('Param("grow", LENGTH, 0.2)', 'Param("grow", "metres", 0.2)'),
     "spiral = mdle_spiral.laws", "parameter `grow` of `spiral`: its dimension is `'metres'`",
     "laws.py:10:"),
])
def test_a_broken_entry_point_is_a_located_error(tmp_path: Path, laws: str, point: str,
                                                message: str, where: str) -> None:
    (tmp_path / "p.mdle").write_text("atom a = (stop, never, 1 s)\nrun a\n")
    site = install(tmp_path / "site", laws, point)
    for command in ("check", "run"):
        done = mdle(site, command, "p.mdle", cwd=tmp_path)
        said = done.stdout + done.stderr
        assert done.returncode == 1, said
        assert message in said and where in said and "Traceback" not in said
    repl = mdle(site, "repl", cwd=tmp_path, stdin=":quit\n")
    assert repl.returncode == 1 and message in repl.stdout + repl.stderr
