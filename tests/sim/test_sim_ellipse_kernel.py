"""The compiled ellipses (sim/_kernels.c: the fan's cast, the clearance) give numpy's numbers.

Its two delicate parts each against numpy on millions of values: the complex absolute
value (numpy's own vectorised algorithm, not libm's ``hypot``) and the product of the
beams with the ellipses' coefficients (numpy's matmul, which BLAS rounds). Then whole
scans of many ellipse worlds and fans on both paths, the probe's fallback where BLAS
rounds otherwise; the clearance query's nearest points (Python's floats, to the bit);
and the paper's Figure 1 run end to end with and without the compiled ellipses: the
same trace, byte for byte.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mdle.atoms import estimators
from mdle.sim import collision, ladar, raycast
from mdle.sim.catalog import load_world
from mdle.sim.collision import Collider
from mdle.sim.distance import ellipse_nearest_point
from mdle.sim.shapes import Arc, Ellipse, Rectangle, Wall
from mdle.sim.world import World

REPO = Path(__file__).resolve().parents[2]

needs_ellipses = pytest.mark.skipif(not raycast.COMPILED_ELLIPSES,
                                    reason="this install has no compiled ellipse cast")


def _kernels() -> tuple[Callable[..., None], Callable[..., None], Callable[..., None]]:
    """The compiled ellipse cast, absolute value and product of the beams."""
    kernels = raycast._ELL
    assert kernels is not None
    return kernels.cast, kernels.absolute, kernels.product


def test_an_install_with_the_compiled_fan_cast_has_the_compiled_ellipses() -> None:
    # The probe must accept this machine's numpy: were it to refuse, the ellipses would
    # quietly fall back to numpy (the same numbers, four times the cost).
    if raycast.COMPILED:
        assert raycast._ELL is not None
        assert raycast._ABS_FUSED is not None and raycast.COMPILED_ELLIPSES


def _adversarial_parts() -> tuple[np.ndarray, np.ndarray]:
    """Every pair of awkward parts: signed zeros, subnormals, tiny, huge, inf, NaN, ties."""
    odd = np.array([0.0, -0.0, 5e-324, -5e-324, 2.2e-308, 1e-300, 1e-160, 0.5, 1.0, -1.0,
                    1.0 + 2.0 ** -52, 3.0, 4.0, 1e160, 1e300, 1.7976931348623157e308,
                    -1.7976931348623157e308, math.inf, -math.inf, math.nan])
    return np.repeat(odd, odd.shape[0]), np.tile(odd, odd.shape[0])


def _complex(re: np.ndarray, im: np.ndarray) -> np.ndarray:
    z = np.empty(re.shape[0], dtype=complex)
    z.real, z.imag = re, im
    return z


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal to the bit, NaN where NaN (numpy's NaN and C's may differ in payload)."""
    nan = np.isnan(a)
    return bool((nan == np.isnan(b)).all()
                and (a.view(np.int64)[~nan] == b.view(np.int64)[~nan]).all())


@needs_ellipses
def test_the_compiled_absolute_value_is_numpys_on_millions_of_values() -> None:
    _, absolute, _ = _kernels()
    rng = np.random.default_rng(2027)
    fused = raycast._ABS_FUSED
    wrong = 0
    for scale in (1.0, 1e-150, 1e150, 1e-305, 1e305):
        # parts of every magnitude ratio (some overflow to inf), and parts nearly equal
        # (where rounding bites)
        with np.errstate(over="ignore"):
            re = rng.standard_normal(500_000) * scale * 10.0 ** rng.uniform(-20, 20, 500_000)
            im = rng.standard_normal(500_000) * scale * 10.0 ** rng.uniform(-20, 20, 500_000)
            im[::3] = re[::3] * (1.0 + rng.uniform(-1e-6, 1e-6, im[::3].shape[0]))
        z = _complex(re, im)
        got = np.empty(z.shape[0])
        absolute(z, got, fused)
        assert _same_bits(got, np.abs(z))
        other = np.empty(z.shape[0])
        absolute(z, other, not fused)
        wrong += int((other != got).sum())
    re, im = _adversarial_parts()
    for n in (1, 2, 3, 7, 8, 9, 16, 17, re.shape[0]):     # the SIMD body and its tails
        z = _complex(re[-n:], im[-n:])
        got = np.empty(n)
        absolute(z, got, fused)
        assert _same_bits(got, np.abs(z)), n
    # libm's hypot would not do: numpy's algorithm differs from it here
    z = _complex(rng.standard_normal(100_000), rng.standard_normal(100_000))
    got = np.empty(z.shape[0])
    absolute(z, got, fused)
    assert (got != np.hypot(z.real, z.imag)).sum() > 10_000
    # and the other rounding differs too: the probe can tell them apart
    assert wrong > 1000


@needs_ellipses
def test_the_beams_product_is_numpys_matmul_for_one_ellipse() -> None:
    _, _, product = _kernels()
    rng = np.random.default_rng(4)
    for beams, fov in ((181, math.pi), (361, math.pi), (7, 1.0), (1, 0.0), (720, 6.2)):
        rel = np.linspace(-fov / 2, fov / 2, beams)
        d = np.exp(1j * rel)
        dd = np.column_stack([d, d.conjugate()])
        for _ in range(300):
            coef = (rng.standard_normal((2, 1)) + 1j * rng.standard_normal((2, 1))) \
                * 10.0 ** rng.uniform(-8, 8, (2, 1))
            want = dd @ coef
            got = np.empty_like(want)
            product(dd, coef, got)
            assert _same_bits(got.view(float), want.view(float))


@needs_ellipses
def test_the_in_place_probe_predicts_numpys_in_place_products() -> None:
    # Whatever it finds for a length (a plain scalar loop, the fused SIMD one), numpy's
    # in-place products of that length round so on fresh numbers too.
    rng = np.random.default_rng(44)
    for n in (1, 2, 3, 5, 8, 9):
        fused = raycast._numpy_inplace_rounding(n)
        assert fused is not None
        for _ in range(20):
            a = rng.standard_normal(n) + 1j * rng.standard_normal(n)
            b = rng.standard_normal(n) + 1j * rng.standard_normal(n)
            got = a.copy()
            got *= b
            assert [raycast._exact_product(complex(x), complex(y), fused)
                    for x, y in zip(a, b, strict=True)] == got.tolist()


def _ellipse_world(rng: np.random.Generator, count: int, walls: bool) -> World:
    shapes: list[Any] = [
        Ellipse((float(rng.uniform(-5, 5)), float(rng.uniform(-5, 5))),
                (float(rng.uniform(0.05, 4.0)), float(rng.uniform(0.05, 4.0))),
                float(rng.uniform(-4, 4)))
        for _ in range(count)]
    if walls:
        shapes += [Wall(((-8, -8), (8, -8), (8, 8), (-8, 8)), 0.2, True),
                   Rectangle((3.0, -3.0), (1.0, 0.5), 0.4),
                   Arc((-3.0, 3.0), 1.0, 0.3, 2.5, 0.2)]
    return World("ellipses", obstacles=tuple(shapes))


@needs_ellipses
@pytest.mark.parametrize("beams, fov", [(181, math.pi), (361, math.pi), (7, 1.0),
                                        (360, 2 * math.pi - 2 * math.pi / 360)])
@pytest.mark.parametrize("walls", [False, True])
def test_compiled_and_numpy_ellipse_scans_are_equal_bit_for_bit(
        beams: int, fov: float, walls: bool) -> None:
    rng = np.random.default_rng(beams + walls)
    rel = np.linspace(0.0, fov, beams)
    hits = compared = 0
    for _ in range(12):
        world = _ellipse_world(rng, 1, walls)
        fast, ref = world.caster.fan(rel, 8.0, True), world.caster.fan(rel, 8.0, False)
        assert fast.compiled_ellipses and not ref.compiled_ellipses
        assert fast._ellipses_only == (not walls)     # a whole scan in one call, or not
        P = world.caster.parts
        centre, axes, angle = P.ell_center[0], P.ell_axes[0], float(P.ell_angle[0])
        for k in range(250):
            if k % 5 == 0:      # on the boundary (within rounding), and inside it
                s = float(rng.uniform(-math.pi, math.pi))
                r = 1.0 if k % 10 == 0 else float(rng.uniform(0.0, 1.0))
                lx, ly = r * axes[0] * math.cos(s), r * axes[1] * math.sin(s)
                o = centre + [lx * math.cos(angle) - ly * math.sin(angle),
                              lx * math.sin(angle) + ly * math.cos(angle)]
            else:
                o = rng.uniform(-12.0, 12.0, 2)
            first = float(rng.uniform(-7.0, 7.0))
            r1, h1 = fast.cast(float(o[0]), float(o[1]), first)
            r2, h2 = ref.cast(float(o[0]), float(o[1]), first)
            assert r1.tobytes() == r2.tobytes() and np.array_equal(h1, h2)
            hits += int(h1.sum())
            compared += 1
    assert hits > compared * beams // 10     # the scans saw the ellipses (and walls)


def test_several_ellipses_keep_numpys_cast_where_blas_rounds_otherwise() -> None:
    # For five ellipses numpy's matmul is OpenBLAS's zgemm, whose rounding the compiled
    # product does not follow: the fan's probe sees it and keeps numpy's cast.
    rng = np.random.default_rng(9)
    world = _ellipse_world(rng, 5, True)
    rel = np.linspace(0.0, math.pi, 181)
    fan = world.caster.fan(rel, 8.0)
    assert not fan.compiled_ellipses
    ref = world.caster.fan(rel, 8.0, False)
    for _ in range(50):
        o, first = rng.uniform(-7, 7, 2), float(rng.uniform(-7, 7))
        r1, h1 = fan.cast(float(o[0]), float(o[1]), first)
        r2, h2 = ref.cast(float(o[0]), float(o[1]), first)
        assert r1.tobytes() == r2.tobytes() and np.array_equal(h1, h2)


@needs_ellipses
def test_the_probe_refuses_a_product_that_is_not_numpys(
        monkeypatch: pytest.MonkeyPatch) -> None:
    product = _kernels()[2]

    def off_by_an_ulp(dd: np.ndarray, coef: np.ndarray, out: np.ndarray) -> None:
        product(dd, coef, out)
        out.real = np.nextafter(out.real, math.inf)

    assert raycast._ELL is not None
    monkeypatch.setattr(raycast, "_ELL", dataclasses.replace(raycast._ELL, product=off_by_an_ulp))
    fan = load_world("ellipse").caster.fan(np.linspace(0.0, math.pi, 181), 8.0)
    assert not fan.compiled_ellipses


@needs_ellipses
def test_the_ellipse_kernel_refuses_arrays_that_do_not_fit() -> None:
    fan = load_world("ellipse").caster.fan(np.linspace(0.0, math.pi, 181), 8.0)
    ellipses = _kernels()[0]
    good: list[Any] = [np.full(181, 8.0), fan._dd, fan._ell_k, fan._ell_c, fan._ell_uconj,
                       fan._ell_alpha, fan._ell_beta, complex(-9, 0.3), 1j, 1e-12,
                       True, True, False]
    ellipses(*good)
    assert (good[0] < 8.0).any()
    for i, bad, match in [(0, np.zeros(181, dtype=np.float32), "t"),
                          (1, fan._dd[:-1].copy(), "dd"),
                          (2, np.zeros((2, 2), complex), "rows"),
                          (5, np.zeros(2), "alpha"),
                          (4, fan._ell_uconj.real.copy(), "uconj")]:
        args = list(good)
        args[i] = bad
        with pytest.raises((ValueError, BufferError), match=match):
            ellipses(*args)
    with pytest.raises(TypeError, match="13 arguments"):
        ellipses(*good[:-1])
    with pytest.raises(TypeError):
        ellipses(*good[:7], "here", *good[8:])


@needs_ellipses
def test_the_compiled_nearest_point_is_pythons_to_the_bit() -> None:
    near = collision._ELLIPSE_NEAR
    assert near is not None
    rng = np.random.default_rng(31)
    n = 200_000
    a, b = 10.0 ** rng.uniform(-2, 1, n), 10.0 ** rng.uniform(-2, 1, n)
    b[::7] = a[::7]                               # circles
    y0, y1 = rng.standard_normal(n) * a * 2, rng.standard_normal(n) * b * 2
    y1[::5] = 0.0                                 # on the major or minor axis
    y0[::11] = 0.0
    y0[::13] *= 1e-9                              # near the centre
    y1[::17] = -0.0
    for k in range(n):
        # one ellipse at the origin, unturned: the query is the point itself
        got = near(float(y0[k]), float(y1[k]), math.inf, np.zeros(1, complex),
                   np.ones(1, complex), np.zeros(1), np.array([a[k], b[k]]), True, True)
        (lx, ly, ex, ey, i), = got
        assert (lx, ly, i) == (y0[k], y1[k], 0)
        want = ellipse_nearest_point(float(a[k]), float(b[k]), lx, ly)
        assert (ex, ey) == want and math.copysign(1.0, ex) == math.copysign(1.0, want[0])


@needs_ellipses
def test_compiled_and_numpy_clearances_are_the_same() -> None:
    rng = np.random.default_rng(12)
    queries = 0
    for w in range(30):
        world = _ellipse_world(rng, int(rng.integers(1, 9)), bool(w % 2))
        fast, ref = Collider(world.parts, 0.2), Collider(world.parts, 0.2, compiled=False)
        assert fast._ell_near is not None and ref._ell_near is None
        P = world.parts
        for k in range(600):
            if k % 3 == 0:          # on an ellipse, inside it, at its centre, just outside
                j = int(rng.integers(0, P.ell_angle.shape[0]))
                s, r = float(rng.uniform(-4, 4)), float(rng.choice([0.0, 0.3, 1.0, 1.2]))
                lx, ly = r * P.ell_axes[j, 0] * math.cos(s), r * P.ell_axes[j, 1] * math.sin(s)
                turn = complex(math.cos(P.ell_angle[j]), math.sin(P.ell_angle[j]))
                z = complex(*P.ell_center[j]) + complex(lx, ly) * turn
                x, y = z.real, z.imag
            else:
                x, y = (float(v) for v in rng.uniform(-10, 10, 2))
            assert fast.distance(x, y) == ref.distance(x, y)
            queries += 1
    assert queries == 18_000
    # nine ellipses and more: the vectorised branch, never the compiled one
    many = _ellipse_world(rng, 9, False)
    assert Collider(many.parts, 0.2)._ell_near is None


def _fig1_trace(tmp_path: Path, name: str) -> bytes:
    from mdle.cli import main

    out = tmp_path / f"{name}.jsonl"
    plan = REPO / "plans" / "paper" / "fig1-ellipse.mdle"
    assert main(["run", str(plan), "--rate", "50", "--seed", "7", "--quiet",
                 "--trace", str(out)]) == 0
    text = out.read_bytes()
    # the header names the command line, the same in both but for the file's name
    return text.replace(str(out).encode(), b"TRACE")


@needs_ellipses
def test_figure_1_runs_to_the_same_trace_with_and_without_the_compiled_loops(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    kernels = raycast._ELL
    assert kernels is not None
    calls = [0]

    def counted(*args: Any) -> None:
        calls[0] += 1
        kernels.scan(*args)

    monkeypatch.setattr(raycast, "_ELL", dataclasses.replace(kernels, scan=counted))
    fast = _fig1_trace(tmp_path, "compiled")
    assert calls[0] >= 3000        # every scan of the 60 s at 50 Hz went through C
    before = calls[0]
    monkeypatch.setattr(raycast, "_ELL", None)
    monkeypatch.setattr(collision, "_ELLIPSE_NEAR", None)
    monkeypatch.setattr(ladar, "_SETTLE", None)
    monkeypatch.setattr(estimators, "_POINTS", None)
    slow = _fig1_trace(tmp_path, "numpy")
    assert calls[0] == before      # ... and none of the second run's
    assert fast == slow
    assert fast.count(b'"type":"scan"') >= 2900
