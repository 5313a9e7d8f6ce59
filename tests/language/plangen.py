"""Hypothesis strategies for MDLe plans that parse and check against the default registry.

Imported by the round-trip and fuzz tests (a plain module, not a test file).
"""

from __future__ import annotations

from hypothesis import strategies as hs

SPEEDS = ["0.3 m/s", "25 cm/s", "0.1 m/s", "1 m/s", "0 m/s"]
LENGTHS = ["1 m", "50 cm", "300 mm", "2.5 m", "0.8m"]
ANGLES = ["0 deg", "30 deg", "-90 deg", "0.5 rad", "45deg"]
RATES = ["30 deg/s", "-45 deg/s", "1 rad/s", "0.2 rad / s"]
TIMES = ["10 s", "2 min", "500 ms", "1.5 s", "3s"]
FACTORS = ["0.5", "2", "1", "0.25", "1.5"]

SEP = hs.sampled_from([", ", ",", ",\n    ", " ,  "])


@hs.composite
def condition(draw: hs.DrawFn, depth: int = 2) -> str:
    """A boolean interrupt expression over the shipped sensor functions."""
    simple = hs.sampled_from([
        "stalled", "never",
        *(f"range({a}) < {d}" for a in ANGLES[:2] for d in LENGTHS[:2]),
        f"min_range({ANGLES[2]}, {ANGLES[1]}) > {LENGTHS[3]}",
        *(f"x > {d}" for d in LENGTHS[:2]), f"y <= -{LENGTHS[0]}", f"t >= {TIMES[0]}",
        f"speed < {SPEEDS[0]}", f"theta != {ANGLES[1]}", f"turn_rate > {RATES[0]}",
        f"dist_to({LENGTHS[0]}, {LENGTHS[1]}) <= {LENGTHS[2]}", "x * 2 + y > 1 m",
        "(x - 1 m) / 2 < 0",
    ])
    if depth <= 0 or draw(hs.booleans()):
        return draw(simple)
    kind = draw(hs.sampled_from(["and", "or", "xor", "not", "paren"]))
    if kind == "not":
        return "not " + draw(condition(depth - 1))
    if kind == "paren":
        return "(" + draw(condition(depth - 1)) + ")"
    return f"{draw(condition(depth - 1))} {kind} {draw(condition(depth - 1))}"


@hs.composite
def law(draw: hs.DrawFn) -> str:
    """A control-law call."""
    return draw(hs.sampled_from([
        *(f"go({v})" for v in SPEEDS), "go(v = 0.2 m/s)", *(f"turn({r})" for r in RATES),
        "turn(rate = 10 deg/s)", "arc(0.2 m/s, 20 deg/s)", "arc(omega = -1 rad/s, v = 0.1 m/s)",
        "stop", "stop()",
    ]))


def timer() -> hs.SearchStrategy[str]:
    """A timer: a time, a bare number of seconds or inf."""
    return hs.sampled_from([*TIMES, "inf", "5", "0.5"])


@hs.composite
def element(draw: hs.DrawFn, atoms: list[str], strings: list[str], depth: int) -> str:
    """An element: a named one, an inline atom, a scaled atom or a nested string."""
    options = ["inline"]
    if atoms:
        options += ["atom", "scaled"]
    if strings:
        options.append("string")
    if depth > 0:
        options.append("group")
    kind = draw(hs.sampled_from(options))
    sep = draw(SEP)
    if kind == "atom":
        return draw(hs.sampled_from(atoms))
    if kind == "string":
        return draw(hs.sampled_from(strings))
    if kind == "inline":
        return f"({draw(law())}{sep}{draw(condition(1))}{sep}{draw(timer())})"
    if kind == "scaled":
        alpha = draw(hs.sampled_from([*FACTORS, "[0.5, 1]", "[2, 0.5]"]))
        return f"({alpha}{sep}{draw(hs.sampled_from(FACTORS))}{sep}{draw(hs.sampled_from(atoms))})"
    items = draw(hs.lists(element(atoms, strings, depth - 1), min_size=1, max_size=3))
    repeat = "..." if draw(hs.booleans()) else ""
    return f"(({sep.join(items)}){repeat}{sep}{draw(condition(1))}{sep}{draw(timer())})"


@hs.composite
def plan(draw: hs.DrawFn) -> str:
    """A whole plan: named interrupts, atoms, behaviors, a main plan, maybe comments."""
    lines: list[str] = []
    interrupts = []
    for i in range(draw(hs.integers(0, 2))):
        lines.append(f"interrupt i{i}(d = {draw(hs.sampled_from(LENGTHS))}) = range(0 deg) < d")
        interrupts.append(f"i{i}")
    atoms: list[str] = []
    for i in range(draw(hs.integers(1, 4))):
        cond = draw(hs.one_of(condition(2), hs.sampled_from(interrupts or ["stalled"])))
        params = "(v = 0.3 m/s)" if draw(hs.booleans()) else ""
        control = "go(v)" if params else draw(law())
        lines.append(f"atom a{i}{params} = ({control}, {cond}, {draw(timer())})")
        atoms.append(f"a{i}")
        if draw(hs.booleans()):
            lines.append(f"# note on a{i}")
    strings: list[str] = []
    for i in range(draw(hs.integers(0, 3))):
        items = draw(hs.lists(element(atoms, strings, 2), min_size=1, max_size=4))
        sep = draw(SEP)
        lines.append(f"behavior b{i} = (({sep.join(items)}){'...' if draw(hs.booleans()) else ''}"
                     f"{sep}{draw(condition(1))}{sep}{draw(timer())})")
        strings.append(f"b{i}")
    items = draw(hs.lists(element(atoms, strings, 2), min_size=1, max_size=4))
    lines.append(f"plan main = (({', '.join(items)}), {draw(condition(2))}, "
                 f"{draw(timer())})  # the entry")
    if draw(hs.booleans()):
        lines.append("run main")
    joiner = draw(hs.sampled_from(["\n", "\n\n", "\n  \n"]))
    return joiner.join(lines) + "\n"
