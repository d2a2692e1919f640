"""Bad inputs by family, each a :class:`Case`: files to write and the ``minkplan``
arguments to run on them, drawn deterministically from a seed.

Families: ``mesh`` (files for ``minkplan minkowski``: empty, garbage, truncated and
miscounted binary STL, NaN/inf, extreme scales, degenerate, open, inverted,
self-intersecting, non-manifold, many shells, OBJ n-gons with bad indices, a directory, a
device), ``scenario`` (YAML for ``minkplan plan``: missing and misspelled keys, wrong
types, anchor bombs, tabs, huge numbers, start/goal outside the bounds or in collision,
mesh paths to folders or devices, non-UTF-8, duplicate keys), ``assembly`` (the same for
``minkplan assemble``), ``cli`` (arguments: bad numbers, unknown choices and options) and
``output`` (outputs under a file, in ``/proc``, names over the file-name limit).

Every case names its outputs under ``out/`` of the case's folder, so the runner can tell a
partial output from none.
"""

from __future__ import annotations

import io
import random
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import trimesh

__all__ = ["FAMILIES", "Case", "cases"]


@dataclass(frozen=True)
class Case:
    """One fuzz input: ``files`` (relative path -> bytes, written in the case's folder;
    ``None`` makes a folder), then ``minkplan *argv`` run in that folder."""

    name: str
    family: str
    argv: tuple[str, ...]
    files: dict[str, bytes | None] = field(default_factory=dict)


def _stl(mesh: trimesh.Trimesh) -> bytes:
    buffer = io.BytesIO()
    mesh.export(buffer, file_type="stl")
    return buffer.getvalue()


def _cube(scale: float = 1.0, at=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    mesh = trimesh.creation.box(extents=[scale] * 3)
    mesh.apply_translation(at)
    return mesh


def _minkowski(name: str, mesh_bytes: bytes, suffix: str = "stl") -> Case:
    return Case(name, "mesh", ("minkowski", f"a.{suffix}", "b.stl", "-o", "out/sum.stl",
                               "--no-progress"),
                {f"a.{suffix}": mesh_bytes, "b.stl": _stl(_cube())})


# ---------------------------------------------------------------- meshes


def _mesh_cases(rng: random.Random) -> list[Case]:
    cube = _cube()
    good = _stl(cube)
    scale = 10.0 ** rng.choice([200, 250, 300, -12, -200, 30])
    scaled = cube.copy()
    scaled.apply_scale(scale)
    nan = cube.copy()
    vertices = nan.vertices.copy()
    vertices[rng.randrange(len(vertices)), rng.randrange(3)] = rng.choice(
        [np.nan, np.inf, -np.inf])
    open_cube = trimesh.Trimesh(cube.vertices, cube.faces[rng.randrange(1, 12):],
                                process=False)
    inverted = cube.copy()
    inverted.invert()
    crossing = trimesh.util.concatenate([_cube(), _cube(at=(0.5, 0.5, 0.5))])
    fin = trimesh.Trimesh(np.vstack([cube.vertices, [[0.0, 0.0, 2.0]]]),
                          np.vstack([cube.faces, [[0, 1, 8]]]), process=False)
    shells = trimesh.util.concatenate([_cube(0.01, (i * 0.02, 0.0, 0.0))
                                       for i in range(rng.randint(50, 400))])
    flat = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]],
                           [[0, 1, 2], [1, 2, 3], [0, 2, 3], [0, 1, 3]], process=False)
    n = rng.randint(0, 2**32 - 1)
    cut = rng.randrange(1, len(good))
    ngon = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4 {}\n".format(
        rng.choice(["9", "0", "-7", "x", "1.5"]))
    return [
        _minkowski("empty", b""),
        _minkowski("garbage", bytes(rng.getrandbits(8) for _ in range(rng.randint(1, 300)))),
        _minkowski("truncated", good[:cut]),
        _minkowski("miscounted", good[:80] + n.to_bytes(4, "little") + good[84:]),
        _minkowski("nan_vertex", _stl(trimesh.Trimesh(vertices, nan.faces, process=False))),
        _minkowski(f"scale_{scale:.0e}", _stl(scaled)),
        _minkowski("open", _stl(open_cube)),
        _minkowski("inverted", _stl(inverted)),
        _minkowski("self_intersecting", _stl(crossing)),
        _minkowski("non_manifold", _stl(fin)),
        _minkowski("many_shells", _stl(shells)),
        _minkowski("degenerate", _stl(flat)),
        _minkowski("ngon_bad_index", ngon.encode(), "obj"),
        Case("mesh_is_a_folder", "mesh", ("minkowski", "a.stl", "b.stl", "-o", "out/s.stl"),
             {"a.stl": None, "b.stl": good}),
        Case("mesh_is_a_device", "mesh", ("minkowski", "/dev/zero", "b.stl", "-o",
                                          "out/s.stl"), {"b.stl": good}),
        Case("bad_eps", "mesh", ("minkowski", "a.stl", "b.stl", "-o", "out/s.stl", "--eps",
                                 rng.choice(["0", "-1", "nan", "inf", "1e-300", "abc"])),
             {"a.stl": good, "b.stl": good}),
    ]


# ---------------------------------------------------------------- scenarios

_SCENARIO = """name: fuzz
robot: {name: peg, box: [1, 1, 1]}
obstacles:
  - {name: wall, box: [1, 10, 10], position: [3, 0, 0]}
start: [0, 0, 0]
goal: [6, 0, 0]
bounds: {min: [-5, -8, -8], max: [10, 8, 8]}
planner: {time_limit: 5}
"""


def _plan(name: str, text: str | bytes, files: dict[str, bytes | None] | None = None,
          family: str = "scenario") -> Case:
    data = text.encode() if isinstance(text, str) else text
    return Case(name, family, ("plan", "s.yaml", "--out", "out", "--no-progress"),
                {"s.yaml": data, **(files or {})})


def _scenario_cases(rng: random.Random) -> list[Case]:
    s = _SCENARIO
    number = rng.choice(["1e400", "-1e400", ".nan", ".inf", "1e308", "99999999999999999999"])
    key = rng.choice(["start", "goal", "robot", "obstacles"])
    lines = s.splitlines(keepends=True)
    bomb = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{c}: &{c} [{', '.join(['*' + chr(ord(c) - 1)] * 9)}]\n" for c in "bcdefghi")
    return [
        _plan("missing_key", "".join(line for line in lines if not line.startswith(key))),
        _plan("misspelled_key", s.replace("start:", "strat:")),
        _plan("wrong_type", s.replace("start: [0, 0, 0]", rng.choice(
            ["start: zero", "start: [0, 0]", "start: {x: 1}", "start: [a, b, c]"]))),
        _plan("anchor_bomb", bomb + s),
        _plan("tabs", s.replace("  - ", "\t- ")),
        _plan("huge_number", s.replace("goal: [6, 0, 0]", f"goal: [{number}, 0, 0]")),
        _plan("outside_bounds", s.replace("goal: [6, 0, 0]", "goal: [60, 0, 0]")),
        _plan("in_collision", s.replace("start: [0, 0, 0]", "start: [3, 0, 0]")),
        _plan("mesh_is_a_folder", s.replace("box: [1, 1, 1]", "mesh: parts"),
              {"parts": None}),
        _plan("mesh_is_a_device", s.replace("box: [1, 1, 1]", "mesh: /dev/zero")),
        _plan("non_utf8", s.encode() + bytes([0xFF, 0xFE, 0x80]) + b"\n"),
        _plan("duplicate_key", s + "start: [1, 1, 1]\n"),
        _plan("not_a_mapping", rng.choice(["[1, 2, 3]", "just text", "", "~"])),
        _plan("garbage", bytes(rng.getrandbits(8) for _ in range(rng.randint(1, 200)))),
        _plan("bad_planner_value", s.replace("time_limit: 5", rng.choice(
            ["time_limit: -1", "time_limit: abc", "seed: -3", "resolution: 0",
             "exact: maybe", "clearance: -1"]))),
    ]


_ASSEMBLY = """name: fuzz
base: block
parts:
  - {name: block, box: [4, 4, 1], position: [0, 0, -0.5]}
  - {name: peg, box: [1, 1, 1], position: [0, 0, 0.5]}
"""


def _assemble(name: str, text: str | bytes) -> Case:
    data = text.encode() if isinstance(text, str) else text
    return Case(name, "assembly", ("assemble", "a.yaml", "--out", "out", "--no-progress"),
                {"a.yaml": data})


def _assembly_cases(rng: random.Random) -> list[Case]:
    a = _ASSEMBLY
    return [
        _assemble("no_parts", "name: x\nparts: []\n"),
        _assemble("one_part", "parts:\n  - {name: a, box: [1, 1, 1]}\n"),
        _assemble("duplicate_names", a.replace("name: peg", "name: block")),
        _assemble("unknown_base", a.replace("base: block", "base: lid")),
        _assemble("overlapping", a.replace("position: [0, 0, 0.5]", "position: [0, 0, 0]")),
        _assemble("wrong_type", a.replace("box: [1, 1, 1]", rng.choice(
            ["box: one", "box: [1, 1]", "box: [-1, 1, 1]", "box: [.nan, 1, 1]"]))),
        _assemble("misspelled", a.replace("parts:", "prts:")),
        _assemble("garbage", bytes(rng.getrandbits(8) for _ in range(rng.randint(1, 200)))),
    ]


# ---------------------------------------------------------------- arguments, outputs


def _cli_cases(rng: random.Random) -> list[Case]:
    files: dict[str, bytes | None] = {"s.yaml": _SCENARIO.encode()}
    picks = [
        ("--time-limit", rng.choice(["0", "-1", "nan", "inf", "abc", "1e999"])),
        ("--seed", rng.choice(["-1", "1.5", "abc", "99999999999999999999999"])),
        ("--planner", rng.choice(["ompl:", "ompl:Nope", "rrt", ""])),
        ("--exact", rng.choice(["maybe", "", "TRUE"])),
        ("--hold-orientation", rng.choice(["middle", ""])),
    ]
    flag, value = rng.choice(picks)
    return [
        Case(f"plan_{flag.strip('-')}", "cli", ("plan", "s.yaml", "--out", "out", flag, value),
             files),
        Case("unknown_option", "cli", ("plan", "s.yaml", "--out", "out",
                                       rng.choice(["--tme-limit", "--fast", "-q"]), "1"), files),
        Case("unknown_command", "cli", (rng.choice(["plam", "solve", "--nope"]),), {}),
        Case("missing_argument", "cli", (rng.choice(["plan", "assemble", "minkowski",
                                                     "batch"]),), {}),
        Case("batch_bad_runs", "cli", ("batch", "s.yaml", "--out", "out", "--runs",
                                       rng.choice(["0", "-2", "x"])), files),
        _memory_case(rng, files),
    ]


def _memory_case(rng: random.Random, files: dict[str, bytes | None]) -> Case:
    """``--memory-limit`` out of range (0, negative, NaN, inf, huge, not a number), or
    valid but too small for the work, before or after the subcommand: exit 2, one line."""
    value = rng.choice(["0", "-1", "nan", "inf", "-inf", "1e30", "abc", "", "0.0001",
                        "0.002", "0.01"])
    command = rng.choice([("plan", "s.yaml", "--out", "out", "--no-progress"),
                          ("minkowski", "m.stl", "m.stl", "-o", "out/s.stl", "--eps", "0.01",
                           "--no-progress")])
    argv = ((*command, "--memory-limit", value) if rng.random() < 0.5
            else ("--memory-limit", value, *command))
    box = (b"solid b\n" + b"".join(
        b"facet normal 0 0 0\nouter loop\n" + b"".join(
            b"vertex %d %d %d\n" % v for v in tri) + b"endloop\nendfacet\n"
        for tri in _BOX_TRIANGLES) + b"endsolid b\n")
    return Case(f"memory_limit_{command[0]}", "cli", argv, {**files, "m.stl": box})


_BOX_TRIANGLES = [  # a unit cube, outward
    ((0, 0, 0), (0, 1, 0), (1, 1, 0)), ((0, 0, 0), (1, 1, 0), (1, 0, 0)),
    ((0, 0, 1), (1, 0, 1), (1, 1, 1)), ((0, 0, 1), (1, 1, 1), (0, 1, 1)),
    ((0, 0, 0), (1, 0, 0), (1, 0, 1)), ((0, 0, 0), (1, 0, 1), (0, 0, 1)),
    ((0, 1, 0), (0, 1, 1), (1, 1, 1)), ((0, 1, 0), (1, 1, 1), (1, 1, 0)),
    ((0, 0, 0), (0, 0, 1), (0, 1, 1)), ((0, 0, 0), (0, 1, 1), (0, 1, 0)),
    ((1, 0, 0), (1, 1, 0), (1, 1, 1)), ((1, 0, 0), (1, 1, 1), (1, 0, 1)),
]


def _output_cases(rng: random.Random) -> list[Case]:
    files: dict[str, bytes | None] = {"s.yaml": _SCENARIO.encode(), "file": b"x"}
    where = rng.choice(["file/out", "/proc/minkplan-out", "x" * 300 + "/o"])
    command = rng.choice([("plan", "s.yaml", "--out", where),
                          ("minkowski", "file", "file", "-o", where + "/s.stl")])
    return [Case(f"unwritable_{command[0]}", "output", (*command, "--no-progress"), files)]


FAMILIES: dict[str, Callable[[random.Random], list[Case]]] = {
    "mesh": _mesh_cases,
    "scenario": _scenario_cases,
    "assembly": _assembly_cases,
    "cli": _cli_cases,
    "output": _output_cases,
}


def cases(seed: int, rounds: int = 1) -> list[Case]:
    """``rounds`` draws of every family's cases, from ``seed`` (the same seed, the same
    cases)."""
    rng = random.Random(seed)
    every: list[Case] = []
    # making broken meshes (NaN vertices) warns in trimesh: those warnings are the
    # generator's, not the product's
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        for round_ in range(rounds):
            for family, make in FAMILIES.items():
                every += [Case(f"{family}/{c.name}#{round_}", c.family, c.argv, c.files)
                          for c in make(rng)]
    return every
