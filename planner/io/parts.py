"""The parts of a problem file: the mapping of one object (a mesh file or a primitive,
with name, pose, scale, ``kind``, ``repair``) to a checked :class:`~planner.problem.Part`.

Entry points: :func:`object_spec` (cheap checks of one object, file existence),
:func:`build_part` (the part, its mesh read once per file and made a solid or a surface
by :func:`planner.meshes.kinds.classify`), :func:`assign_names`.
"""

from __future__ import annotations

import difflib
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from planner.meshes import MESH_SUFFIXES
from planner.meshes.kinds import KINDS, Classified, classify
from planner.primitives import PRIMITIVE_KINDS, make_primitive
from planner.problem import Part, Pose
from planner.values import describe_value

from .fields import check_mapping, field_error, join, name_of, parse_orientation, real, vector

__all__ = ["OBSTACLE_KEYS", "ROBOT_KEYS", "MeshCache", "ObjectSpec", "assign_names",
           "build_part", "object_spec", "rotation4"]


ROBOT_KEYS = ("name", "mesh", *PRIMITIVE_KINDS, "scale", "repair", "kind")


OBSTACLE_KEYS = ("name", "mesh", *PRIMITIVE_KINDS, "position", "orientation", "scale", "repair",
                 "kind")


@dataclass
class ObjectSpec:
    field: str
    name: str | None
    mesh_path: Path | None
    primitive: dict[str, Any] | None
    scale: np.ndarray
    pose: Pose
    repair: bool = False
    kind: str = "auto"


def object_spec(value: Any, field: str, allowed: Sequence[str], base_dir: Path) -> ObjectSpec:
    if isinstance(value, str):
        raise field_error(field, f"expected a mapping such as {{mesh: {value}}} or "
                            f"{{box: [sx, sy, sz]}}, got {describe_value(value)}")
    if field == "robot" and isinstance(value, Mapping):
        if "orientation" in value:
            raise field_error("robot.orientation", "the robot's orientation is the start's: write "
                                              "start: {position: [x, y, z], orientation: ...}")
        if "position" in value:
            raise field_error("robot.position", "the robot's position is given by start and goal; "
                                           "remove it")
    spec = check_mapping(value, field, allowed)
    sources = [key for key in ("mesh", *PRIMITIVE_KINDS) if key in spec]
    if not sources:
        raise field_error(join(field, "mesh"),
                     "missing required field (or a primitive: box, sphere, cylinder)")
    if len(sources) > 1:
        raise field_error(join(field, sources[1]),
                     f"give only one of {', '.join(sources)} (a mesh file or one primitive)")
    name = None if spec.get("name") is None else name_of(spec["name"], join(field, "name"))
    mesh_path = None
    primitive = None
    if sources[0] == "mesh":
        mesh_path = _resolve_mesh(spec["mesh"], join(field, "mesh"), base_dir)
    else:
        primitive = {sources[0]: spec[sources[0]]}
    scale = np.ones(3)
    if spec.get("scale") is not None:
        scale_field = join(field, "scale")
        raw = spec["scale"]
        if isinstance(raw, (list, tuple)):
            scale = vector(raw, scale_field, form="[sx, sy, sz]")
        else:
            scale = np.full(3, real(raw, scale_field))
        if np.any(scale <= 0):
            raise field_error(scale_field, f"scale factors must be > 0, got {raw!r}")
    position = np.zeros(3)
    if spec.get("position") is not None:
        position = vector(spec["position"], join(field, "position"))
    rotation = parse_orientation(spec.get("orientation"), field=join(field, "orientation"))
    repair = False
    if spec.get("repair") is not None:
        if not isinstance(spec["repair"], bool):
            raise field_error(join(field, "repair"),
                         f"expected true or false, got {describe_value(spec['repair'])}")
        if mesh_path is None:
            raise field_error(join(field, "repair"), "only mesh files can be repaired")
        repair = spec["repair"]
    kind = "auto"
    if spec.get("kind") is not None:
        kind = spec["kind"]
        if kind not in KINDS:
            close = difflib.get_close_matches(str(kind), KINDS, n=1, cutoff=0.5)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            raise field_error(join(field, "kind"), f"expected one of {', '.join(KINDS)}, got "
                                                   f"{describe_value(kind)}{hint}")
    return ObjectSpec(field, name, mesh_path, primitive, scale, Pose(position, rotation),
                      repair, kind)


def _resolve_mesh(value: Any, field: str, base_dir: Path) -> Path:
    if not isinstance(value, str) or not value.strip():
        raise field_error(field, f"expected a file path (relative to the scenario file), got "
                            f"{describe_value(value)}")
    path = Path(os.path.expanduser(value.strip()))
    if not path.is_absolute():
        path = base_dir / path
    if path.is_file():
        return path
    folder = path.parent.resolve()
    hint = ""
    if folder.is_dir():
        # only mesh files are worth suggesting for a mesh
        names = sorted(p.name for p in folder.iterdir()
                       if p.is_file() and p.suffix.lower() in MESH_SUFFIXES)
        close = difflib.get_close_matches(path.name, names, n=1, cutoff=0.6)
        if close:
            hint = f"; did you mean '{close[0]}'?"
    elif not path.exists():
        hint = "; that folder does not exist either"
    if path.exists():
        raise field_error(field, f"'{value}' is not a file (looked in {folder})")
    raise field_error(field, f"file '{value}' not found (looked in {folder}){hint}")


MeshCache = dict[tuple[Path, bool, str], tuple[Classified, str]]


def build_part(spec: ObjectSpec, name: str, cache: MeshCache,
               transform: np.ndarray | None = None) -> Part:
    """The object as a :class:`~planner.problem.Part`: its mesh in its own frame with the
    scale applied (then ``transform``, ``(4, 4)``, if given), solid or surface as its
    ``kind`` says (:func:`planner.meshes.kinds.classify`), read once per file, kind and
    ``repair`` setting."""
    if spec.mesh_path is not None:
        key = (spec.mesh_path.resolve(), spec.repair, spec.kind)
        if key not in cache:
            cache[key] = _load_mesh_file(key[0], spec)
        classified, source = cache[key]
    else:
        assert spec.primitive is not None
        classified = classify(make_primitive(spec.primitive, field=spec.field),
                              name=spec.name or spec.field, kind=spec.kind)
        ((kind, value),) = spec.primitive.items()
        source = f"{kind} {value}"
    mesh = classified.mesh.copy()
    if not np.allclose(spec.scale, 1.0):
        mesh.apply_scale(spec.scale)  # positive factors: winding is kept
        source += f" scaled {spec.scale.tolist()}"
    if transform is not None:
        mesh.apply_transform(transform)
    return Part(name, mesh, source, classified.solid, classified.reason,
                checked=classified.solid, repairs=dict(classified.changes))


def _load_mesh_file(path: Path, spec: ObjectSpec) -> tuple[Classified, str]:
    """Read a mesh file and make it the part its ``kind`` asks for (with ``repair: true``,
    a solid that repair may fill holes of)."""
    from planner.meshes import load_mesh  # noqa: PLC0415

    field = join(spec.field, "mesh")
    label = spec.name or path.stem
    try:
        classified = classify(load_mesh(path, name=label), name=label, kind=spec.kind,
                              repair=spec.repair)
    except (ValueError, OSError) as error:  # InvalidMeshError is a ValueError
        hint = ""
        if not spec.repair and "repair_mesh" in str(error):
            hint = " (in a scenario: add 'repair: true' to this object, or kind: surface)"
        raise field_error(field, f"{error}{hint}") from None
    source = str(path)
    if classified.changes:
        source += f" ({classified.reason}: {classified.changes})"
    return classified, source


def assign_names(specs: Sequence[ObjectSpec]) -> list[str]:
    """Unique names: explicit ones must not repeat; a default is the mesh file's stem or
    the primitive's kind (``"robot"`` for a primitive robot), made unique with the
    object's index (``block_3``)."""
    taken: dict[str, str] = {}
    for spec in specs:
        if spec.name is not None:
            if spec.name in taken:
                raise field_error(join(spec.field, "name"),
                             f"name '{spec.name}' is already used by {taken[spec.name]}")
            taken[spec.name] = spec.field
    names = []
    for spec in specs:
        if spec.name is not None:
            names.append(spec.name)
            continue
        if spec.mesh_path is not None:
            base = spec.mesh_path.stem
        elif spec.field == "robot":
            base = "robot"
        else:
            base = next(iter(spec.primitive or {"obstacle": None}))
        index = spec.field.rsplit("[", 1)[-1].rstrip("]") if "[" in spec.field else ""
        candidate, counter = base, 1
        while candidate in taken:
            candidate = f"{base}_{index}" if counter == 1 and index else f"{base}_{counter}"
            counter += 1
        taken[candidate] = spec.field
        names.append(candidate)
    return names


def rotation4(rotation: np.ndarray) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, :3] = rotation
    return matrix
