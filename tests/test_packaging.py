"""The install puts the simulator and the atoms inside the ``mdle`` namespace (``mdle.sim``,
``mdle.atoms``): nothing named ``sim`` or ``atoms`` at the top of site-packages, where it
could clash with another project's package of that name."""

from __future__ import annotations

import sysconfig
from importlib import metadata
from pathlib import Path

import mdle
import mdle.atoms
import mdle.sim


def test_no_top_level_sim_or_atoms_is_installed() -> None:
    # The installed distribution, not a source tree's mdle.egg-info (whose SOURCES.txt lists
    # sim/ and atoms/ as they are in the checkout) that an earlier test's sys.path finds.
    purelib = sysconfig.get_paths()["purelib"]
    dist = next(iter(metadata.distributions(name="mdle", path=[purelib])), None)
    assert dist is not None, f"mdle is not installed in {purelib}"
    files = dist.files or []
    assert files, "mdle is not installed"
    tops = {Path(str(f)).parts[0] for f in files}
    assert not tops & {"sim", "atoms"}, sorted(tops)


def test_sim_and_atoms_are_subpackages_of_mdle() -> None:
    home = Path(mdle.__file__).parent
    for package in (mdle.sim, mdle.atoms):
        assert package.__file__ is not None
        assert Path(package.__file__).parent.parent == home, package.__file__
    assert mdle.sim.load_world("default").name == "default"
