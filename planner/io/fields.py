"""Reading YAML problem files: line numbers for every field, and checks of single fields
that raise :class:`~planner.errors.ScenarioError` naming the field.

Entry points: :func:`load_yaml` (text to data, recording each field's line in a
:class:`Document`), :meth:`Document.locate` (an error with ``"<file>:<line>: "`` in
front), :func:`check_mapping` (allowed and required keys, with did-you-mean), the field
checks :func:`real`, :func:`vector`, :func:`name_of`, :func:`parse_orientation`, and
:func:`settings_from_mapping` (the ``planner:`` block).

Each check raises ``ScenarioError(field=...)`` without file or line; the readers add
those (see :meth:`Document.locate`).
"""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import yaml
from trimesh import transformations as tf

from planner.errors import ScenarioError
from planner.problem import SETTING_CHECKS, PlannerSettings
from planner.tolerances import tol
from planner.values import describe_value

T = TypeVar("T")

__all__ = [
    "Document",
    "check_mapping",
    "field_error",
    "join",
    "load_yaml",
    "name_of",
    "parse_document",
    "parse_orientation",
    "read_text",
    "real",
    "rotation_angle_deg",
    "settings_from_mapping",
    "vector",
]


ORIENTATION_KEYS = ("quaternion", "rpy", "axis", "angle_deg")


def field_error(field: str, problem: str) -> ScenarioError:
    """``field`` ``""`` is the document itself (reported as "top level", field None)."""
    return ScenarioError(f"{field or 'top level'}: {problem}", field=field or None)


def join(field: str, key: Any) -> str:
    return f"{field}.{key}" if field else str(key)


def check_mapping(value: Any, field: str, allowed: Sequence[str],
             required: Sequence[str] = ()) -> dict[str, Any]:
    """Check that ``value`` is a mapping with only ``allowed`` keys and all ``required``."""
    if not isinstance(value, Mapping):
        what = f"a mapping with keys {', '.join(allowed)}"
        raise field_error(field, f"expected {what}, got {describe_value(value)}")
    for key in value:
        if not isinstance(key, str) or key not in allowed:
            close = difflib.get_close_matches(str(key), allowed, n=1, cutoff=0.6)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            raise field_error(join(field, key),
                         f"unknown key{hint} (allowed here: {', '.join(allowed)})")
    for key in required:
        if key not in value:
            raise field_error(join(field, key), "missing required field")
    return dict(value)


def real(value: Any, field: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise field_error(field, f"expected a number, got {describe_value(value)}")
    number = float(value)
    if not math.isfinite(number):
        raise field_error(field, f"expected a finite number, got {value!r}")
    return number


def vector(value: Any, field: str, size: int = 3, form: str = "[x, y, z]") -> np.ndarray:
    if not isinstance(value, (list, tuple)):
        raise field_error(field, f"expected a list of {size} numbers {form}, got "
                                 f"{describe_value(value)}")
    if len(value) != size:
        raise field_error(field, f"expected {size} numbers {form}, got {len(value)}")
    return np.array([real(v, f"{field}[{i}]") for i, v in enumerate(value)])


def name_of(value: Any, field: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise field_error(field, f"expected a non-empty string, got {describe_value(value)}")
    return value.strip()


def parse_orientation(value: Any, *, field: str = "orientation") -> np.ndarray:
    """An orientation spec as a ``(3, 3)`` rotation matrix.

    Accepted forms:

    - ``[w, x, y, z]`` or ``{quaternion: [w, x, y, z]}``: a unit quaternion, scalar first;
      normalised when its norm is within ``tol.quaternion_norm`` of 1.
    - ``{rpy: [r, p, y]}``: degrees about the fixed x, y, z axes, applied in that order:
      ``R = Rz(y) @ Ry(p) @ Rx(r)``.
    - ``{axis: [x, y, z], angle_deg: a}``: ``a`` degrees about ``axis`` (right-hand rule).
    - ``null``: the identity.

    Raises:
        ScenarioError: with ``field`` (and no file/line) for anything else.
    """
    if value is None:
        return np.eye(3)
    if isinstance(value, (list, tuple)):
        if len(value) == 3:
            raise field_error(field, "3 numbers are ambiguous: write a quaternion [w, x, y, z], "
                                "{rpy: [roll, pitch, yaw]} in degrees or "
                                "{axis: [x, y, z], angle_deg: a}")
        return _quaternion(value, field)
    if not isinstance(value, Mapping):
        raise field_error(field, "expected a quaternion [w, x, y, z], {rpy: [r, p, y]} or "
                            f"{{axis: [x, y, z], angle_deg: a}}, got {describe_value(value)}")
    spec = check_mapping(value, field, ORIENTATION_KEYS)
    if "angle_deg" in spec and "axis" not in spec:
        raise field_error(join(field, "axis"), "missing required field (angle_deg needs an axis)")
    forms = [k for k in ("quaternion", "rpy", "axis") if k in spec]
    if not forms:
        raise field_error(field, "empty orientation: give quaternion, rpy or axis + angle_deg")
    if len(forms) > 1:
        raise field_error(field, f"give only one of {', '.join(forms)}")
    if "quaternion" in spec:
        return _quaternion(spec["quaternion"], join(field, "quaternion"))
    if "rpy" in spec:
        roll, pitch, yaw = np.radians(vector(spec["rpy"], join(field, "rpy"),
                                              form="[roll, pitch, yaw] in degrees"))
        return tf.euler_matrix(roll, pitch, yaw, axes="sxyz")[:3, :3]
    axis = vector(spec["axis"], join(field, "axis"))
    if "angle_deg" not in spec:
        raise field_error(join(field, "angle_deg"), "missing required field (the angle about axis)")
    angle = real(spec["angle_deg"], join(field, "angle_deg"))
    norm = float(np.linalg.norm(axis))
    if norm == 0.0:
        raise field_error(join(field, "axis"), "axis must not be the zero vector")
    return tf.rotation_matrix(math.radians(angle), axis / norm)[:3, :3]


def _quaternion(value: Any, field: str) -> np.ndarray:
    q = vector(value, field, 4, "[w, x, y, z]")
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > tol.quaternion_norm:
        raise field_error(field, f"quaternion [w, x, y, z] must have unit length, its norm is "
                            f"{norm:.6g}")
    return tf.quaternion_matrix(q / norm)[:3, :3]


def rotation_angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    """Angle of the rotation taking orientation ``a`` to ``b``, in degrees."""
    cosine = (np.trace(a.T @ b) - 1.0) / 2.0
    return math.degrees(math.acos(min(1.0, max(-1.0, cosine))))


class _Loader(yaml.SafeLoader):
    """SafeLoader that also reads ``1e3`` as a float (as YAML 1.2 does), not a string."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."),
)


_FIELD_TAIL = re.compile(r"(?:\.[^.\[\]]+|\[\d+\])$")


class Document:
    """Where the scenario came from: its label (file name) and the line of every field."""

    def __init__(self, label: str, lines: dict[str, int] | None = None) -> None:
        self.label = label
        self.lines = lines or {}

    def line_of(self, field: str | None) -> int | None:
        """Line of ``field``, or of its nearest ancestor that has one."""
        while field:
            if field in self.lines:
                return self.lines[field]
            shorter = _FIELD_TAIL.sub("", field)
            if shorter == field:
                break
            field = shorter
        return None

    def locate(self, error: ScenarioError) -> ScenarioError:
        """The same error with ``"<file>:<line>: "`` in front and ``line`` set."""
        line = error.line if error.line is not None else self.line_of(error.field)
        where = self.label if line is None else f"{self.label}:{line}"
        return ScenarioError(f"{where}: {error}", field=error.field, line=line,
                             details=error.details)


def _record_lines(node: yaml.Node, field: str, lines: dict[str, int], document: Document,
                  stack: set[int]) -> None:
    """Record the 1-based line of every mapping key and list item below ``node``."""
    if id(node) in stack:  # a recursive alias: nothing new below
        return
    stack.add(id(node))
    if isinstance(node, yaml.MappingNode):
        seen: dict[str, int] = {}
        for key_node, value_node in node.value:
            if not isinstance(key_node, yaml.ScalarNode) or key_node.value == "<<":
                continue
            key = key_node.value
            child = join(field, key)
            line = key_node.start_mark.line + 1
            if key in seen:
                raise document.locate(ScenarioError(
                    f"{child}: duplicate key (first given on line {seen[key]})",
                    field=child, line=line))
            seen[key] = line
            lines[child] = line
            _record_lines(value_node, child, lines, document, stack)
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            child = f"{field}[{index}]"
            lines[child] = item.start_mark.line + 1
            _record_lines(item, child, lines, document, stack)
    stack.discard(id(node))


MAX_YAML_VALUES = 200_000
"""The most values a problem file may hold once its aliases are expanded: a real one has
hundreds; an alias bomb (a few lines that expand to billions) is refused."""


def _expanded_size(node: yaml.Node, sizes: dict[int, int], stack: set[int]) -> int:
    """How many values ``node`` holds with its aliases expanded (shared nodes counted
    each time they are used, computed once; a recursive alias counts once)."""
    if id(node) in sizes:
        return sizes[id(node)]
    if id(node) in stack:
        return 1
    stack.add(id(node))
    children: list[yaml.Node] = []
    if isinstance(node, yaml.MappingNode):
        children = [n for pair in node.value for n in pair]
    elif isinstance(node, yaml.SequenceNode):
        children = list(node.value)
    total = 1
    for child in children:
        total += _expanded_size(child, sizes, stack)
        if total > MAX_YAML_VALUES:
            break
    stack.discard(id(node))
    sizes[id(node)] = total
    return total


def load_yaml(text: str, document: Document) -> Any:
    try:
        loader = _Loader(text)  # reads the characters at once: control characters fail here
    except yaml.reader.ReaderError as error:
        row = text.count("\n", 0, error.position) + 1
        raise ScenarioError(f"{document.label}:{row}: a control character (code "
                            f"{error.character!r}) where YAML allows none", line=row) from None
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        if _expanded_size(node, {}, set()) > MAX_YAML_VALUES:
            raise ScenarioError(f"{document.label}: the file holds more than "
                                f"{MAX_YAML_VALUES:,} values once its aliases (*name) are "
                                f"expanded; a problem file needs far fewer")
        document.lines[""] = node.start_mark.line + 1
        _record_lines(node, "", document.lines, document, set())
        return loader.construct_document(node)
    except yaml.MarkedYAMLError as error:
        mark = error.problem_mark or error.context_mark
        if (mark is not None and error.context_mark is not None
                and mark.index >= len(text.rstrip())):
            mark = error.context_mark  # "end of file": point at what was left open
        line = None if mark is None else mark.line + 1
        column = "" if mark is None else f" (column {mark.column + 1})"
        problem = error.problem or error.context or "invalid YAML"
        if error.problem and error.context and error.context_mark is not None:
            column = (f"{column[:-1]}; {error.context} that started on line "
                      f"{error.context_mark.line + 1})")
        where = document.label if line is None else f"{document.label}:{line}"
        raise ScenarioError(f"{where}: YAML syntax error: {problem}{column}",
                            line=line) from None
    except yaml.YAMLError as error:
        raise ScenarioError(f"{document.label}: YAML error: {error}") from None
    finally:
        loader.dispose()



def read_text(path: Path, what: str) -> str:
    """The UTF-8 text of a problem file, or a one-line error naming it (``what``: "scenario",
    "assembly")."""
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ScenarioError(f"{path}: {what} file not found "
                            f"(looked in {path.parent.resolve()})") from None
    except (OSError, UnicodeDecodeError) as error:
        raise ScenarioError(f"{path}: cannot read the {what} file: {error}") from None


def parse_document(source: str | Mapping[str, Any], document: Document,
                   build: Callable[[Any], T]) -> T:
    """``build`` the problem from YAML text or a mapping; its errors get the document's
    file and line in front (:meth:`Document.locate`)."""
    data = load_yaml(source, document) if isinstance(source, str) else source
    try:
        return build(data)
    except ScenarioError as error:
        raise document.locate(error) from None


def settings_from_mapping(mapping: Mapping[str, Any] | None, *,
                          field: str = "planner") -> PlannerSettings:
    """Settings from a mapping such as the YAML ``planner:`` block.

    Missing keys and ``null`` values take the defaults.

    Raises:
        ScenarioError: an unknown key (with a suggestion) or a bad value; ``field`` is
            ``"<field>.<key>"``; no file or line (the readers add them).
    """
    if mapping is None:
        return PlannerSettings()
    values = check_mapping(mapping, field, PlannerSettings.keys())
    kwargs: dict[str, Any] = {}
    for name, value in values.items():
        if value is None:
            continue
        try:
            kwargs[name] = SETTING_CHECKS[name](value)
        except ValueError as error:
            raise field_error(f"{field}.{name}", str(error)) from None
    return PlannerSettings(**kwargs)
