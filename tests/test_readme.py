"""The README's examples work as written: its plan checks, its Python snippet runs."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

README = Path(__file__).resolve().parent.parent / "README.md"


def _blocks(lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", README.read_text(encoding="utf-8"), re.S)


def test_readme_plan_checks_clean() -> None:
    from mdle.lang import load_text

    (plan,) = _blocks("mdle")
    program = load_text(plan, "README.md")
    assert program.entry == "main" and not program.warnings


def test_readme_python_example_runs(tmp_path: Path) -> None:
    (code,) = _blocks("python")
    out = subprocess.run([sys.executable, "-c", code], cwd=README.parent, capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert re.fullmatch(r"main ran to its end at 60\.0 s; closest approach 0\.\d\d m\n",
                        out.stdout), out.stdout


def test_readme_first_command_names_an_existing_plan() -> None:
    text = README.read_text(encoding="utf-8")
    plans = re.findall(r"mdle run (plans/\S+\.mdle)", text)
    assert plans and all((README.parent / p).is_file() for p in plans)


def test_ci_runs_the_readme_fresh_machine_commands_in_order() -> None:
    # .ci/run runs exactly what this prints, so README and CI cannot drift apart
    out = subprocess.run([sys.executable, str(README.parent / ".ci" / "readme_commands.py"),
                          str(README)], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    first, second = out.stdout.splitlines()
    assert "mdle run plans/" in first and "--plot" in first
    assert "pip install '.[test]'" in second and second.endswith("pytest -n 2")
    ci = (README.parent / ".ci" / "run").read_text(encoding="utf-8")
    assert "readme_commands.py" in ci and "git clone" in ci


def test_readme_says_its_mdle_commands_need_the_venv_before_the_first_one() -> None:
    text = README.read_text(encoding="utf-8")
    note = text.find(". .venv/bin/activate")
    first_bare = re.search(r"(?<![/\w])mdle (run|check|fmt|show|plot|repl|worlds|experiment)\b",
                           text)
    assert note >= 0 and first_bare is not None
    # the fresh-machine lines spell out .venv/bin/mdle; every later one relies on the note
    assert note < first_bare.start()


def test_readme_paper_figure_commands_write_their_figure(tmp_path: Path) -> None:
    import shlex

    from mdle.cli import main

    text = README.read_text(encoding="utf-8")
    rows = re.findall(r"^\| Fig\. [123][^|]*\| `mdle (run [^`]+)` \|$", text, re.M)
    assert len(rows) == 4  # Figures 1, 2, 3 and Figure 2 on the left
    for row in rows:
        argv = shlex.split(row)
        assert "--plot" in argv, row
    # the first one, cut short, writes its figure where it says
    argv = shlex.split(rows[0])
    out = argv[argv.index("--plot") + 1]
    argv[argv.index("--plot") + 1] = str(tmp_path / out)
    argv[1] = str(README.parent / argv[1])
    assert main([*argv, "--until", "1", "--quiet"]) == 0
    assert (tmp_path / out).read_bytes()[:4] == b"\x89PNG"


def test_readme_shows_a_figure_the_figures_script_makes() -> None:
    text = README.read_text(encoding="utf-8")
    shown = re.findall(r"!\[[^]]*\]\((docs/figures/[^)]+\.png)\)", text)
    script = (README.parent / "docs" / "figures" / "make_figures.py").read_text("utf-8")
    assert shown and all(Path(p).name in script for p in shown)
    assert "python docs/figures/make_figures.py" in text
