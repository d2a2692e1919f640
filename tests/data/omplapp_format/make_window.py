"""Write ``window.cfg`` and its two COLLADA files: a problem in OMPL.app's file format,
authored here (OMPL.app's own problems may not be redistributed, see ../README.md).

It is laid out as OMPL.app's SketchUp exports are: ``Z_UP`` files whose triangles sit
under a node with a ``<matrix>``, the world a triangle soup (a double-sided floor quad
that is no solid, and a wall with a window made of closed boxes), and the ``.cfg``'s
numbers in OMPL.app's frame, ``app = (x, z, -y)`` of the file's coordinates. The robot,
a 10-unit cube, starts in front of the wall and must pass the 20 x 20 window to reach
the goal behind it. Run ``python tests/data/omplapp_format/make_window.py`` to rewrite
the files (deterministic).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

BOX_FACES = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                      [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])
"""Outward triangles of a box whose corners are numbered as :func:`box` returns them."""


def box(lo: tuple[float, float, float], hi: tuple[float, float, float]) -> np.ndarray:
    """The ``(8, 3)`` corners of an axis-aligned box: bottom ring, then top ring."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    return np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                     [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]], dtype=float)


def boxes(*extents) -> tuple[np.ndarray, np.ndarray]:
    """Closed boxes side by side as one vertex and face list."""
    vertices = [box(lo, hi) for lo, hi in extents]
    faces = [BOX_FACES + 8 * i for i in range(len(extents))]
    return np.vstack(vertices), np.vstack(faces)


def double_sided_quad(z: float, lo: float, hi: float) -> tuple[np.ndarray, np.ndarray]:
    """A horizontal square exported with both sides (each triangle twice, flipped)."""
    vertices = np.array([[lo, lo, z], [hi, lo, z], [hi, hi, z], [lo, hi, z]], dtype=float)
    up = np.array([[0, 1, 2], [0, 2, 3]])
    return vertices, np.vstack([up, up[:, ::-1]])


def geometry_xml(gid: str, vertices: np.ndarray, faces: np.ndarray) -> str:
    numbers = " ".join(f"{v:.6f}" for v in vertices.ravel())
    indices = " ".join(str(i) for i in faces.ravel())
    return f"""    <geometry id="{gid}">
      <mesh>
        <source id="{gid}-pos">
          <float_array id="{gid}-pos-array" count="{vertices.size}">{numbers}</float_array>
          <technique_common>
            <accessor source="#{gid}-pos-array" count="{len(vertices)}" stride="3">
              <param name="X" type="float"/><param name="Y" type="float"/>
              <param name="Z" type="float"/>
            </accessor>
          </technique_common>
        </source>
        <vertices id="{gid}-vtx"><input semantic="POSITION" source="#{gid}-pos"/></vertices>
        <triangles count="{len(faces)}">
          <input semantic="VERTEX" source="#{gid}-vtx" offset="0"/>
          <p>{indices}</p>
        </triangles>
      </mesh>
    </geometry>
"""


def collada(geometries: dict[str, tuple[np.ndarray, np.ndarray]], offset) -> str:
    """A ``Z_UP`` COLLADA 1.4.1 document: every geometry under one node translated by
    ``offset`` (its vertices are stored minus it, as SketchUp stores instances)."""
    library = "".join(geometry_xml(gid, v - np.asarray(offset, float), f)
                      for gid, (v, f) in geometries.items())
    instances = "".join(f'        <instance_geometry url="#{gid}"/>\n' for gid in geometries)
    ox, oy, oz = offset
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset>
    <contributor><authoring_tool>minkplan tests/data make_window.py</authoring_tool></contributor>
    <unit meter="1" name="meter"/>
    <up_axis>Z_UP</up_axis>
  </asset>
  <library_geometries>
{library}  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene">
      <node id="instance_0" name="instance_0">
        <matrix>1 0 0 {ox} 0 1 0 {oy} 0 0 1 {oz} 0 0 0 1</matrix>
{instances}      </node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
"""


def app(file_point) -> list[float]:
    """OMPL.app's coordinates of a point given in the Z-up file's frame."""
    x, y, z = file_point
    return [x, z, -y]


def cfg_text(start_file, goal_file, lo_file, hi_file) -> str:
    start, goal = app(start_file), app(goal_file)
    corners = np.array([app(lo_file), app(hi_file)])
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    lines = ["[problem]", "name = window", "robot = window_robot.dae",
             "world = window_env.dae"]
    for key, point in (("start", start), ("goal", goal)):
        lines += [f"{key}.{axis} = {value}" for axis, value in zip("xyz", point, strict=True)]
        lines += [f"{key}.theta = 0", f"{key}.axis.x = 1", f"{key}.axis.y = 0",
                  f"{key}.axis.z = 0"]
    lines += [f"volume.min.{axis} = {value}" for axis, value in zip("xyz", lo, strict=True)]
    lines += [f"volume.max.{axis} = {value}" for axis, value in zip("xyz", hi, strict=True)]
    lines += ["", "[benchmark]", "time_limit=20.0", "mem_limit=1000.0", "run_count=10", "",
              "[planner]", "rrtconnect=", ""]
    return "\n".join(lines)


def main() -> None:
    # the wall: y in [45, 55], x in [0, 100], z in [0, 60]; the window x, z in [40, 60]
    wall = boxes(((0, 45, 0), (40, 55, 60)), ((60, 45, 0), (100, 55, 60)),
                 ((40, 45, 0), (60, 55, 20)), ((40, 45, 40), (60, 55, 60)))
    floor = double_sided_quad(0.0, -20.0, 120.0)
    robot = boxes(((-5, -5, -5), (5, 5, 5)))
    (HERE / "window_env.dae").write_text(collada({"floor": floor, "wall": wall},
                                                 (50.0, 50.0, 0.0)))
    (HERE / "window_robot.dae").write_text(collada({"robot": robot}, (0.0, 0.0, 0.0)))
    (HERE / "window.cfg").write_text(cfg_text(start_file=(20, 20, 10), goal_file=(20, 80, 10),
                                              lo_file=(0, -10, 5.5), hi_file=(100, 110, 50)))


if __name__ == "__main__":
    main()
