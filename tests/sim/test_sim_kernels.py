"""The compiled loops (sim/_kernels.c) give the numpy paths' numbers, bit for bit.

The other tests run whichever path the install has; these put the two side by side: the
fan cast's single scans over many worlds and fans, a team's batch, a whole seeded run, the
plain-rounding branch against a Python reference; a team's occlusions by the robots'
discs, found and applied, and a whole team run; and bad buffers.
"""

from __future__ import annotations

import importlib.util
import math
import shutil
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from mdle.core.backend import Command
from mdle.core.pose import Pose
from mdle.sim import crowd, raycast
from mdle.sim.backend import SimBackend
from mdle.sim.catalog import load_world
from mdle.sim.crowd import Discs, occlude, occlusions
from mdle.sim.ladar import LMS200
from mdle.sim.profiles import robot_profile
from mdle.sim.raycast import COMPILED, FanCaster
from mdle.sim.shapes import Circle, Curve, Ellipse, Rectangle, Wall
from mdle.sim.team import TeamSim
from mdle.sim.world import RobotPlace, World
from tests.sim.conftest import boxes_world

# Skips only on an install built without a C compiler: the first test below fails an
# install that had one and did not build the loops, so these never skip unnoticed.
needs_build = pytest.mark.skipif(raycast._KERNEL is None,
                                 reason="this install has no compiled fan cast")
needs_kernel = pytest.mark.skipif(not COMPILED, reason="this install has no compiled fan cast")
needs_cuts = pytest.mark.skipif(not crowd.COMPILED,
                                reason="this install has no compiled occlusions")


def _mixed() -> World:
    return World("mix", obstacles=(
        Wall(((-6, -6), (6, -6), (6, 6), (-6, 6)), 0.2, True),
        Circle((1.0, 1.0), 0.5), Ellipse((-2.0, 2.0), (1.0, 0.5), 0.3),
        Rectangle((0.0, -3.5), (1.0, 0.4), 0.2), Wall(((-4.0, -1.0), (-3.0, 0.5)), 1e-3)))


def _ring() -> World:
    pts = tuple((4 * math.cos(a), 3 * math.sin(a))
                for a in np.linspace(0, 2 * math.pi, 40, endpoint=False))
    return World("ring", obstacles=(Curve(pts, thickness=0.2, closed=True, spacing=0.05),))


def test_an_install_built_with_a_c_compiler_has_the_compiled_fan_cast() -> None:
    # The build is optional (pyproject.toml): this pins that it really happens where it can.
    if shutil.which("cc") or shutil.which("gcc"):
        assert raycast._KERNEL is not None and crowd._KERNELS is not None
    assert COMPILED == (raycast._KERNEL is not None and raycast._FUSED is not None)


def test_the_version_says_whether_the_loops_are_compiled(
        capsys: pytest.CaptureFixture[str]) -> None:
    from mdle.cli import main

    assert main(["--version"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("mdle ")
    assert ("simulator: compiled loops" in out) == (raycast._KERNEL is not None), out
    searches_built = importlib.util.find_spec("mdle.atoms._searches") is not None
    assert ("whole-scan model: compiled loops" in out) == searches_built, out
    points_built = importlib.util.find_spec("mdle.atoms._points") is not None
    assert ("scan points: compiled loops" in out) == points_built, out


@needs_kernel
@pytest.mark.parametrize("beams", [181, 361, 7])
@pytest.mark.parametrize("fov", [1.0, math.pi, 4.5, 2 * math.pi])
@pytest.mark.parametrize("make", [lambda: boxes_world(25, 6, 1), lambda: boxes_world(90, 15, 7),
                                  _mixed, _ring], ids=["100 faces", "culled", "mixed", "ring"])
def test_compiled_and_numpy_scans_are_equal_bit_for_bit(
        beams: int, fov: float, make: Callable[[], World]) -> None:
    world = make()
    rel = np.linspace(0.0, fov, beams)
    fast, ref = world.caster.fan(rel, 8.0, True), world.caster.fan(rel, 8.0, False)
    rng = np.random.default_rng(beams)
    hits = 0
    for _ in range(40):
        o = rng.uniform(-12.0, 12.0, 2)
        first = float(rng.uniform(-7.0, 7.0))   # every heading: the intervals' wrap too
        r1, h1 = fast.cast(float(o[0]), float(o[1]), first)
        r2, h2 = ref.cast(float(o[0]), float(o[1]), first)
        assert np.array_equal(r1, r2) and np.array_equal(h1, h2)
        hits += int(h1.sum())
    assert hits > 40 * beams // 10    # the scans saw something


@needs_kernel
def test_a_teams_batch_cast_is_the_same_on_both_paths() -> None:
    world = boxes_world(25, 6, 3)
    rel = np.linspace(0.0, math.pi, 181)
    fast, ref = world.caster.fan(rel, 8.0, True), world.caster.fan(rel, 8.0, False)
    assert fast.batchable()
    rng = np.random.default_rng(5)
    ox, oy, first = rng.uniform(-6, 6, 30), rng.uniform(-6, 6, 30), rng.uniform(-7, 7, 30)
    r1, h1 = fast.cast_many(ox, oy, first)
    r2, h2 = ref.cast_many(ox, oy, first)
    assert np.array_equal(r1, r2) and np.array_equal(h1, h2)
    for s in range(30):
        r, h = fast.cast(float(ox[s]), float(oy[s]), float(first[s]))
        assert np.array_equal(r1[s], r) and np.array_equal(h1[s], h)


@needs_kernel
def test_a_seeded_run_is_the_same_on_both_paths() -> None:
    from mdle.lang import load_text
    from mdle.runtime import Scheduler

    text = ("atom f = (follow_boundary(side = right, rc = 0.5 m, v = 0.5 m/s), never, inf)\n"
            "plan main = ((f), never, inf)\n")
    runs = []
    for compiled in (True, False):
        backend = SimBackend(load_world("hexagon"), seed=3, compiled=compiled)
        sch = Scheduler(load_text(text).elements["main"], backend, 10.0, [],
                        stall_timeout=None)
        path = []
        for _ in range(400):
            assert sch.tick()
            obs = backend.observe()
            path.append((obs.pose.x, obs.pose.y, obs.pose.theta,
                         None if obs.scan is None else obs.scan.ranges.tobytes()))
        runs.append(path)
    assert runs[0] == runs[1]
    assert sum(p[3] is not None for p in runs[0]) > 300


def _reference_faces(zw: np.ndarray, front_min: np.ndarray, best: np.ndarray,
                     rel_s: np.ndarray, dconj: np.ndarray, rot: complex, c: complex,
                     kc: complex, eps: float, wrap_hi: float, may_wrap: bool) -> None:
    """The face loop in Python floats: plain complex products, libm's atan2."""
    faces = []
    for j in range(zw.shape[1]):
        q = complex(zw[0, j]) * rot - c
        pc = complex(zw[1, j]) * rot.conjugate() - c.conjugate()
        w = pc * q
        if not w.imag > front_min[j]:
            continue
        kp = complex(zw[2, j]) * rot - kc
        e = complex(zw[3, j]) * rot
        lo = math.atan2(kp.imag, kp.real)
        s = 1.0 / w.imag
        faces.append((math.atan2(w.imag, w.real) + lo + eps, lo - eps,
                      complex(e.real * s, e.imag * s)))
    if may_wrap and faces and max(f[0] for f in faces) >= wrap_hi:
        faces += [(hi - 2 * math.pi, lo - 2 * math.pi, f) for hi, lo, f in faces]
    for hi, lo, f in faces:
        for k in range(int(np.searchsorted(rel_s, lo)), int(np.searchsorted(rel_s, hi))):
            best[k] = max(best[k], (complex(dconj[k]) * f).imag)


def _kernel_args(fan: FanCaster, ox: float, oy: float, first: float) -> list[Any]:
    """The kernel's arguments but the last (``fused``): a fresh ``best`` at index 2."""
    phi = first + fan._half
    rot = complex(math.cos(phi), -math.sin(phi))
    c = complex(ox, oy) * rot
    return [fan._zw, fan.caster._front_min, np.full(fan._rel_s.shape[0], fan._inv_none),
            fan._rel_s, fan._dconj, rot, c, fan._kappa * c, raycast._EPS_ANGLE,
            fan._wrap_hi, fan._may_wrap]


@needs_build
def test_the_plain_rounding_branch_matches_python_floats() -> None:
    # For a machine whose numpy rounds complex products without a fused multiply-add.
    world = boxes_world(25, 6, 2)
    fan = world.caster.fan(np.linspace(0.0, math.pi, 181), 8.0)
    rng = np.random.default_rng(11)
    assert raycast._KERNEL is not None
    for _ in range(30):
        o, first = rng.uniform(-6, 6, 2), float(rng.uniform(-7, 7))
        args = _kernel_args(fan, float(o[0]), float(o[1]), first)
        got, want = args[2], args[2].copy()
        raycast._KERNEL(*args, False)
        _reference_faces(args[0], args[1], want, *args[3:])
        assert np.array_equal(got, want)
        assert (got > fan._inv_none).any()


@needs_build
def test_the_kernel_rejects_buffers_of_the_wrong_shape_or_type() -> None:
    fan = boxes_world(5, 3, 0).caster.fan(np.linspace(0.0, math.pi, 181), 8.0)
    kernel = raycast._KERNEL
    assert kernel is not None
    good = [*_kernel_args(fan, 0.0, 0.0, 0.0), True]
    kernel(*good)
    for i, bad, match in [
            (2, np.zeros(181, dtype=np.float32), "best"),     # float32
            (2, np.zeros(180), "best"),                       # one beam short
            (2, np.zeros(362)[::2], "contiguous"),            # strided
            (0, good[0][:, :3].copy(), "zw"),                 # faces != front_min
            (4, good[4].real.copy(), "dconj"),                # real, not complex
            (3, np.zeros(181, dtype=np.int64), "rel_s")]:
        args = list(good)
        args[i] = bad
        with pytest.raises((ValueError, BufferError), match=match):
            kernel(*args)
    ro = good[2].copy()
    ro.flags.writeable = False
    with pytest.raises((ValueError, BufferError)):
        kernel(*good[:2], ro, *good[3:])
    with pytest.raises(TypeError, match="12 arguments"):
        kernel(*good[:-1])
    with pytest.raises(TypeError):
        kernel(*good[:5], "turn", *good[6:])


def test_asking_for_the_compiled_cast_where_it_is_missing_says_so(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(raycast, "COMPILED", False)
    caster = boxes_world(5, 3, 0).caster
    with pytest.raises(ValueError, match="no compiled fan cast"):
        caster.fan(np.linspace(0.0, math.pi, 181), 8.0, compiled=True)
    ranges, hit = caster.fan(np.linspace(0.0, math.pi, 181), 8.0).cast(0.0, 0.0, 0.0)
    assert hit.any()     # the numpy path casts


_Scans = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
               np.ndarray, Discs]


def _random_scans(rng: np.random.Generator) -> tuple[_Scans, int]:
    n_scan, n_disc = int(rng.integers(1, 12)), int(rng.integers(1, 14))
    discs = Discs(rng.uniform(-6, 6, n_disc), rng.uniform(-6, 6, n_disc),
                  rng.uniform(0.1, 0.6, n_disc), np.arange(n_disc))
    beams = rng.choice([181, 361, 7], n_scan).astype(np.intp)
    return ((rng.uniform(-6, 6, n_scan), rng.uniform(-6, 6, n_scan),
             rng.uniform(-7, 7, n_scan), rng.uniform(0.3, 5.5, n_scan) / (beams - 1), beams,
             rng.uniform(1, 10, n_scan), rng.integers(-1, n_disc, n_scan).astype(np.intp),
             discs), int(beams.max()))


@needs_cuts
def test_compiled_and_numpy_occlusions_are_equal_bit_for_bit() -> None:
    rng = np.random.default_rng(21)
    cuts = 0
    for _ in range(150):
        scans, width = _random_scans(rng)
        fast, ref = occlusions(*scans, compiled=True), occlusions(*scans, compiled=False)
        assert all(np.array_equal(a, b) for a, b in zip(fast, ref, strict=True))
        cuts += fast[0].shape[0]
        # applied in place: the nearer of the range there and each cut, the beam valid
        ranges = rng.uniform(0.5, 9.0, (scans[0].shape[0], width))
        valid = rng.random(ranges.shape) < 0.5
        r2, v2 = ranges.copy(), valid.copy()
        occlude(*scans, ranges, valid, compiled=True)
        occlude(*scans, r2, v2, compiled=False)
        assert np.array_equal(ranges, r2) and np.array_equal(valid, v2)
    assert cuts > 10_000


def _team() -> TeamSim:
    rng = np.random.default_rng(8)
    boxes = [Rectangle(tuple(rng.uniform(-7, 7, 2)), (0.6, 0.4), float(rng.uniform(0, 3)))
             for _ in range(8)]
    world = World("room", obstacles=(
        Wall(((-9, -9), (9, -9), (9, 9), (-9, 9)), 0.2, True), *boxes))
    profile = robot_profile("pioneer2dx")
    places = [RobotPlace(f"r{i}", profile, LMS200,
                         Pose(1.6 * math.cos(i), 1.6 * math.sin(i), 2.0 * i))
              for i in range(6)]
    return TeamSim(world, places, seed=4)


@needs_kernel
@needs_cuts
def test_a_team_run_is_the_same_on_both_paths(monkeypatch: pytest.MonkeyPatch) -> None:
    def run() -> list[tuple[float, float, float, bytes, bytes]]:
        team, seen = _team(), []
        for k in range(40):
            for i, m in enumerate(team.members):
                m.command(Command(0.3, 0.5 * math.sin(0.3 * k + i)))
            team.step(0.1)
            for m in team.members:
                scan = m.observe().scan
                assert scan is not None
                pose = m.true_pose
                seen.append((pose.x, pose.y, pose.theta, scan.ranges.tobytes(),
                             scan.valid.tobytes()))
        return seen

    fast = run()
    monkeypatch.setattr(raycast, "COMPILED", False)
    monkeypatch.setattr(crowd, "_KERNELS", None)
    assert fast == run()


@needs_cuts
def test_the_occlusion_kernels_refuse_arrays_that_do_not_fit() -> None:
    assert crowd._KERNELS is not None
    cuts, apply = crowd._KERNELS
    # a disc 2 m ahead, and the robot's own far away (skipped)
    d = Discs(np.array([2.0, -50.0]), np.array([0.0, 0.0]), np.array([0.5, 0.25]),
              np.array([0, 1]))
    one = np.array([0.0])
    scans = (one, one, np.array([-0.5]), np.array([0.01]), np.array([101]), np.array([8.0]),
             np.array([1]), d.cx, d.cy, d.r)
    room = np.empty(100, np.intp), np.empty(100, np.intp), np.empty(100)
    assert cuts(*scans, *room) > 10                        # the disc ahead cuts some beams
    with pytest.raises(ValueError, match="no room"):
        cuts(*scans, np.empty(3, np.intp), np.empty(3, np.intp), np.empty(3))
    with pytest.raises(ValueError, match="beam"):
        cuts(*scans, room[0], room[1][:50], room[2])
    with pytest.raises(ValueError, match="rows of at least 101 beams"):
        apply(*scans, np.zeros((1, 100)), np.zeros((1, 100), bool))
    with pytest.raises(ValueError, match="valid"):
        apply(*scans, np.zeros((1, 101)), np.zeros((1, 101), np.int8))
    with pytest.raises(ValueError, match="skip"):
        apply(*scans[:6], np.array([-1.0]), *scans[7:], np.zeros((1, 101)),
              np.zeros((1, 101), bool))
    ranges, valid = np.full((1, 101), 8.0), np.zeros((1, 101), bool)
    apply(*scans, ranges, valid)
    assert valid.sum() > 10 and ranges.min() == pytest.approx(1.5, abs=1e-3)


@needs_kernel
@needs_cuts
def test_hostile_numbers_never_take_the_loops_outside_their_arrays() -> None:
    # NaN, infinite or huge origins and steps: garbage in, but never a crash or a write
    # outside the arrays (the C loops clamp every index they compute).
    d = Discs(np.array([2.0, 0.0]), np.array([0.0, 3.0]), np.array([0.5, 0.4]),
              np.array([0, 1]))
    odd = [math.nan, math.inf, -math.inf, 1e300, -1e300, 1e-300, 0.0]
    for x in odd:
        for step in [*odd, -0.01]:
            scans = (np.array([x]), np.array([0.0]), np.array([-0.5]), np.array([step]),
                     np.array([181], np.intp), np.array([8.0]), np.array([1], np.intp), d)
            scan, beam, t = occlusions(*scans, compiled=True)
            assert ((beam >= 0) & (beam < 181)).all() and (scan == 0).all()
            ranges, valid = np.full((1, 181), 8.0), np.zeros((1, 181), bool)
            occlude(*scans, ranges, valid, compiled=True)
            assert ranges.shape == (1, 181)
    fan = boxes_world(25, 6, 1).caster.fan(np.linspace(0.0, math.pi, 181), 8.0, True)
    headings = [a for a in odd if not math.isinf(a)]   # math.cos refuses an infinite one
    for x in odd:
        for first in headings:
            ranges, hit = fan.cast(x, 0.5, first)
            assert ranges.shape == hit.shape == (181,)
    many = fan.cast_many(np.array(odd), np.zeros(len(odd)), np.resize(headings, len(odd)))
    assert many[0].shape == (len(odd), 181)


@needs_kernel
@pytest.mark.parametrize("indexed", [False, True])
def test_a_single_face_in_range_casts_the_same_on_both_paths(indexed: bool) -> None:
    # A world of more than 256 faces where the bounding boxes in range hold one face
    # alone: numpy multiplies a single number in place in its plain scalar loop, which the
    # numpy path avoids for that face (tests/sim/test_sim_ellipse_kernel.py checks the
    # same quirk for the ellipses' numbers).
    block = Rectangle((0.0, -12.0), (30.0, 20.0), 0.0)       # its near face at y = -2
    far = [Rectangle((100.0 + 2 * i, 100.0), (0.5, 0.5), 0.0) for i in range(80)]
    world = World("one face", obstacles=(block, *far))
    rel = np.linspace(0.0, math.pi, 181)
    fast = world.caster.fan(rel, 8.0, True, indexed=indexed)
    ref = world.caster.fan(rel, 8.0, False)
    rng = np.random.default_rng(17)
    hits = 0
    for _ in range(400):
        x, y, first = rng.uniform(-5, 5), rng.uniform(-1.5, 4.0), rng.uniform(-7, 7)
        r1, h1 = fast.cast(float(x), float(y), float(first))
        r2, h2 = ref.cast(float(x), float(y), float(first))
        assert r1.tobytes() == r2.tobytes() and np.array_equal(h1, h2)
        hits += int(h1.sum())
    assert hits > 400 * 20
