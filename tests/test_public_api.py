"""`mdle`'s public names: each resolves, none is loaded before it is used, and the Python
examples of the README and the docs, written with them, run."""

from __future__ import annotations

import doctest
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import mdle

ROOT = Path(__file__).resolve().parents[1]
#: Pages whose Python examples run here as they are shown: each block that begins with its
#: imports (a fragment of a module or of a session is left out). hardware.md's needs a
#: robot, and architecture.md's walk-through tests a sensor function it adds to the
#: package: only their imports are checked, with every other page's, below.
RUN = ["README.md", "docs/runtime.md", "docs/language.md"]


def _python_blocks(page: Path) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", page.read_text(), re.S | re.M)


def test_every_public_name_resolves_to_what_its_module_defines() -> None:
    assert len(set(mdle.__all__)) == len(mdle.__all__)
    for name in mdle.__all__:
        assert getattr(mdle, name) is not None, name
        assert name in dir(mdle)
    from mdle.runtime import run_named
    from mdle.sim import SimBackend

    assert mdle.run_named is run_named and mdle.SimBackend is SimBackend
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        mdle.nothing  # noqa: B018


def test_importing_mdle_loads_none_of_them() -> None:
    # every command imports the package: `mdle check` must not pay for the runtime,
    # the simulator's numpy or the drivers
    code = ("import sys, mdle; heavy = [m for m in ('numpy', 'mdle.runtime', 'mdle.sim', "
            "'mdle.drivers', 'mdle.record.trace', 'mdle.lang') if m in sys.modules]; print(heavy)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=60)
    assert out.stdout.strip() == "[]"


def test_the_package_docstring_example_runs() -> None:
    result = doctest.testmod(mdle, optionflags=doctest.ELLIPSIS)
    assert result.attempted >= 4 and result.failed == 0


def test_every_example_imports_from_mdle_what_it_exports() -> None:
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    imports = [found for page in pages for block in _python_blocks(page)
               for found in re.findall(r"^from mdle import (?:\(([^)]*)\)|([^(\n]+)$)", block,
                                       re.M)]
    names = {n.strip() for pair in imports for part in pair
             for n in part.replace("\n", ",").split(",") if n.strip()}
    # one from each page that imports from mdle: README, runtime, hardware, architecture
    assert {"ended_how", "TraceWriter", "open_backend", "CheckError"} <= names
    assert names - {"sim"} <= set(mdle.__all__), names - set(mdle.__all__)


@pytest.mark.parametrize("page", RUN)
def test_the_page_s_python_examples_run(page: str, tmp_path: Path) -> None:
    blocks = _python_blocks(ROOT / page)
    assert blocks, page
    (tmp_path / "plans").symlink_to(ROOT / "plans")  # the examples name plans/...
    for i, block in enumerate(blocks):
        if not block.startswith(("import ", "from ")):  # a fragment of a module or session
            continue
        script = tmp_path / f"example{i}.py"
        # a block that defines tests runs them too
        script.write_text(block + "\n\nfor _name, _fn in list(globals().items()):\n"
                          "    if _name.startswith('test_') and callable(_fn):\n"
                          "        _fn()\n")
        out = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True,
                             text=True, timeout=300,
                             env={**os.environ, "MPLBACKEND": "Agg"})
        assert out.returncode == 0, f"{page}, example {i + 1}:\n{out.stderr[-3000:]}"
