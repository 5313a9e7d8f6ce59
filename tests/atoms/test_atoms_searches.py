"""The compiled searches of the whole-scan model (atoms/_searches.c) give numpy's answers.

The other tests run whichever path the install has; these put the two side by side: the
nearest point on the followed side, the points around it and the next face's point on
random noisy scans of several surfaces (millimetre points, so ties are common), moved and
mirrored as the atom moves and mirrors them; the cases where the compiled search hands
over to numpy (a distance at the limit, NaN, arrays in another form); and whole seeded
runs of ``follow_boundary``, which give the same numbers either way.
"""

from __future__ import annotations

import dataclasses
import math
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mdle.atoms import closest as C
from mdle.atoms import searches as S

PLANS = Path(__file__).resolve().parents[2] / "plans" / "paper"

# Skips only on an install built without a C compiler: the first test below fails an
# install that had one and did not build the searches, so these never skip unnoticed.
needs_build = pytest.mark.skipif(S._COMPILED is None,
                                 reason="this install has no compiled searches")


def test_an_install_built_with_a_c_compiler_has_the_compiled_searches() -> None:
    # The build is optional (pyproject.toml): this pins that it really happens where it can.
    if shutil.which("cc") or shutil.which("gcc"):
        assert S._COMPILED is not None and S.COMPILED


def _scene(seed: int) -> np.ndarray:
    """Law-frame points of a noisy scan of a few discs and walls, some beams missing.

    Moved by a small random motion (the latency prediction's shift) on odd seeds, and
    mirrored (the left side's law frame) on seeds divisible by 3.
    """
    rng = np.random.default_rng(seed)
    bearings = np.radians(np.arange(-90.0, 90.5, 1.0))
    u = np.exp(1j * bearings)
    r = np.full(bearings.size, np.inf)
    for _ in range(int(rng.integers(1, 5))):
        c = complex(rng.uniform(-1.0, 3.0), rng.uniform(-2.5, 2.5))
        rho = rng.uniform(0.02, 0.6)
        b = (u.conjugate() * c).real
        disc = b * b - abs(c) ** 2 + rho * rho
        hit = np.where(disc >= 0, b - np.sqrt(np.maximum(disc, 0.0)), np.inf)
        r = np.minimum(r, np.where(hit > 0, hit, np.inf))
    if rng.random() < 0.5:  # a wall on the right
        wall = -rng.uniform(0.3, 1.5) / np.where(bearings < 0, np.sin(bearings), np.nan)
        r = np.minimum(r, np.where(wall > 0, wall, np.inf))
    r = np.round(r * (1.0 + rng.normal(0.0, 0.008, r.shape)), 3)  # whole millimetres
    r[rng.random(r.size) < 0.05] = np.inf
    ok = np.isfinite(r)
    z = r[ok] * u[ok]
    if seed % 2:
        dth = rng.uniform(-0.1, 0.1)
        z = (z - complex(rng.uniform(0, 0.1), rng.uniform(-0.02, 0.02))) \
            * complex(math.cos(dth), -math.sin(dth))
    if seed % 3 == 0:
        z = z[::-1].conjugate()
    return np.ascontiguousarray(z)


def _d2(z: np.ndarray) -> np.ndarray:
    d2 = z.real * z.real
    d2 += z.imag * z.imag
    return d2


@needs_build
@pytest.mark.parametrize("seed", range(60))
def test_the_compiled_searches_answer_as_numpy(seed: int) -> None:
    z = _scene(seed)
    d2 = _d2(z)
    k = S._COMPILED.nearest_right(z, d2)
    assert k != S.AMBIGUOUS
    assert k == S.nearest_right_numpy(z, d2)
    if z.size == 0:
        return
    rng = np.random.default_rng(1000 + seed)
    for q, radius in ((complex(z[max(k, 0)]), 0.25), (complex(z[0]), 0.125),
                      (complex(rng.normal(), rng.normal()), 0.7)):
        sel = np.empty(z.size, dtype=bool)
        assert S._COMPILED.within(z, q, radius, sel) == int(S.within_numpy(z, q, radius).sum())
        assert np.array_equal(sel, S.within_numpy(z, q, radius))
    for fitted in (S.within(z, complex(z[max(k, 0)]), 0.25), rng.random(z.size) < 0.1,
                   np.zeros(z.size, dtype=bool)):
        got = S._COMPILED.next_face(z, d2, fitted, C.WINDOW, C.JUMP)
        assert got != S.AMBIGUOUS
        assert got == S.next_face_numpy(z, d2, fitted, C.WINDOW, C.JUMP)


@needs_build
def test_the_compiled_squared_ranges_are_numpys_bit_for_bit() -> None:
    # scans, and values at the ends of the doubles' range (squares that underflow to
    # subnormals or zero, overflow to inf, signed zeros): the same bits as numpy's
    rng = np.random.default_rng(11)
    odd = np.array([0.0, -0.0, 5e-324, -5e-324, 1e-160, 2.2e-308, 1e154, -1e155, 1.7e308,
                    math.inf, -math.inf, 3.7, -0.001, 9.999])
    edges = np.empty(odd.size * odd.size, dtype=complex)
    edges.real, edges.imag = np.repeat(odd, odd.size), np.tile(odd, odd.size)
    wide = (rng.normal(size=4000) * 10.0 ** rng.integers(-170, 170, 4000)
            + 1j * rng.normal(size=4000) * 10.0 ** rng.integers(-170, 170, 4000))
    for z in [_scene(seed) for seed in range(60)] + [edges, wide, np.zeros(0, complex)]:
        got = S.squared_ranges(z)
        assert got.dtype == np.float64 and got.shape == z.shape
        with np.errstate(over="ignore", under="ignore"):
            assert got.tobytes() == S.squared_ranges_numpy(z).tobytes()
    # NaN stays NaN; strided and single-precision points are left to numpy
    nan = np.array([complex(math.nan, 1.0), complex(2.0, math.nan), 3.0 - 4.0j])
    assert np.array_equal(S.squared_ranges(nan), [math.nan, math.nan, 25.0], equal_nan=True)
    z = _scene(4)
    assert S._COMPILED.squared_ranges(z[::2], np.empty(z[::2].size)) == S.AMBIGUOUS
    assert S._COMPILED.squared_ranges(z, np.empty(z.size - 1)) == S.AMBIGUOUS
    for other in (z[::2], z.astype(np.complex64)):
        assert S.squared_ranges(other).tobytes() == S.squared_ranges_numpy(other).tobytes()


@needs_build
@pytest.mark.parametrize("seed", range(20))
def test_points_within_reach_of_the_robot_are_numpys_modulus_below_it(seed: int) -> None:
    # the safety layer reads the points within reach as within(z, 0, reach): numpy's
    # abs(z) < reach, whichever path answers
    z = _scene(seed)
    for reach in np.random.default_rng(seed).uniform(0.1, 3.0, 25):
        assert np.array_equal(S.within(z, 0j, float(reach)), np.abs(z) < reach)
        assert np.array_equal(S.within_numpy(z, 0j, float(reach)), np.abs(z) < reach)


@needs_build
def test_a_distance_at_the_limit_is_left_to_numpy(monkeypatch: pytest.MonkeyPatch) -> None:
    # points 0.25 m and (to rounding) 0.2 m apart: the compiled search cannot tell on which
    # side of the limit numpy's modulus falls, so numpy answers
    z = np.array([0.5 - 0.5j, 0.75 - 0.5j, 0.95 - 0.5j, 1.0 + 0.0j])
    d2 = _d2(z)
    sel = np.empty(4, dtype=bool)
    assert S._COMPILED.within(z, complex(z[0]), 0.25, sel) == S.AMBIGUOUS
    assert np.array_equal(S.within(z, complex(z[0]), 0.25), S.within_numpy(z, z[0], 0.25))
    fitted = np.array([False, True, False, False])
    assert S._COMPILED.next_face(z, d2, fitted, C.WINDOW, 0.2) == S.AMBIGUOUS
    assert S._COMPILED.next_face(z, d2, fitted, C.WINDOW, 0.25) == S.AMBIGUOUS
    got = C.next_nearest(z, d2, fitted)
    monkeypatch.setattr(S, "_COMPILED", None)
    assert got == C.next_nearest(z, d2, fitted)


@needs_build
def test_nan_and_other_forms_are_left_to_numpy() -> None:
    z = _scene(4)
    d2 = _d2(z)
    fitted = S.within(z, complex(z[3]), 0.25)
    bad = d2.copy()
    bad[5] = math.nan
    zbad = z.copy()
    zbad[5] = complex(math.nan, -1.0)
    assert S._COMPILED.nearest_right(zbad, _d2(zbad)) == S.AMBIGUOUS
    assert S._COMPILED.next_face(z, bad, fitted, C.WINDOW, C.JUMP) == S.AMBIGUOUS
    assert S._COMPILED.within(zbad, complex(z[3]), 0.25, np.empty(z.size, bool)) == S.AMBIGUOUS
    # strided, another dtype, a read-only mask to write, another length, no limit
    assert S._COMPILED.nearest_right(z[::2], d2[::2]) == S.AMBIGUOUS
    assert S._COMPILED.nearest_right(z.astype(np.complex64), d2) == S.AMBIGUOUS
    ro = np.empty(z.size, dtype=bool)
    ro.setflags(write=False)
    assert S._COMPILED.within(z, 0j, 0.25, ro) == S.AMBIGUOUS
    assert S._COMPILED.next_face(z, d2[1:], fitted, C.WINDOW, C.JUMP) == S.AMBIGUOUS
    assert S._COMPILED.within(z, 0j, 0.0, np.empty(z.size, bool)) == S.AMBIGUOUS
    assert S._COMPILED.next_face(z, d2, fitted, C.WINDOW, -1.0) == S.AMBIGUOUS
    # and the wrappers answer as numpy there
    assert S.nearest_right(zbad, _d2(zbad)) == S.nearest_right_numpy(zbad, _d2(zbad))
    assert np.array_equal(S.within(z, 0j, 0.0), np.zeros(z.size, dtype=bool))
    with pytest.raises(TypeError, match="takes 5 arguments"):
        S._COMPILED.next_face(z, d2, fitted)


def _runs(monkeypatch: pytest.MonkeyPatch, fn: Any) -> tuple[Any, Any]:
    """Run ``fn()`` with the compiled searches, then with numpy's only."""
    compiled = fn()
    monkeypatch.setattr(S, "_COMPILED", None)
    return compiled, fn()


@needs_build
@pytest.mark.parametrize("element", ["main", "mirrored"])
def test_a_seeded_run_is_the_same_with_either_path(monkeypatch: pytest.MonkeyPatch,
                                                   element: str) -> None:
    from mdle.experiments.following import run_follow

    def hexagon() -> Any:
        return run_follow(str(PLANS / "fig2-hexagon.world.yaml"), rc=0.5, sensing="scan",
                          robot="ideal", plan=str(PLANS / "fig2-hexagon.mdle"),
                          element=element, duration=20.0)

    compiled, numpy_only = _runs(monkeypatch, hexagon)
    assert dataclasses.asdict(compiled) == dataclasses.asdict(numpy_only)


@needs_build
def test_a_pioneer_run_with_latency_is_the_same_with_either_path(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # the Pioneer's latency moves the points (the prediction's shift) before the searches
    from mdle.lang import load_program
    from mdle.runtime import run
    from mdle.runtime.observer import Recorder
    from mdle.sim import SimBackend, load_world

    def corridor() -> Any:
        program = load_program(PLANS / "fig6-corridor.mdle")
        rec = Recorder()
        run(program.elements["main"], SimBackend(load_world(PLANS / "fig6-corridor.world.yaml")),
            rate=10.0, observers=[rec])
        return [(s.true_x, s.true_y, sorted(s.diag.items())) for s in rec.samples]

    compiled, numpy_only = _runs(monkeypatch, corridor)
    assert len(compiled) > 100
    assert compiled == numpy_only
