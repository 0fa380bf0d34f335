"""The arm in 3-D in the browser, on viser: its URDF meshes or capsules along its links, joint sliders, the tool
frame, a run's playback, and overlays that only the dynamics can draw.

``Viewer(arm)`` (``arm.view()``, ``result.view()``, ``armdyn view ARM``) starts a viser server on 127.0.0.1 and
draws the arm in it; nothing needs a window or a GPU on this side (the browser renders). A URDF arm is drawn with
the ``<visual>`` geometry of its file (meshes resolved from ``package://``, ``file://`` and relative paths and
loaded with trimesh; boxes, cylinders and spheres), each URDF link on the arm link whose body carries it, as
``armdyn.load_urdf`` merges fixed joints. An arm read by ``armdyn.load_mjcf`` is drawn with its model's geoms
(``armdyn.model.sources.geometry_of``: the visual geoms when the model has any; meshes as MuJoCo compiled them,
spheres, capsules, ellipsoids, cylinders and boxes). DH arms, and links whose meshes cannot be loaded (with a
warning naming the file), are drawn as capsules from each joint to the next in ``LINK_COLOR``.

The overlays (``OVERLAYS``, each a checkbox of the viewer's panel):

- ``"inertia"``: every link's equivalent inertia ellipsoid, the uniform solid ellipsoid of the link's mass and
  principal central moments, its axes along the principal axes (``equivalent_ellipsoid``);
- ``"lambda"``: the tool's task-space inertia ellipsoid, from the translational Lambda = (J_v M^-1 J_v^T)^-1
  (Lewis, Dawson and Abdallah 2004, Section 3.5; Khatib 1987), axes its eigenvectors and radii
  ``LAMBDA_SCALE * lambda_i / max(lambda)``: the longest axis points where the arm feels heaviest at the tool;
- ``"manipulability"``: the ellipsoid of J_v J_v^T (Yoshikawa 1985), axes its eigenvectors and radii
  ``MANIPULABILITY_SCALE * sqrt(sigma_i^2)``, the tool speeds that unit joint speeds reach;
- ``"com"``: the whole arm's centre of mass, a sphere;
- ``"gravity"``: the gravity torque G_i(q) of every joint (3.3.1), an arrow along the joint's axis of length
  ``GRAVITY_SCALE * G_i / max|G|`` (its sign the direction) with its value as a label.

``Viewer.save_html(path)`` writes one self-contained page (viser's client with the scene recorded inline) that
replays the scene, and a run, offline.
"""

from __future__ import annotations

import contextlib
import io
import os
import socket
import threading
import time
import warnings
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from armdyn import inputs
from armdyn.errors import MissingDependencyError, ModelError

if TYPE_CHECKING:
    from armdyn.robot import Robot
    from armdyn.simulation import Result

__all__ = [
    "FRAME_RATE",
    "GRAVITY_SCALE",
    "LAMBDA_MAX_CONDITION",
    "LAMBDA_SCALE",
    "LINK_COLOR",
    "MANIPULABILITY_SCALE",
    "OVERLAYS",
    "TORQUE_COLOR",
    "Viewer",
    "equivalent_ellipsoid",
    "lambda_ellipsoid",
    "manipulability_ellipsoid",
    "resolve_mesh",
    "scene_data",
    "urdf_of",
]

LINK_COLOR = (40, 170, 80)
"""The colour of every link (RGB, 0-255): capsules, meshes and primitives alike."""
TORQUE_COLOR = (220, 40, 40)
"""A link's colour in playback when its joint's torque reaches the limit (|tau| / limit = 1); LINK_COLOR at 0."""
OVERLAYS = ("inertia", "lambda", "manipulability", "com", "gravity")
"""The overlays a Viewer can show, each a checkbox of its panel."""
LAMBDA_SCALE = 0.15
"""The radius (m) of the Lambda ellipsoid's longest axis: radius_i = LAMBDA_SCALE * lambda_i / max(lambda)."""
LAMBDA_MAX_CONDITION = 1e12
"""Above this condition number of J_v M^-1 J_v^T, Lambda is taken as not finite (its ellipsoid is hidden)."""
MANIPULABILITY_SCALE = 0.2
"""Metres per (m/s per rad/s) of the manipulability ellipsoid: radius_i = MANIPULABILITY_SCALE * sigma_i."""
GRAVITY_SCALE = 0.15
"""The length (m) of the gravity-torque arrow of the joint with the largest |G_i|."""
FRAME_RATE = 30.0
"""Frames per second of a run's playback and of a saved page's recording."""

_OVERLAY_COLORS = {
    "inertia": (255, 165, 0),
    "lambda": (130, 60, 200),
    "manipulability": (0, 170, 200),
    "com": (30, 30, 30),
    "gravity": (40, 90, 220),
}
_MESH_SUFFIXES = (".dae", ".stl", ".obj", ".ply", ".off", ".glb", ".gltf")


# ----- what the overlays are: numbers, no drawing -------------------------------------------------------------------
def equivalent_ellipsoid(mass: float, inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The uniform solid ellipsoid with a body's mass and central principal moments.

    A solid ellipsoid of mass m and semi-axes a_1, a_2, a_3 has principal moments I_1 = m (a_2^2 + a_3^2) / 5 and
    its permutations, so a_i^2 = 5 (I_j + I_k - I_i) / (2 m). A moment that breaks the triangle inequality
    (a CAD export's, loaded with strict=False) gives a zero semi-axis.

    Parameters
    ----------
    mass : float
        The body's mass, kg, > 0.
    inertia : numpy.ndarray
        Its inertia tensor about its centre of mass, (3, 3), kg m^2.

    Returns
    -------
    axes : numpy.ndarray
        (3, 3): the principal axes as columns, a rotation (determinant +1).
    radii : numpy.ndarray
        (3,): the semi-axis along each column, m.

    Raises
    ------
    armdyn.ModelError
        When the mass is not positive.
    """
    if not mass > 0:
        raise ModelError(f"an equivalent ellipsoid needs a positive mass, got {mass}")
    moments, axes = np.linalg.eigh(0.5 * (inertia + inertia.T))
    squares = 5.0 * (moments.sum() - 2.0 * moments) / (2.0 * mass)
    return _rotation(axes), np.sqrt(np.maximum(squares, 0.0))


def lambda_ellipsoid(arm: Robot, q: np.ndarray) -> dict[str, np.ndarray]:
    """The tool's task-space inertia ellipsoid: Lambda of the tool position (Section 3.5), drawn at the tool.

    Lambda = (J_v M^-1 J_v^T)^-1 (Khatib 1987, eq. 12; ``armdyn.task_space.operational_inertia`` of
    ``ToolPosition`` without damping), the 3x3 translational inertia felt at the tool. Axes: its eigenvectors; radii:
    ``LAMBDA_SCALE * lambda_i / max(lambda)``, so the longest axis is the direction in which the arm feels
    heaviest.

    Parameters
    ----------
    arm : Robot
        The arm.
    q : numpy.ndarray
        Joint positions, (n,).

    Returns
    -------
    dict
        "axes" (3, 3) eigenvectors as columns (a rotation), "radii" (3,) m, "centre" (3,) the tool's position,
        "eigenvalues" (3,) kg, "matrix" Lambda (3, 3).

    Raises
    ------
    armdyn.ModelError
        When J_v M^-1 J_v^T is singular (condition number above LAMBDA_MAX_CONDITION): a planar arm, or a
        singular configuration.
    """
    M, Jv = arm.inertia_matrix(q), arm.jacobian(q)[:3]
    inverse = Jv @ np.linalg.solve(M, Jv.T)  # Lambda^-1 = J_v M^-1 J_v^T, the tool's mobility
    inverse = 0.5 * (inverse + inverse.T)
    if np.linalg.cond(inverse) > LAMBDA_MAX_CONDITION:
        raise ModelError(
            f"{arm.name}: J_v M^-1 J_v^T is singular at q = {np.asarray(q)} (condition number above "
            f"{LAMBDA_MAX_CONDITION:.0e}): the tool cannot move in some direction, Lambda is not finite there"
        )
    Lambda = np.linalg.inv(inverse)
    Lambda = 0.5 * (Lambda + Lambda.T)
    eigenvalues, axes = np.linalg.eigh(Lambda)
    return {
        "axes": _rotation(axes),
        "radii": LAMBDA_SCALE * eigenvalues / eigenvalues.max(),
        "centre": arm.tool_pose(q)[:3, 3],
        "eigenvalues": eigenvalues,
        "matrix": Lambda,
    }


def manipulability_ellipsoid(arm: Robot, q: np.ndarray) -> dict[str, np.ndarray]:
    """The tool's manipulability ellipsoid: J_v J_v^T (Yoshikawa 1985), drawn at the tool.

    The tool velocities v = J_v qd of the joint velocities with |qd| = 1 fill the ellipsoid whose axes are the
    eigenvectors of J_v J_v^T and semi-axes the square roots of its eigenvalues (J_v's singular values); drawn
    with radii ``MANIPULABILITY_SCALE * sqrt(eigenvalue)``.

    Parameters
    ----------
    arm : Robot
        The arm.
    q : numpy.ndarray
        Joint positions, (n,).

    Returns
    -------
    dict
        "axes" (3, 3) eigenvectors as columns (a rotation), "radii" (3,) m, "centre" (3,) the tool's position,
        "eigenvalues" (3,), "matrix" J_v J_v^T (3, 3).
    """
    Jv = arm.jacobian(q)[:3]
    matrix = Jv @ Jv.T
    eigenvalues, axes = np.linalg.eigh(matrix)
    return {
        "axes": _rotation(axes),
        "radii": MANIPULABILITY_SCALE * np.sqrt(np.maximum(eigenvalues, 0.0)),
        "centre": arm.tool_pose(q)[:3, 3],
        "eigenvalues": eigenvalues,
        "matrix": matrix,
    }


def _inertia_ellipsoids(arm: Robot, transforms: np.ndarray) -> list[dict[str, Any]]:
    """Every massive link's equivalent ellipsoid in the world at the link poses ``transforms`` (n, 4, 4)."""
    ellipsoids = []
    for i, link in enumerate(arm.links):
        body = link.inertial
        if not body.mass > 0:
            continue
        axes, radii = equivalent_ellipsoid(float(body.mass), np.asarray(body.inertia, dtype=float))
        R, p = transforms[i, :3, :3], transforms[i, :3, 3]
        ellipsoids.append({
            "link": link.name,
            "axes": R @ axes,
            "radii": radii,
            "centre": p + R @ np.asarray(body.com, dtype=float),
            "local_axes": axes,
            "local_centre": np.asarray(body.com, dtype=float),
            "mass": float(body.mass),
        })  # fmt: skip
    return ellipsoids


def _centre_of_mass(arm: Robot, transforms: np.ndarray) -> np.ndarray:
    """The whole arm's centre of mass in the world: sum m_i c_i / sum m_i (the base if no link has mass)."""
    masses = np.array([float(link.inertial.mass) for link in arm.links])
    if masses.sum() <= 0:
        return np.asarray(arm.base, dtype=float)[:3, 3].copy()
    coms = np.array([np.asarray(link.inertial.com, dtype=float) for link in arm.links])
    world = np.einsum("nij,nj->ni", transforms[:, :3, :3], coms) + transforms[:, :3, 3]
    return masses @ world / masses.sum()


def scene_data(arm: Robot, q: np.ndarray) -> dict[str, Any]:
    """The overlays' numbers at one configuration (no drawing): what a Viewer draws, for tests and reports.

    Parameters
    ----------
    arm : Robot
        The arm.
    q : numpy.ndarray
        Joint positions, (n,).

    Returns
    -------
    dict
        "q"; "lambda" and "manipulability" as ``lambda_ellipsoid`` and ``manipulability_ellipsoid`` give them
        ("lambda" None where J_v is singular); "inertia" a list of {"link", "axes", "radii", "centre", "mass"} in
        the world, one per link with mass; "com" (3,); "gravity" G(q) (n,); "tool" the tool pose (4, 4);
        "transforms" the link poses (n, 4, 4).

    Raises
    ------
    armdyn.ModelError
        When q is not n finite numbers.
    """
    transforms = arm.link_transforms(q)
    q = np.asarray(q, dtype=float)
    try:
        lam: dict[str, np.ndarray] | None = lambda_ellipsoid(arm, q)
    except (ModelError, np.linalg.LinAlgError):
        lam = None  # a singular J_v (or M, of an arm loaded with strict=False): no finite Lambda
    return {
        "q": q,
        "lambda": lam,
        "manipulability": manipulability_ellipsoid(arm, q),
        "inertia": _inertia_ellipsoids(arm, transforms),
        "com": _centre_of_mass(arm, transforms),
        "gravity": np.asarray(arm.gravity_vector(q), dtype=float),
        "tool": arm.tool_pose(q),
        "transforms": transforms,
    }


def _rotation(axes: np.ndarray) -> np.ndarray:
    """Orthonormal columns as a proper rotation: the last column flipped when the determinant is -1."""
    axes = np.array(axes, dtype=float)
    if np.linalg.det(axes) < 0:
        axes[:, 2] = -axes[:, 2]
    return axes


# ----- what a link looks like: the URDF's <visual> elements, or capsules ---------------------------------------------
@dataclass
class _Shape:
    """One piece of a link's drawing, in the arm link's frame."""

    kind: str  # "mesh", "box", "cylinder", "sphere" or "capsule"
    pose: np.ndarray  # 4x4 in the arm link's frame (the base's for link -1)
    vertices: np.ndarray  # (V, 3) float32, in the shape's own frame
    faces: np.ndarray  # (F, 3) uint32
    file: str | None = None


@dataclass
class _LinkDrawing:
    name: str
    kind: str = "capsule"
    shapes: list[_Shape] = field(default_factory=list)
    files: list[str] = field(default_factory=list)


def _trimesh() -> Any:
    try:
        import trimesh
    except ImportError:
        raise MissingDependencyError("trimesh", "view", needed_by="armdyn.viewer") from None
    return trimesh


def _viser() -> Any:
    try:
        import viser
    except ImportError:
        raise MissingDependencyError("viser", "view", needed_by="armdyn.viewer") from None
    return viser


def _rpy(rpy: np.ndarray) -> np.ndarray:
    """The URDF's fixed-axis roll, pitch, yaw as a rotation: Rz(yaw) Ry(pitch) Rx(roll)."""
    (cr, cp, cy), (sr, sp, sy) = np.cos(rpy), np.sin(rpy)
    return np.array([
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ])  # fmt: skip


def _numbers(text: str | None, count: int, default: Sequence[float], where: str) -> np.ndarray:
    if text is None:
        return np.array(default, dtype=float)
    try:
        values = np.array([float(word) for word in text.split()])
    except ValueError:
        raise ModelError(f"{where}: '{text}' is not {count} numbers") from None
    if values.shape != (count,) or not np.all(np.isfinite(values)):
        raise ModelError(f"{where}: '{text}' is not {count} finite numbers")
    return values


def _origin(element: Any, where: str) -> np.ndarray:
    """The 4x4 pose of an element's <origin> (identity when absent)."""
    pose = np.eye(4)
    origin = element.find("origin")
    if origin is not None:
        pose[:3, :3] = _rpy(_numbers(origin.get("rpy"), 3, (0, 0, 0), f"{where} <origin> rpy"))
        pose[:3, 3] = _numbers(origin.get("xyz"), 3, (0, 0, 0), f"{where} <origin> xyz")
    return pose


def resolve_mesh(filename: str, urdf: str | os.PathLike[str]) -> Path | None:
    """The file a URDF's ``<mesh filename>`` names, or None when it cannot be found.

    ``package://NAME/REST`` is looked up in the URDF's folder and each folder above it: a folder named NAME, or a
    folder holding one named NAME (a ROS workspace, example-robot-data's ``robots`` folder), then in the folders of
    ``ROS_PACKAGE_PATH``; ``file://PATH`` is PATH; any other name is relative to the URDF's folder.

    Parameters
    ----------
    filename : str
        The ``filename`` attribute.
    urdf : str or os.PathLike
        The URDF file.

    Returns
    -------
    pathlib.Path or None
        The mesh file.
    """
    folder = Path(urdf).resolve().parent
    if filename.startswith("package://"):
        package, _, rest = filename[len("package://") :].partition("/")
        roots = [folder, *folder.parents]
        roots += [Path(entry) for entry in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if entry]
        for root in roots:
            for candidate in (root / rest if root.name == package else None, root / package / rest):
                if candidate is not None and candidate.is_file():
                    return candidate
        return None
    path = Path(filename[len("file://") :]) if filename.startswith("file://") else Path(filename)
    path = path if path.is_absolute() else folder / path
    return path if path.is_file() else None


def _urdf_frames(root: Any, arm: Robot, where: str) -> tuple[dict[str, tuple[int, np.ndarray]], list[str]]:
    """Where each URDF link's frame is: (index of the arm link whose body carries it, -1 for the base; its pose in
    that link's frame), walking the tree as ``armdyn.load_urdf`` does (fixed joints merged into their parent)."""
    joints = root.findall("joint")
    children: dict[str, list[Any]] = {}
    childless = {link.get("name") for link in root.findall("link")}
    for joint in joints:
        parent, child = joint.find("parent"), joint.find("child")
        if parent is None or child is None:
            continue
        children.setdefault(parent.get("link"), []).append(joint)
        childless.discard(child.get("link"))
    notes: list[str] = []
    if len(childless) != 1:
        raise ModelError(f"{where}: expected one root link, found {sorted(n for n in childless if n) or 'none'}")
    base = childless.pop()
    index = {name: i for i, name in enumerate(arm.joint_names)}
    frames: dict[str, tuple[int, np.ndarray]] = {base: (-1, np.eye(4))}
    stack = [(joint, -1, np.eye(4)) for joint in reversed(children.get(base, []))]
    while stack:
        joint, parent, prefix = stack.pop()
        child = joint.find("child").get("link")
        placement = prefix @ _origin(joint, f"{where}: joint '{joint.get('name')}'")
        if joint.get("type") in ("revolute", "continuous", "prismatic") and joint.get("name") in index:
            parent, placement = index[joint.get("name")], np.eye(4)
        elif joint.get("type") != "fixed":
            notes.append(f"{where}: joint '{joint.get('name')}' is not a joint of the arm; drawn fixed at 0")
        frames[child] = (parent, placement)
        stack.extend((grandchild, parent, placement) for grandchild in reversed(children.get(child, [])))
    return frames, notes


def _read_visuals(arm: Robot, urdf: Path) -> tuple[dict[int, list[_Shape]], dict[int, list[str]], list[str]]:
    """The URDF's <visual> shapes by arm link (-1 the base), the files that failed per link, and warnings."""
    from lxml import etree

    trimesh = _trimesh()
    try:
        root = etree.parse(str(urdf)).getroot()
    except (OSError, etree.XMLSyntaxError) as error:
        raise ModelError(f"{urdf}: cannot be read as URDF XML ({error})") from None
    frames, notes = _urdf_frames(root, arm, urdf.name)
    shapes: dict[int, list[_Shape]] = {}
    failed: dict[int, list[str]] = {}
    cache: dict[tuple[Path, tuple[float, ...]], tuple[np.ndarray, np.ndarray]] = {}
    for link in root.findall("link"):
        name = link.get("name")
        if name not in frames:
            continue
        owner, frame = frames[name]
        for number, visual in enumerate(link.findall("visual")):
            where = f"{urdf.name}: link '{name}' <visual> {number}"
            geometry = visual.find("geometry")
            elements = [] if geometry is None else [child for child in geometry if isinstance(child.tag, str)]
            element = elements[0] if elements else None  # comments skipped
            if element is None:
                continue
            pose = frame @ _origin(visual, where)
            kind = etree.QName(element).localname
            if kind == "mesh":
                filename = element.get("filename") or ""
                scale = tuple(_numbers(element.get("scale"), 3, (1, 1, 1), f"{where} <mesh> scale"))
                path = resolve_mesh(filename, urdf)
                if path is None:
                    notes.append(f"{where}: mesh file '{filename}' not found; link drawn as a capsule")
                    failed.setdefault(owner, []).append(filename)
                    continue
                key = (path, scale)
                if key not in cache:
                    try:
                        mesh = _load_mesh(trimesh, path)
                        cache[key] = (
                            (np.asarray(mesh.vertices) * np.array(scale)).astype(np.float32),
                            np.asarray(mesh.faces, dtype=np.uint32),
                        )
                    except Exception as error:  # any loader failure is the file's: warn, draw a capsule
                        notes.append(f"{where}: mesh file '{path}' cannot be loaded ({error}); link drawn as a capsule")
                        failed.setdefault(owner, []).append(str(path))
                        continue
                vertices, faces = cache[key]
                if len(faces) == 0:
                    notes.append(
                        f"{where}: mesh file '{path}' cannot be loaded (it holds no triangles); link drawn as a capsule"
                    )
                    failed.setdefault(owner, []).append(str(path))
                    continue
                shapes.setdefault(owner, []).append(_Shape("mesh", pose, vertices, faces, str(path)))
                continue
            if kind == "box":
                primitive = trimesh.creation.box(extents=_numbers(element.get("size"), 3, (0, 0, 0), where + " size"))
            elif kind == "cylinder":
                radius = float(_numbers(element.get("radius"), 1, (0,), where + " radius")[0])
                length = float(_numbers(element.get("length"), 1, (0,), where + " length")[0])
                primitive = trimesh.creation.cylinder(radius=radius, height=length, sections=24)
            elif kind == "sphere":
                radius = float(_numbers(element.get("radius"), 1, (0,), where + " radius")[0])
                primitive = trimesh.creation.icosphere(subdivisions=2, radius=radius)
            else:
                notes.append(f"{where}: geometry <{kind}> is not drawn")
                continue
            shapes.setdefault(owner, []).append(
                _Shape(kind, pose, primitive.vertices.astype(np.float32), primitive.faces.astype(np.uint32))
            )
    return shapes, failed, notes


def _mjcf_shapes(arm: Robot) -> dict[int, list[_Shape]]:
    """The geoms of the MuJoCo model ``armdyn.load_mjcf`` read the arm from, by arm link (-1 the base): meshes as
    MuJoCo compiled them, the primitives from their MuJoCo sizes (empty for an arm made otherwise)."""
    from armdyn.model.sources import geometry_of

    shapes: dict[int, list[_Shape]] = {}
    for geom in geometry_of(arm):
        if geom.kind == "mesh":
            assert geom.vertices is not None and geom.faces is not None
            vertices, faces = geom.vertices, geom.faces
        else:
            mesh = _primitive(geom.kind, geom.size)
            vertices, faces = mesh.vertices.astype(np.float32), mesh.faces.astype(np.uint32)
        shapes.setdefault(geom.link, []).append(_Shape(geom.kind, geom.pose, vertices, faces))
    return shapes


def _primitive(kind: str, size: np.ndarray) -> Any:
    """A MuJoCo primitive geom as a triangle mesh in its own frame (its long axis along z, as MuJoCo's)."""
    trimesh = _trimesh()
    if kind == "sphere":
        return trimesh.creation.icosphere(subdivisions=2, radius=float(size[0]))
    if kind == "capsule":
        return trimesh.creation.capsule(height=2 * float(size[1]), radius=float(size[0]), count=[16, 8])
    if kind == "cylinder":
        return trimesh.creation.cylinder(radius=float(size[0]), height=2 * float(size[1]), sections=24)
    if kind == "box":
        return trimesh.creation.box(extents=2 * np.asarray(size[:3], dtype=float))
    mesh = trimesh.creation.icosphere(subdivisions=2, radius=1.0)  # an ellipsoid: the unit sphere scaled
    mesh.apply_scale(np.asarray(size[:3], dtype=float))
    return mesh


def _load_mesh(trimesh: Any, path: Path) -> Any:
    """One mesh file as one trimesh.Trimesh, vertices merged. A COLLADA file whose materials break (a texture it
    names is missing: pycollada then drops the geometry's instance) is read again without its material bindings,
    which the viewer does not use."""
    mesh = trimesh.load(str(path), force="mesh")
    if len(mesh.faces) == 0 and path.suffix.lower() == ".dae":
        from lxml import etree

        tree = etree.parse(str(path))
        for binding in list(tree.getroot().iter("{*}bind_material")):
            binding.getparent().remove(binding)
        mesh = trimesh.load(io.BytesIO(etree.tostring(tree)), file_type="dae", force="mesh")
    mesh.merge_vertices()
    return mesh


def _segments(arm: Robot) -> dict[int, list[tuple[np.ndarray, np.ndarray]]]:
    """Each link's capsule segments in its own frame: from its joint's origin to each child's joint origin and to
    the tool (the base, -1: from the world origin of the base to the first joints)."""
    segments: dict[int, list[tuple[np.ndarray, np.ndarray]]] = {}
    for i, link in enumerate(arm.links):
        start = np.linalg.inv(np.asarray(link.joint.frame_offset, dtype=float))[:3, 3]
        ends = [np.asarray(c.joint.placement, dtype=float)[:3, 3] for c in arm.links if c.parent == i]
        if arm.tool_link == i:
            ends.append(np.asarray(arm.tool, dtype=float)[:3, 3])
        segments[i] = [(start, end) for end in ends] or [(start, start)]
        end = np.asarray(link.joint.placement, dtype=float)[:3, 3]
        if link.parent < 0 and np.linalg.norm(end) > 1e-9:
            segments.setdefault(-1, []).append((np.zeros(3), end))
    return segments


def _capsule(start: np.ndarray, end: np.ndarray, radius: float) -> _Shape:
    """A capsule of ``radius`` from ``start`` to ``end`` (a sphere when they coincide), in their frame."""
    trimesh = _trimesh()
    axis = end - start
    length = float(np.linalg.norm(axis))
    mesh = trimesh.creation.capsule(height=length, radius=radius, count=[16, 8])
    pose = np.eye(4)
    pose[:3, 3] = 0.5 * (start + end)
    if length > 0:
        pose[:3, :3] = _z_to(axis / length)
    return _Shape("capsule", pose, mesh.vertices.astype(np.float32), mesh.faces.astype(np.uint32))


def _z_to(direction: np.ndarray) -> np.ndarray:
    """A rotation taking z to the unit vector ``direction``."""
    z = direction
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def _drawings(arm: Robot, urdf: Path | None) -> tuple[dict[int, _LinkDrawing], list[str]]:
    """What each arm link (and the base, -1) is drawn with, and the warnings of the meshes that failed."""
    segments = _segments(arm)
    lengths = [float(np.linalg.norm(b - a)) for pieces in segments.values() for a, b in pieces]
    radius = float(np.clip(0.03 * sum(lengths), 0.008, 0.05))
    shapes: dict[int, list[_Shape]] = {}
    failed: dict[int, list[str]] = {}
    notes: list[str] = []
    if urdf is not None:
        shapes, failed, notes = _read_visuals(arm, urdf)
    else:
        shapes = _mjcf_shapes(arm)
    described = urdf is not None or bool(shapes)  # a file says how the links look: the base drawn only by it
    drawings = {-1: _LinkDrawing("base", "none")}
    for i, link in enumerate(arm.links):
        drawings[i] = _LinkDrawing(link.name)
    for index, drawing in drawings.items():
        own = shapes.get(index, [])
        drawing.shapes = list(own)
        drawing.files = [shape.file for shape in own if shape.file is not None]
        if own:
            drawing.kind = "mesh" if drawing.files else own[0].kind
        wanted = index in failed or (not own and (index >= 0 or not described))
        if wanted and segments.get(index):
            drawing.shapes += [_capsule(a, b, radius) for a, b in segments[index]]
            drawing.kind = drawing.kind if own else "capsule"
    return drawings, notes


# ----- the viewer -----------------------------------------------------------------------------------------------------
def urdf_of(arm: Robot) -> Path | None:
    """The URDF file ``armdyn.load_urdf`` read ``arm`` from, or None for an arm made otherwise.

    Parameters
    ----------
    arm : Robot
        The arm.

    Returns
    -------
    pathlib.Path or None
        The file.
    """
    from armdyn.model.sources import source_file

    return source_file(arm)


def _wxyz(rotation: np.ndarray) -> np.ndarray:
    """A rotation as viser's unit quaternion (w, x, y, z) (armdyn.kinematics.quaternion)."""
    from armdyn.kinematics import quaternion

    return np.array(quaternion(rotation))


def _blend(ratio: float) -> tuple[int, int, int]:
    """LINK_COLOR at 0, TORQUE_COLOR at 1 (and beyond)."""
    r = float(np.clip(ratio, 0.0, 1.0))
    low, high = np.array(LINK_COLOR, dtype=float), np.array(TORQUE_COLOR, dtype=float)
    red, green, blue = np.rint(low + r * (high - low)).astype(int)
    return int(red), int(green), int(blue)


class Viewer:
    """The arm in the browser, on a viser server: links, joint sliders, tool frame, overlays and a run's playback.

    Parameters
    ----------
    arm : Robot
        The arm to draw.
    host : str, optional
        The address the server binds (default "127.0.0.1": this machine only).
    port : int, optional
        Its port (default 0: a free port the system picks).
    overlays : iterable of str, optional
        The overlays shown at the start (names of ``OVERLAYS``); every one is a checkbox of the panel.
    q : array_like or str, optional
        The configuration drawn first, or the name of one of the arm's (default its "qn", else "qz", else zeros).
    urdf : str or os.PathLike, optional
        The URDF whose ``<visual>`` elements draw the links (default the file ``load_urdf`` read the arm from;
        none for other arms: capsules).
    result : armdyn.simulation.Result, optional
        A run to play back: a time slider and play/pause, the desired tool path (along q_d) and the tool's trace
        (along q) as lines, each link coloured by its joint's |tau| relative to ``torque_limits`` (LINK_COLOR at 0,
        TORQUE_COLOR at the limit), and for runs with drives their inputs in the panel.
    torque_limits : array_like, optional
        The torque limits of the colours, one per joint or one for all (default the run's largest |tau| per joint).

    Attributes
    ----------
    url : str
        The page to open, "http://127.0.0.1:PORT".
    warnings : list of str
        The meshes that could not be found or loaded (each such link is drawn as capsules).

    Raises
    ------
    armdyn.MissingDependencyError
        When viser or trimesh is not installed (the extra ``view``).
    armdyn.ModelError
        When an overlay is unknown, q is not a configuration of the arm, or the URDF cannot be read.

    Warns
    -----
    UserWarning
        For each mesh that could not be found or loaded.
    """

    def __init__(
        self,
        arm: Robot,
        *,
        host: str = "127.0.0.1",
        port: int = 0,
        overlays: Iterable[str] = (),
        q: Any = None,
        urdf: str | os.PathLike[str] | None = None,
        result: Result | None = None,
        torque_limits: Any = None,
    ) -> None:
        viser = _viser()
        _trimesh()
        chosen = tuple(overlays) if not isinstance(overlays, str) else (overlays,)
        for name in chosen:
            if name not in OVERLAYS:
                raise ModelError(f"overlay '{name}' is not one of {', '.join(OVERLAYS)}")
        self.arm = arm
        self.result = result
        self._q = self._start(q)
        path = Path(urdf) if urdf is not None else urdf_of(arm)
        self._drawings, self.warnings = _drawings(arm, path)
        for note in self.warnings:
            warnings.warn(note, stacklevel=2)
        self._limits = self._torque_limits(torque_limits)
        _check_address(host, port)
        with contextlib.redirect_stdout(io.StringIO()):  # viser prints its address; ``url`` gives it
            self._server = viser.ViserServer(host=host, port=port, verbose=False)
        self._lock = threading.RLock()
        self._stop = threading.Event()
        self._player: threading.Thread | None = None
        try:
            self._build(chosen)
            self.set_configuration(self._q)
        except BaseException:
            self.close()
            raise

    # ----- what the page shows --------------------------------------------------------------------------------------
    @property
    def url(self) -> str:
        """The page to open in a browser: "http://HOST:PORT"."""
        return f"http://{self._server.get_host()}:{self._server.get_port()}"

    @property
    def q(self) -> np.ndarray:
        """The configuration drawn, (n,)."""
        return self._q.copy()

    def _start(self, q: Any) -> np.ndarray:
        arm = self.arm
        if self.result is not None and q is None:
            return np.asarray(self.result.q[0], dtype=float)
        if isinstance(q, str):
            return arm.configuration(q)
        if q is None:
            for name in ("qn", "qz"):
                if name in arm.configurations:
                    return arm.configuration(name)
            return np.zeros(arm.n)
        return self._checked(q)

    def _checked(self, q: Any) -> np.ndarray:
        """q as one finite real state of the arm (armdyn.inputs.state's checks), or a ModelError naming it."""
        values = inputs.state(q, self.arm.n, "q", f" for '{self.arm.name}'")
        if values.shape != (self.arm.n,):
            raise ModelError(f"q must be one state of {self.arm.n} values for '{self.arm.name}', got {values.shape}")
        return np.array(values, dtype=float)

    def _torque_limits(self, limits: Any) -> np.ndarray:
        n = self.arm.n
        if limits is not None:
            values = np.broadcast_to(np.asarray(limits, dtype=float), (n,)).copy()
            if not np.all(values > 0):
                raise ModelError(f"torque_limits must be positive, got {values}")
            return values
        if self.result is None:
            return np.ones(n)
        largest = np.max(np.abs(np.asarray(self.result.tau, dtype=float)), axis=0)
        return np.where(largest > 0, largest, 1.0)

    def _build(self, overlays: tuple[str, ...]) -> None:
        arm, scene, gui = self.arm, self._server.scene, self._server.gui
        scene.set_up_direction("+z")
        reach = max(sum(float(np.linalg.norm(b - a)) for pieces in _segments(arm).values() for a, b in pieces), 0.3)
        base = np.asarray(arm.base, dtype=float)[:3, 3]
        size = float(np.ceil(1.5 * reach))
        scene.add_grid("/grid", width=size, height=size, cell_size=0.1, section_size=0.5, plane="xy", position=base)
        look_at = base + np.array([0.0, 0.0, 0.3 * reach])
        self._server.initial_camera.look_at = look_at
        self._server.initial_camera.position = look_at + 0.9 * reach * np.array([1.0, 0.8, 0.5]) / np.sqrt(1.89)
        self._nodes: dict[int, Any] = {}
        self._meshes: dict[int, list[Any]] = {}
        for index, drawing in self._drawings.items():
            node = scene.add_frame(f"/arm/link{index}" if index >= 0 else "/arm/base", show_axes=False)
            self._nodes[index] = node
            self._meshes[index] = []
            for k, shape in enumerate(drawing.shapes):
                handle = scene.add_mesh_simple(
                    f"{node.name}/shape{k}",
                    shape.vertices,
                    shape.faces,
                    color=LINK_COLOR,
                    wxyz=_wxyz(shape.pose[:3, :3]),
                    position=shape.pose[:3, 3],
                )
                self._meshes[index].append(handle)
        tool = np.asarray(arm.tool, dtype=float)
        scene.add_frame(
            f"/arm/link{arm.tool_link}/tool",
            axes_length=0.08,
            axes_radius=0.004,
            wxyz=_wxyz(tool[:3, :3]),
            position=tool[:3, 3],
        )
        # overlays
        data = scene_data(arm, self._q)
        self._overlay: dict[str, list[Any]] = {name: [] for name in OVERLAYS}
        for ellipsoid in data["inertia"]:
            index = arm.joint_names.index(ellipsoid["link"])
            self._overlay["inertia"].append(
                scene.add_icosphere(
                    f"/arm/link{index}/inertia",
                    radius=1.0,
                    color=_OVERLAY_COLORS["inertia"],
                    opacity=0.45,
                    subdivisions=2,
                    scale=tuple(np.maximum(ellipsoid["radii"], 1e-4)),
                    wxyz=_wxyz(ellipsoid["local_axes"]),
                    position=ellipsoid["local_centre"],
                    visible="inertia" in overlays,
                )
            )
        for name in ("lambda", "manipulability"):
            self._overlay[name].append(
                scene.add_icosphere(
                    f"/overlays/{name}",
                    radius=1.0,
                    color=_OVERLAY_COLORS[name],
                    opacity=0.4,
                    subdivisions=2,
                    visible=name in overlays,
                )
            )
        self._overlay["com"].append(
            scene.add_icosphere("/overlays/com", radius=0.025, color=_OVERLAY_COLORS["com"], visible="com" in overlays)
        )
        self._overlay["gravity"].append(
            scene.add_arrows(
                "/overlays/gravity",
                points=np.zeros((arm.n, 2, 3)),
                colors=_OVERLAY_COLORS["gravity"],
                shaft_radius=0.006,
                head_radius=0.015,
                head_length=0.03,
                visible="gravity" in overlays,
            )
        )
        self._labels = [
            scene.add_label(f"/overlays/gravity_label{i}", "", font_screen_scale=0.75, visible="gravity" in overlays)
            for i in range(arm.n)
        ]
        self._shown = set(overlays)
        # the panel: overlays, joints, playback
        with gui.add_folder("Overlays"):
            for name in OVERLAYS:
                box = gui.add_checkbox(name, initial_value=name in overlays)
                box.on_update(lambda event, name=name: self.show_overlay(name, event.target.value))
        self._sliders = []
        if self.result is None:
            with gui.add_folder("Joints"):
                lower, upper = np.asarray(arm.qlim, dtype=float)
                for i, joint in enumerate(arm.joint_names):
                    span = np.pi if arm.kinds[i] == "revolute" else 1.0
                    low = max(lower[i], self._q[i] - span) if np.isfinite(lower[i]) else self._q[i] - span
                    high = min(upper[i], self._q[i] + span) if np.isfinite(upper[i]) else self._q[i] + span
                    low, high = min(low, self._q[i]), max(high, self._q[i])  # q outside the limits still shows
                    slider = gui.add_slider(joint, min=float(low), max=float(high), step=1e-3, initial_value=self._q[i])
                    slider.on_update(lambda _event: self._from_sliders())
                    self._sliders.append(slider)
        else:
            self._build_playback()

    def _build_playback(self) -> None:
        result, scene, gui = self.result, self._server.scene, self._server.gui
        assert result is not None
        t = np.asarray(result.t, dtype=float)
        steps = max(int(np.floor((t[-1] - t[0]) * FRAME_RATE)) + 1, 1)
        self._frame_times = t[0] + np.arange(steps) / FRAME_RATE
        self._frame_rows = np.clip(np.searchsorted(t, self._frame_times), 0, len(t) - 1)
        rows = self._frame_rows
        trace = self.arm.tool_pose(np.asarray(result.q, dtype=float)[rows])[:, :3, 3]
        scene.add_spline_catmull_rom("/run/trace", trace, color=(20, 20, 20), thickness=0.004)
        if result.q_d is not None:
            desired = self.arm.tool_pose(np.asarray(result.q_d, dtype=float)[rows])[:, :3, 3]
            scene.add_spline_catmull_rom("/run/desired", desired, color=(230, 60, 160), thickness=0.004)
        with gui.add_folder("Playback"):
            self._time = gui.add_slider(
                "time (s)", min=float(t[0]), max=float(t[-1]), step=1.0 / FRAME_RATE, initial_value=float(t[0])
            )
            self._playing = gui.add_checkbox("play", initial_value=False)
            self._torque_text = gui.add_markdown("")
            self._inputs = None
            if getattr(result, "drives", None) is not None:
                self._inputs = gui.add_markdown("")
        self._time.on_update(lambda event: self.show_time(float(event.target.value)))
        self._playing.on_update(lambda event: self._play(bool(event.target.value)))

    # ----- changing what is drawn ------------------------------------------------------------------------------------
    def _from_sliders(self) -> None:
        self.set_configuration(np.array([slider.value for slider in self._sliders]))

    def set_configuration(self, q: Any) -> None:
        """Draw the arm at q: every link frame moved, the overlays recomputed.

        Parameters
        ----------
        q : array_like
            Joint positions, (n,), rad or m.

        Raises
        ------
        armdyn.ModelError
            When q is not n finite numbers.
        """
        q = self._checked(q)
        with self._lock:
            self._q = q
            arm = self.arm
            T = arm.link_transforms(q)
            base = np.asarray(arm.base, dtype=float)
            with self._server.atomic():
                for index, node in self._nodes.items():
                    pose = base if index < 0 else T[index]
                    node.wxyz = _wxyz(pose[:3, :3])
                    node.position = pose[:3, 3]
                self._draw_overlays(q, T)

    def _draw_overlays(self, q: np.ndarray, T: np.ndarray) -> None:
        arm, shown = self.arm, self._shown
        if "lambda" in shown or "manipulability" in shown:
            data = {"manipulability": manipulability_ellipsoid(arm, q)}
            with contextlib.suppress(ModelError, np.linalg.LinAlgError):  # singular: no Lambda, ellipsoid hidden
                data["lambda"] = lambda_ellipsoid(arm, q)
            for name in ("lambda", "manipulability"):
                handle = self._overlay[name][0]
                if name not in data:
                    handle.visible = False
                    continue
                handle.visible = name in shown
                handle.scale = tuple(np.maximum(data[name]["radii"], 1e-4))
                handle.wxyz = _wxyz(data[name]["axes"])
                handle.position = data[name]["centre"]
        if "com" in shown:
            self._overlay["com"][0].position = _centre_of_mass(arm, T)
        if "gravity" in shown:
            G = np.asarray(arm.gravity_vector(q), dtype=float)
            largest = float(np.max(np.abs(G))) if np.any(G) else 1.0
            joints = _joint_frames(arm, T)
            points = np.zeros((arm.n, 2, 3))
            for i in range(arm.n):
                origin, axis = joints[i]
                points[i, 0] = origin
                points[i, 1] = origin + GRAVITY_SCALE * G[i] / largest * axis
                unit = "N m" if arm.kinds[i] == "revolute" else "N"
                self._labels[i].text = f"G{i + 1} = {G[i]:.3g} {unit}"
                self._labels[i].visible = abs(G[i]) >= 0.01 * largest  # the joints gravity loads, uncluttered
                self._labels[i].position = points[i, 1]
            self._overlay["gravity"][0].points = points

    def show_overlay(self, name: str, visible: bool = True) -> None:
        """Show or hide one overlay (as its checkbox does).

        Parameters
        ----------
        name : str
            One of ``OVERLAYS``.
        visible : bool, optional
            Show it (default) or hide it.

        Raises
        ------
        armdyn.ModelError
            When the name is not an overlay.
        """
        if name not in OVERLAYS:
            raise ModelError(f"overlay '{name}' is not one of {', '.join(OVERLAYS)}")
        with self._lock:
            (self._shown.add if visible else self._shown.discard)(name)
            with self._server.atomic():
                for handle in self._overlay[name]:
                    handle.visible = visible
                if name == "gravity":
                    for label in self._labels:
                        label.visible = visible
            self.set_configuration(self._q)

    def show_time(self, t: float) -> None:
        """Draw the run at time t: the arm at q(t), its links coloured by |tau(t)| / limit, the drives' inputs.

        Parameters
        ----------
        t : float
            The time, s (the nearest sample at or after it is drawn).

        Raises
        ------
        armdyn.ModelError
            When the viewer has no run.
        """
        result = self.result
        if result is None:
            raise ModelError("show_time needs a run: make the viewer with result= (result.view())")
        row = int(np.clip(np.searchsorted(np.asarray(result.t), t), 0, len(result.t) - 1))
        self._show_row(row)

    def _show_row(self, row: int) -> None:
        result = self.result
        assert result is not None
        tau = np.asarray(result.tau[row], dtype=float)
        ratio = np.abs(tau) / self._limits
        with self._lock:
            self.set_configuration(result.q[row])
            with self._server.atomic():
                for index, handles in self._meshes.items():
                    if index >= 0:
                        for handle in handles:
                            handle.color = _blend(float(ratio[index]))
        lines = " | ".join(f"{name}: {value:.3g}" for name, value in zip(self.arm.joint_names, tau, strict=True))
        self._torque_text.content = f"t = {result.t[row]:.3f} s; tau: {lines}"
        if self._inputs is not None and result.drives is not None:
            v = np.asarray(result.drives.v[row], dtype=float)
            shown = " | ".join(f"{name}: {value:.3g}" for name, value in zip(self.arm.joint_names, v, strict=True))
            self._inputs.content = f"drive inputs (V; A for valves): {shown}"

    def _play(self, playing: bool) -> None:
        if not playing:
            self._stop.set()
            return
        self._stop.clear()

        def run() -> None:
            result = self.result
            assert result is not None
            while not self._stop.wait(1.0 / FRAME_RATE):
                t = self._time.value + 1.0 / FRAME_RATE
                self._time.value = float(result.t[0]) if t > result.t[-1] else t

        self._player = threading.Thread(target=run, daemon=True)
        self._player.start()

    # ----- numbers, the saved page, closing ---------------------------------------------------------------------------
    def scene_data(self) -> dict[str, Any]:
        """What the scene shows at the current configuration, as numbers (``scene_data`` of the arm and q) with the
        drawing's links and warnings.

        Returns
        -------
        dict
            ``armdyn.viewer.scene_data``'s keys, with "links" a list of {"name", "kind" ("mesh", "capsule", "box",
            "cylinder", "sphere"; "none" for an undrawn base), "files"} (the base first, then one per joint),
            "warnings" the list of meshes that could not be found or loaded, "overlays" the overlays shown and
            "link_color" LINK_COLOR.
        """
        data = scene_data(self.arm, self._q)
        data["links"] = [
            {"name": drawing.name, "kind": drawing.kind, "files": list(drawing.files)}
            for _, drawing in sorted(self._drawings.items())
        ]
        data["warnings"] = list(self.warnings)
        data["overlays"] = tuple(name for name in OVERLAYS if name in self._shown)
        data["link_color"] = LINK_COLOR
        return data

    def save_html(self, path: str | os.PathLike[str]) -> Path:
        """Write one self-contained page that replays the scene offline: viser's client with the recording inline.

        The page needs no network and no server: the client's script and the scene (and for a run, every frame at
        FRAME_RATE per second, meshes sent once) are in the file.

        Parameters
        ----------
        path : str or os.PathLike
            The .html file to write.

        Returns
        -------
        pathlib.Path
            The file written.

        Raises
        ------
        armdyn.ModelError
            When the file's folder does not exist.
        """
        target = Path(path)
        if not target.parent.is_dir():
            raise ModelError(f"{target}: the folder {target.parent} does not exist")
        with self._lock:
            serializer = self._server.get_scene_serializer()
            if self.result is not None:
                current = self._q
                for row in self._frame_rows:
                    self._show_row(int(row))
                    serializer.insert_sleep(1.0 / FRAME_RATE)
                page = serializer.as_html()
                self.set_configuration(current)
            else:
                serializer.insert_sleep(1.0 / FRAME_RATE)
                page = serializer.as_html()
        target.write_text(page, encoding="utf-8")
        return target

    def close(self) -> None:
        """Stop the server (and a playing run); the page loses its connection."""
        self._stop.set()
        if self._player is not None:
            self._player.join(timeout=1.0)
        with contextlib.redirect_stdout(io.StringIO()):
            self._server.stop()

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"Viewer({self.arm.name}, {self.url})"

    def serve_forever(self) -> None:
        """Keep serving until interrupted (Ctrl-C), then close."""
        try:
            while True:
                time.sleep(1.0)
        except KeyboardInterrupt:
            pass
        finally:
            self.close()


def _check_address(host: object, port: object) -> None:
    """A ModelError unless ``port`` is 0 (a free one) or a port from 1 to 65535 that ``host`` can listen on now:
    viser's server thread, failing to bind, would leave its caller waiting for ever."""
    if isinstance(port, bool) or not isinstance(port, (int, np.integer)) or not 0 <= int(port) <= 65535:
        raise ModelError(f"port must be an integer from 0 (a free port) to 65535, got {port!r}")
    if not isinstance(host, str) or not host:
        raise ModelError(f"host must be an address to listen on, such as '127.0.0.1', got {host!r}")
    try:
        with socket.create_server((host, int(port))):
            pass
    except (OSError, OverflowError, UnicodeError) as error:
        raise ModelError(f"the viewer cannot listen on {host}:{port}: {error}") from None


def _joint_frames(arm: Robot, T: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Each joint's origin and unit axis in the world, from the link poses T (n, 4, 4)."""
    frames = []
    for i, link in enumerate(arm.links):
        joint = T[i] @ np.linalg.inv(np.asarray(link.joint.frame_offset, dtype=float))
        frames.append((joint[:3, 3], joint[:3, :3] @ np.asarray(link.joint.axis, dtype=float)))
    return frames
