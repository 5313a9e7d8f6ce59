"""Big worlds: ray casts in floor plans of 100 to 100,000 segments, beside the peers; maps.

Run:  python benchmarks/bigworld.py [--rounds 9] [--calls 100]
      python benchmarks/bigworld.py --office DIR     # draw the office map (PGM + YAML)

Prints, for floor plans of about 100, 1,000, 10,000 and 100,000 segments (rooms of 6 m
with doors, two boxes and a 24-sided pillar each, at a fixed density: the robot in a
middle room sees about the same whatever the size):

* the cost of one 181-beam, 180-degree scan of 8 m: mdle's grid walk (the default), the
  cast it replaced (every face within range, culled by bounding box, compiled), and
  irsim-x's LiDAR (its C++ ray cast over a hash grid: ``pip install 'mdle[peers]'``),
  measured in interleaved rounds in this one process: each round times ``--calls``
  scans of each in turn, and the figures are the medians over rounds of each round's
  median scan, with the ratio taken per round;
* how many times real time a controlled tick runs at 10 Hz (``follow_boundary`` on an
  LMS-200 scan, a Pioneer with its timing model off) in a building map imported from
  a 4000 x 4000 occupancy grid, and how long that map takes to load.

A world's segments go to irsim-x as one linestring per ring (each obstacle's outline).
IR-SIM itself (``ir-sim``, pure Python) installs the same ``irsim`` package as irsim-x,
so the two cannot share an environment: its figures in ``docs/performance.md`` come from
a separate one.
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

# This folder holds a file named like the package (sim.py): keep it off the path.
_HERE = os.path.dirname(os.path.abspath(__file__))
sys.path[:] = [p for p in sys.path if os.path.abspath(p or os.curdir) != _HERE]

import numpy as np  # noqa: E402 (after the path fix above)

from mdle.core.pose import Pose  # noqa: E402 (after the path fix above)
from mdle.sim.ladar import LMS200  # noqa: E402 (after the path fix above)
from mdle.sim.shapes import Polygon, Rectangle, Wall  # noqa: E402 (after the path fix above)
from mdle.sim.world import World  # noqa: E402 (after the path fix above)

FOV, BEAMS, RANGE = math.pi, 181, LMS200.max_range


def floor_plan(n_segments: int, seed: int = 0, room: float = 6.0) -> World:
    """Build a floor of about ``n_segments`` segments: rooms of ``room`` m, furnished alike."""
    rng = np.random.default_rng(seed)
    rooms = max(1, round(n_segments / 48))
    nx = max(1, round(math.sqrt(rooms)))
    ny = max(1, math.ceil(rooms / nx))
    t = 0.15
    ring = np.linspace(0, 2 * math.pi, 24, endpoint=False)
    shapes: list[Rectangle | Polygon | Wall] = []
    for i in range(nx):
        for j in range(ny):
            x0, y0 = i * room, j * room
            d = float(rng.uniform(1.5, room - 1.5))      # a door in the south wall
            shapes += [Rectangle((x0 + (d - 0.5) / 2, y0), (d - 0.5, t)),
                       Rectangle((x0 + (d + 0.5 + room) / 2, y0), (room - d - 0.5, t))]
            d = float(rng.uniform(1.5, room - 1.5))      # and in the west wall
            shapes += [Rectangle((x0, y0 + (d - 0.5) / 2), (t, d - 0.5)),
                       Rectangle((x0, y0 + (d + 0.5 + room) / 2), (t, room - d - 0.5))]
            for _ in range(2):
                c = (x0 + float(rng.uniform(1, room - 1)), y0 + float(rng.uniform(1, room - 1)))
                if math.hypot(c[0] - x0 - room / 2, c[1] - y0 - room / 2) < 1.5:
                    continue                             # the middle stays clear
                shapes.append(Rectangle(c, (float(rng.uniform(0.3, 0.8)),
                                            float(rng.uniform(0.3, 0.8))),
                                        float(rng.uniform(0, 3))))
            cx, cy = x0 + room * 0.8, y0 + room * 0.25
            shapes.append(Polygon(tuple((cx + 0.3 * math.cos(a), cy + 0.3 * math.sin(a))
                                        for a in ring)))
    w, h = nx * room, ny * room
    shapes.append(Wall(((0, 0), (w, 0), (w, h), (0, h)), 0.2, True))
    middle = Pose((nx // 2) * room + room / 2, (ny // 2) * room + room / 2, 0.0)
    return World(f"floor-{n_segments}", tuple(shapes), middle)


def building_grid(cells: int = 4000, room: int = 120, seed: int = 0) -> np.ndarray:
    """Draw a building as map_saver writes it: a (cells, cells) uint8 image, 0 occupied, 254 free.

    Rooms of ``room`` cells with 4-cell walls, a door in two walls of each, a desk, a round
    pillar, and sensor specks (one cell in 2,000).
    """
    rng = np.random.default_rng(seed)
    occ = np.zeros((cells, cells), dtype=bool)
    for k in range(0, cells, room):
        occ[k:k + 4, :] = True
        occ[:, k:k + 4] = True
    yy, xx = np.ogrid[-6:7, -6:7]
    pillar = xx * xx + yy * yy <= 36
    for i in range(0, cells - room, room):
        for j in range(0, cells - room, room):
            d = int(rng.integers(20, room - 30))
            occ[i:i + 4, j + d:j + d + 18] = False
            d = int(rng.integers(20, room - 30))
            occ[i + d:i + d + 18, j:j + 4] = False
            a, b = (int(v) for v in rng.integers(10, room - 30, 2))
            h, w = (int(v) for v in rng.integers(5, 20, 2))
            occ[i + a:i + a + h, j + b:j + b + w] = True
            a, b = (int(v) for v in rng.integers(15, room - 15, 2))
            occ[i + a - 6:i + a + 7, j + b - 6:j + b + 7] |= pillar
    occ |= rng.random((cells, cells)) < 0.0005
    return np.where(occ, 0, 254).astype(np.uint8)


def open_spot(occupied: np.ndarray, resolution: float, side: int = 21) -> tuple[float, float]:
    """Return the centre (m) of the free ``side``-cell square block nearest the map's middle."""
    rows, cols = occupied.shape
    sums = np.zeros((rows + 1, cols + 1))
    sums[1:, 1:] = occupied.cumsum(axis=0).cumsum(axis=1)
    block = (sums[side:, side:] - sums[:-side, side:] - sums[side:, :-side]
             + sums[:-side, :-side])                     # occupied cells in each block
    r, c = np.nonzero(block == 0)
    k = int(np.argmin((r - rows / 2) ** 2 + (c - cols / 2) ** 2))
    row, col = r[k] + side / 2, c[k] + side / 2          # the block's centre, in cells
    return float(col * resolution), float((rows - row) * resolution)


def write_map(folder: Path, img: np.ndarray, name: str, resolution: float = 0.05) -> Path:
    """Write ``img`` as map_saver does (NAME.pgm, P5, and NAME.yaml); return the YAML's path."""
    rows, cols = img.shape
    header = f"P5\n# CREATOR: map_saver.cpp {resolution:.3f} m/pix\n{cols} {rows}\n255\n"
    (folder / f"{name}.pgm").write_bytes(header.encode() + img.tobytes())
    (folder / f"{name}.yaml").write_text(
        f"image: {name}.pgm\nresolution: {resolution:f}\norigin: [0.000000, 0.000000, "
        "0.000000]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
    return folder / f"{name}.yaml"


def office_grid() -> np.ndarray:
    """Draw the office of ``sim/worlds/office.yaml``: 32 x 20 m at 5 cm, as map_saver writes it.

    A corridor along the middle with two round pillars, six offices on each side (a door
    each, a desk in each), an open room at the east end with a round table.
    """
    occ = np.zeros((400, 640), dtype=bool)                # rows top first; 5 cm cells

    def box(x0: float, y0: float, x1: float, y1: float) -> None:   # metres, y up
        occ[400 - round(y1 * 20):400 - round(y0 * 20), round(x0 * 20):round(x1 * 20)] = True

    def disc(cx: float, cy: float, r: float) -> None:
        yy, xx = np.mgrid[0:400, 0:640]
        occ[((xx + 0.5) / 20 - cx) ** 2 + ((400 - yy - 0.5) / 20 - cy) ** 2 <= r * r] = True

    for x0, y0, x1, y1 in ((0, 0, 32, 0.2), (0, 19.8, 32, 20), (0, 0, 0.2, 20),
                           (31.8, 0, 32, 20)):
        box(x0, y0, x1, y1)
    for k in range(7):                                     # office walls, 4 m apart
        x = 4.0 * k
        box(x, 0, x + 0.15, 8.5)
        box(x, 11.5, x + 0.15, 20)
    for k in range(6):                                     # corridor walls with doors
        x = 4.0 * k
        box(x, 8.5, x + 1.5, 8.65)
        box(x + 2.5, 8.5, x + 4.15, 8.65)
        box(x, 11.35, x + 1.0, 11.5)
        box(x + 2.0, 11.35, x + 4.15, 11.5)
        box(x + 1.0, 2.0, x + 3.0, 2.8)                    # desks
        box(x + 1.0, 17.2, x + 3.0, 18.0)
    disc(9.0, 10.0, 0.3)
    disc(17.0, 10.0, 0.3)
    disc(28.0, 10.0, 1.0)                                  # the open room's table
    return np.where(occ, 0, 254).astype(np.uint8)


def _rings(world: World) -> list[np.ndarray]:
    """Return the world's faces as chains of points: each ring's vertices, in order."""
    s0, s1 = world.parts.seg_start, world.parts.seg_end
    breaks = np.flatnonzero(np.any(s1[:-1] != s0[1:], axis=1)) + 1
    return [np.vstack([s0[a:b], s1[b - 1:b]]) for a, b in
            zip(np.r_[0, breaks], np.r_[breaks, s0.shape[0]], strict=True)]


def irsim_x_scan(world: World) -> Callable[[float, float, float], np.ndarray] | None:
    """Return irsim-x's LiDAR ray cast over ``world`` as a function of the pose, or None."""
    try:
        from cpp import _core  # irsim-x's C++ core (pip install 'mdle[peers]')
    except ImportError:
        return None
    sim = _core.SimWorld()
    for ring in _rings(world):
        sim.add_obstacle({"type": "linestring", "vertices": ring.astype(np.float32).tolist()})
    angles = np.linspace(-FOV / 2, FOV / 2, BEAMS).astype(np.float32)

    def scan(x: float, y: float, th: float) -> np.ndarray:
        return np.asarray(sim.raycast_at(x, y, th, angles, RANGE))

    return scan


def interleaved(fns: dict[str, Callable[[int], object]], calls: int, rounds: int
                ) -> dict[str, list[float]]:
    """Time each function ``calls`` times per round, in turn; return each round's median (us)."""
    out: dict[str, list[float]] = {k: [] for k in fns}
    names = list(fns)
    for k in range(calls):
        for f in fns.values():
            f(k)
    for r in range(rounds):
        for name in (names if r % 2 == 0 else names[::-1]):
            f, times = fns[name], []
            for k in range(calls):
                t0 = time.perf_counter()
                f(k)
                times.append(time.perf_counter() - t0)
            out[name].append(statistics.median(times) * 1e6)
    return out


def _turning(cast: Callable[[float, float, float], object], p: Pose, angles: np.ndarray
             ) -> Callable[[int], object]:
    """Return a function of k casting from ``p`` at the k-th of ``angles`` (in turn)."""
    def call(k: int) -> object:
        return cast(p.x, p.y, float(angles[k % angles.shape[0]]))

    return call


def scans(calls: int, rounds: int) -> None:
    """Print the scan costs of mdle (walk, plain) and irsim-x in floor plans of four sizes."""
    rel = np.linspace(0.0, FOV, BEAMS)
    headings = np.linspace(-math.pi, math.pi, 64, endpoint=False)
    print(f"one {BEAMS}-beam scan, {math.degrees(FOV):.0f} deg, {RANGE:g} m, robot in a middle "
          f"room (median over {rounds} interleaved rounds of {calls} scans, us):")
    print("  segments | mdle grid walk | mdle plain (before) | irsim-x | irsim-x / mdle")
    first_walk = None
    for n in (100, 1000, 10_000, 100_000):
        world = floor_plan(n)
        p = world.start_pose
        walk = world.caster.fan(rel, RANGE, None, True)
        plain = world.caster.fan(rel, RANGE, None, False)
        fns = {"walk": _turning(walk.cast, p, headings - FOV / 2),
               "plain": _turning(plain.cast, p, headings - FOV / 2)}
        peer = irsim_x_scan(world)
        if peer is not None:    # its angles are about the heading; mdle's from the first beam
            fns["irsim-x"] = _turning(peer, p, headings)
        t = interleaved(fns, calls, rounds)
        w, pl = statistics.median(t["walk"]), statistics.median(t["plain"])
        first_walk = first_walk or (world.parts.n_segments, w)
        if "irsim-x" in t:
            x = statistics.median(t["irsim-x"])
            ratio = statistics.median(a / b for a, b in zip(t["irsim-x"], t["walk"],
                                                            strict=True))
            peer_cols = f"{x:7.1f} | x{ratio:.2f}"
        else:
            peer_cols = "    n/a | (pip install 'mdle[peers]')"
        print(f"  {world.parts.n_segments:8d} | {w:14.1f} | {pl:19.1f} | {peer_cols}")
    print(f"  (the walk at 100k against ~1k segments: see the rows; {first_walk})")


def building(cells: int) -> None:
    """Print the load time and memory of a (cells x cells) building map, and its tick rate."""
    from mdle.lang import load_text
    from mdle.runtime import Scheduler
    from mdle.sim.backend import SimBackend
    from mdle.sim.catalog import load_world

    img = building_grid(cells)
    x, y = open_spot(img == 0, 0.05)
    with tempfile.TemporaryDirectory() as tmp:
        path = write_map(Path(tmp), img, "building")
        (Path(tmp) / "world.yaml").write_text(
            f"name: building\nmap: {path.name}\nstart: {{x: {x}, y: {y}, theta: 0}}\n")
        # In a fresh process: its peak memory is the load's own.
        child = subprocess.run([sys.executable, __file__, "--load", str(Path(tmp) / "world.yaml")],
                               capture_output=True, text=True, check=True)
        print(child.stdout, end="")
        world = load_world(str(Path(tmp) / "world.yaml"))
    text = ("atom f = (follow_boundary(side = right, rc = 0.6 m, v = 0.3 m/s), never, inf)\n"
            "plan main = ((f), never, inf)\n")
    backend = SimBackend(world, seed=1, robot="pioneer2dx")
    sch = Scheduler(load_text(text).elements["main"], backend, 10.0, [], stall_timeout=None)
    for _ in range(50):
        sch.tick()
    ticks = []
    for _ in range(9):
        t0 = time.perf_counter()
        for _ in range(100):
            sch.tick()
        ticks.append((time.perf_counter() - t0) / 100)
    tick = statistics.median(ticks)
    print(f"  a controlled tick (follow_boundary, 10 Hz): {tick * 1e6:.0f} us, "
          f"{0.1 / tick:.0f}x real time (median of 9 runs of 100 ticks)")


def load_only(path: str) -> None:
    """Load a world (its map, start check, caster and grid); print the time and peak memory."""
    from mdle.sim.catalog import load_world

    wall, cpu = time.perf_counter(), time.process_time()
    world = load_world(path)
    world.caster.grid                          # noqa: B018 (built on first use: count it)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"a map_server map as a world's `map:` ({world.parts.n_segments} segments): loaded "
          f"(image, outlines, faces, start check, caster, grid) in {wall:.2f} s ({cpu:.2f} s "
          f"of CPU); the process's peak memory {peak:.0f} MB")


def main() -> None:
    """Parse the command line and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=9, help="interleaved rounds")
    parser.add_argument("--calls", type=int, default=100, help="scans per round")
    parser.add_argument("--cells", type=int, default=4000, help="the building map's side")
    parser.add_argument("--office", metavar="DIR",
                        help="only write the office map (office.pgm, office.yaml) into DIR")
    parser.add_argument("--load", metavar="WORLD", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.load:
        load_only(args.load)
        return
    if args.office:
        print(write_map(Path(args.office), office_grid(), "office"))
        return
    print("load average " + ", ".join(f"{x:.2f}" for x in os.getloadavg()))
    scans(args.calls, args.rounds)
    building(args.cells)
    print("load average " + ", ".join(f"{x:.2f}" for x in os.getloadavg()))


if __name__ == "__main__":
    main()
