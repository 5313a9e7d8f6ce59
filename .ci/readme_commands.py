"""Print the README's fresh-machine commands, one a line, in the README's order.

They are the indented command lines of the section `## On a fresh machine`. `.ci/run`
runs exactly these lines, so the commands a newcomer copies and the ones CI runs
cannot drift apart.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

SECTION = "## On a fresh machine"


def commands(readme: str) -> list[str]:
    """Return the indented (code block) lines of the fresh-machine section."""
    start = readme.index(SECTION) + len(SECTION)
    end = readme.find("\n## ", start)
    body = readme[start:end if end >= 0 else len(readme)]
    return [line.strip() for line in body.splitlines() if re.match(r"^ {4}\S", line)]


def main(argv: list[str]) -> int:
    """Print the commands of the README named in ``argv`` (default README.md)."""
    path = Path(argv[1] if len(argv) > 1 else "README.md")
    found = commands(path.read_text(encoding="utf-8"))
    if len(found) != 2:
        sys.stderr.write(f"{path}: expected 2 commands under `{SECTION}`, "
                         f"found {len(found)}\n")
        return 1
    sys.stdout.write("".join(f"{c}\n" for c in found))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
