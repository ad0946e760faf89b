"""Seeing a robot: what to draw of it (:class:`RobotDrawing`), and a live meshcat scene (:class:`Viewer`).

:class:`RobotDrawing` turns a configuration into world-frame geometry with Pinocchio: every frame origin joined
to its parent frame's origin (the links as segments, fixed and locked joints included), the joint origins,
axes for chosen frames, and the URDF's ``<visual>`` meshes and primitives where their files resolve locally
(``package://`` paths are looked up next to the URDF, in ``ROS_PACKAGE_PATH`` and in installed ``cmeel`` data
such as example-robot-data; nothing is downloaded). The rerun recordings (:mod:`framework.recording`) draw
the same geometry.

:class:`Viewer` shows a configuration or animates a joint path in meshcat, with targets and paths, and exports
the scene (animation included) as one self-contained HTML page. Every drawn object is a rigid body whose
world transform is set per configuration, so a still and an animation use one code path. meshcat is imported
only here, when a viewer is created.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sysconfig
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from .errors import ViewerError

if TYPE_CHECKING:  # pragma: no cover
    from .robot import Robot

#: Colours (RGB 0-255) used by the recordings and the meshcat viewer.
LINK_COLOR = (255, 127, 14)
JOINT_COLOR = (40, 40, 40)
TARGET_COLOR = (214, 39, 40)
DESIRED_COLOR = (31, 119, 180)
TRACKED_COLOR = (44, 160, 44)
VISUAL_COLOR = (190, 190, 190)


# ---------------------------------------------------------------------------------------------- drawing
@dataclass(frozen=True)
class Visual:
    """One ``<visual>`` of the URDF, attached to a link.

    Attributes:
        link: the link (a body frame of the model).
        frame_id: its Pinocchio frame index.
        origin: ``(4, 4)`` placement of the geometry in the link frame.
        kind: ``"mesh"``, ``"box"``, ``"cylinder"`` (along its z axis) or ``"sphere"``.
        size: mesh scale ``(3,)``; box edge lengths ``(3,)`` [m]; cylinder ``(radius, length)`` [m]; sphere
            ``(radius,)`` [m].
        path: the resolved mesh file (meshes only).
        rgba: colour from the URDF material, each in ``[0, 1]``, if it has one.
    """

    link: str
    frame_id: int
    origin: np.ndarray = field(repr=False)
    kind: str
    size: np.ndarray = field(repr=False)
    path: Path | None = None
    rgba: tuple[float, float, float, float] | None = None


class RobotDrawing:
    """What a viewer draws of a robot: links as segments between frame origins, joints, frames, visuals.

    Computed with Pinocchio from ``robot.model`` (locked joints already folded in), so composed and reduced
    robots draw like any other. Shared by the rerun recordings and the meshcat viewer.

    Args:
        robot: the robot.
        frames: frames drawn as axes (default: the end-effectors).
    """

    def __init__(self, robot: Robot, frames: Sequence[str] | None = None):
        self.robot = robot
        self.frames = tuple(robot.end_effectors if frames is None else frames)
        self.frame_ids = np.array([robot.frame_id(f) for f in self.frames], dtype=int)
        model = robot.model
        self._data = model.createData()
        self.joint_frame_ids = np.array(
            [i for i, f in enumerate(model.frames) if f.type == pin.FrameType.JOINT], dtype=int
        )
        self.segment_frame_ids = self._segments()
        self.visuals, self.missing = robot_visuals(robot)

    def _segments(self) -> np.ndarray:
        """``(m, 2)`` (parent frame, frame) pairs whose origins are apart in some sampled configuration."""
        model = self.robot.model
        pairs = np.array([(f.parentFrame, i) for i, f in enumerate(model.frames) if i > 0], dtype=int)
        if pairs.size == 0:
            return pairs.reshape(0, 2)
        rng = np.random.default_rng(0)
        samples = np.vstack([self.robot.middle, self.robot.random_configurations(rng, 3)])
        M = self.world_frames(samples)
        origins = M[..., :3, 3]
        length = np.linalg.norm(origins[:, pairs[:, 0]] - origins[:, pairs[:, 1]], axis=-1)
        return pairs[(length > 1e-9).any(axis=0)]

    def world_frames(self, X: np.ndarray) -> np.ndarray:
        """``(pop, nframes, 4, 4)`` world placement of every frame of the model for ``X`` ``(pop, n)``."""
        X = self.robot.check_population(X)
        model = self.robot.model
        if len(self._data.oMf) != model.nframes:  # frames added since (Robot.add_frame): Pinocchio sizes Data once
            self._data = model.createData()
        data = self._data
        out = np.empty((X.shape[0], model.nframes, 4, 4))
        for k, q in enumerate(self.robot.to_pinocchio(X)):
            pin.framesForwardKinematics(model, data, q)
            for i in range(model.nframes):
                out[k, i] = data.oMf[i].homogeneous
        return out

    def segments(self, M: np.ndarray) -> np.ndarray:
        """``(pop, m, 2, 3)`` link segments [m] from :meth:`world_frames` ``M``."""
        ids = self.segment_frame_ids
        origins = M[..., :3, 3]
        return np.stack([origins[:, ids[:, 0]], origins[:, ids[:, 1]]], axis=2)

    def joint_origins(self, M: np.ndarray) -> np.ndarray:
        """``(pop, j, 3)`` world positions of the joints [m]."""
        return M[:, self.joint_frame_ids][..., :3, 3]

    def frame_placements(self, M: np.ndarray) -> np.ndarray:
        """``(pop, k, 4, 4)`` world placements of :attr:`frames`."""
        return M[:, self.frame_ids]

    def visual_placements(self, M: np.ndarray) -> np.ndarray:
        """``(pop, v, 4, 4)`` world placements of :attr:`visuals` (without the mesh scale)."""
        if not self.visuals:
            return np.zeros((M.shape[0], 0, 4, 4))
        ids = np.array([v.frame_id for v in self.visuals])
        origins = np.stack([v.origin for v in self.visuals])
        return M[:, ids] @ origins


def robot_visuals(robot: Robot) -> tuple[tuple[Visual, ...], tuple[str, ...]]:
    """The URDF's ``<visual>`` elements whose geometry can be drawn, and the mesh files that did not resolve."""
    if not robot.urdf:
        return (), ()
    try:
        root = ET.fromstring(robot.urdf)
    except ET.ParseError:
        return (), ()
    base_dir = Path(robot.source).parent if robot.source else None
    materials = {m.get("name"): _rgba(m) for m in root.findall("material")}
    visuals, missing = [], []
    for link in root.findall("link"):
        name = link.get("name")
        if not robot.model.existFrame(name, pin.FrameType.BODY):
            continue
        frame_id = robot.model.getFrameId(name, pin.FrameType.BODY)
        for element in link.findall("visual"):
            geometry = element.find("geometry")
            if geometry is None or len(geometry) == 0:
                continue
            shape = geometry[0]
            origin = _origin(element.find("origin"))
            material = element.find("material")
            rgba = None
            if material is not None:
                rgba = _rgba(material) or materials.get(material.get("name"))
            if shape.tag == "mesh":
                path = resolve_mesh(shape.get("filename", ""), base_dir)
                if path is None:
                    missing.append(shape.get("filename", ""))
                    continue
                scale = np.array(_floats(shape.get("scale", "1 1 1"), 3))
                visuals.append(Visual(name, frame_id, origin, "mesh", scale, path, rgba))
            elif shape.tag == "box":
                visuals.append(
                    Visual(name, frame_id, origin, "box", np.array(_floats(shape.get("size"), 3)), None, rgba)
                )
            elif shape.tag == "cylinder":
                size = np.array([float(shape.get("radius", 0)), float(shape.get("length", 0))])
                visuals.append(Visual(name, frame_id, origin, "cylinder", size, None, rgba))
            elif shape.tag == "sphere":
                visuals.append(
                    Visual(
                        name,
                        frame_id,
                        origin,
                        "sphere",
                        np.array([float(shape.get("radius", 0))]),
                        None,
                        rgba,
                    )
                )
    return tuple(visuals), tuple(dict.fromkeys(missing))


def resolve_mesh(filename: str, base_dir: Path | None = None) -> Path | None:
    """A local file for a URDF mesh path (absolute, relative, ``file://`` or ``package://``), or None."""
    filename = filename.removeprefix("file://")
    if filename.startswith("package://"):
        package, _, rest = filename[len("package://") :].partition("/")
        candidates = []
        if base_dir is not None:
            for ancestor in [base_dir, *base_dir.parents]:
                if ancestor.name == package:
                    candidates.append(ancestor / rest)
                candidates.append(ancestor / package / rest)
        candidates += [Path(root) / package / rest for root in _package_roots()]
    elif "://" in filename:
        return None  # http:// and friends: never downloaded
    else:
        path = Path(filename)
        candidates = [path] if path.is_absolute() else ([base_dir / path] if base_dir is not None else [])
    return next((c.resolve() for c in candidates if c.is_file()), None)


def _package_roots() -> list[str]:
    roots = [p for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    roots += [str(Path(p) / "share") for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    for key in ("purelib", "platlib"):
        share = Path(sysconfig.get_paths()[key]) / "cmeel.prefix" / "share"
        if share.is_dir():
            roots.append(str(share))
    return list(dict.fromkeys(roots))


def _floats(text: str | None, size: int) -> list[float]:
    values = [float(v) for v in (text or "").split()]
    return values if len(values) == size else [0.0] * size


def _origin(element: ET.Element | None) -> np.ndarray:
    if element is None:
        return np.eye(4)
    M = np.eye(4)
    M[:3, :3] = pin.rpy.rpyToMatrix(*_floats(element.get("rpy", "0 0 0"), 3))
    M[:3, 3] = _floats(element.get("xyz", "0 0 0"), 3)
    return M


def _rgba(material: ET.Element) -> tuple[float, float, float, float] | None:
    color = material.find("color")
    if color is None or not color.get("rgba"):
        return None
    values = _floats(color.get("rgba"), 4)
    return tuple(values)  # type: ignore[return-value]


# ---------------------------------------------------------------------------------------------- meshcat
def _hex(rgb: Sequence[float]) -> int:
    r, g, b = (int(c) for c in rgb[:3])
    return (r << 16) | (g << 8) | b


def segment_transforms(segments: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rigid placements ``(m, 4, 4)`` and lengths ``(m,)`` that map meshcat's unit cylinder (along y, centred
    at the origin) onto each segment ``(m, 2, 3)``; stretch the y axis by the length to draw it."""
    a, b = segments[:, 0], segments[:, 1]
    d = b - a
    length = np.linalg.norm(d, axis=-1)
    u = d / np.maximum(length, 1e-12)[:, None]
    T = np.tile(np.eye(4), (len(segments), 1, 1))
    y = np.array([0.0, 1.0, 0.0])
    for k, uk in enumerate(u):
        c = float(y @ uk)
        if c < -1 + 1e-9:  # pointing down -y: half a turn about x
            R = np.diag([1.0, -1.0, -1.0])
        else:
            v = np.cross(y, uk)
            V = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
            R = np.eye(3) + V + V @ V / (1.0 + c)
        T[k, :3, :3] = R
    T[:, :3, 3] = 0.5 * (a + b)
    return T, np.maximum(length, 1e-6)


#: Obstacles' colour in meshcat (RGB 0-255).
OBSTACLE_RGB = (150, 110, 80)


class Viewer:
    """A meshcat scene of one robot: show configurations, animate joint paths, draw targets and paths.

    Starts its own meshcat server (or connects to ``zmq_url``); use it as a context manager, or call
    :meth:`close`, so the server stops. The scene is Z-up, in metres, in the world frame.

    Args:
        robot: the robot.
        frames: frames drawn as axes (default: the end-effectors).
        zmq_url: an already running meshcat server (default: start one).
        link_radius: radius of the drawn links [m].

    Example::

        with Viewer(robot) as viewer:
            viewer.show(result.configuration)
            viewer.add_points("targets", [t1, t2])
            viewer.save_html("scene.html")
    """

    def __init__(
        self,
        robot: Robot,
        *,
        frames: Sequence[str] | None = None,
        zmq_url: str | None = None,
        link_radius: float = 0.012,
    ):
        import contextlib
        import io
        import warnings

        with warnings.catch_warnings():  # meshcat 0.3 imports pyzmq's deprecated ioloop module
            warnings.simplefilter("ignore", DeprecationWarning)
            import meshcat
            import meshcat.servers.zmqserver

        self.robot = robot
        self.drawing = RobotDrawing(robot, frames)
        with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints its URL
            self.vis = meshcat.Visualizer(zmq_url=zmq_url)
        self._owns_server = zmq_url is None
        self._g = meshcat.geometry
        self._radius = link_radius
        self._reach = 1.0
        try:
            self._build()
            self.show(robot.middle)
        except BaseException:
            self.close()  # never leave a server behind
            raise

    # ------------------------------------------------------------------ lifecycle
    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Stop the meshcat server this viewer started (idempotent)."""
        process = getattr(self.vis.window, "server_proc", None) if self._owns_server else None
        if process is not None and process.poll() is None:
            process.terminate()
            try:
                process.wait(timeout=5)
            except subprocess.TimeoutExpired:  # pragma: no cover
                process.kill()
        self._owns_server = False

    @property
    def url(self) -> str:
        """Where a browser shows the live scene."""
        return self.vis.url()

    # ------------------------------------------------------------------ the robot
    def _build(self) -> None:
        g, vis, drawing = self._g, self.vis, self.drawing
        vis["robot"].delete()
        link = g.MeshLambertMaterial(color=_hex(LINK_COLOR))
        joint = g.MeshLambertMaterial(color=_hex(JOINT_COLOR))
        for k in range(len(drawing.segment_frame_ids)):
            vis[f"robot/links/{k}"].set_object(g.Cylinder(1.0, self._radius), link)
        for k in range(len(drawing.joint_frame_ids)):
            vis[f"robot/joints/{k}"].set_object(g.Sphere(1.6 * self._radius), joint)
        M = drawing.world_frames(self.robot.middle)
        segments = drawing.segments(M)[0]
        points = segments.reshape(-1, 3)
        self._reach = float(max(np.ptp(points, axis=0).max(), 0.3)) if points.size else 1.0
        for k, name in enumerate(drawing.frames):
            vis[f"robot/frames/{k}"].set_object(g.triad(0.2 * self._reach))
        for k, visual in enumerate(drawing.visuals):
            geometry = self._visual_geometry(visual)
            if geometry is not None:
                color = VISUAL_COLOR if visual.rgba is None else tuple(255 * c for c in visual.rgba[:3])
                vis[f"robot/visuals/{k}"].set_object(geometry, g.MeshLambertMaterial(color=_hex(color)))

    def _visual_geometry(self, visual: Visual):
        g = self._g
        if visual.kind == "box":
            return g.Box(visual.size)
        if visual.kind == "sphere":
            return g.Sphere(float(visual.size[0]))
        if visual.kind == "cylinder":
            return g.Cylinder(float(visual.size[1]), float(visual.size[0]))
        import trimesh

        try:
            mesh = trimesh.load(str(visual.path), force="mesh")
        except Exception:  # noqa: BLE001 - a mesh trimesh cannot read is left out, the skeleton still shows the link
            return None
        return g.TriangularMeshGeometry(np.asarray(mesh.vertices), np.asarray(mesh.faces))

    def _transforms(self, M: np.ndarray) -> dict[str, tuple[np.ndarray, list[float] | None]]:
        """Object path -> (rigid placement (4, 4), scale or None) for one configuration's frames ``M``."""
        drawing = self.drawing
        out: dict[str, tuple[np.ndarray, list[float] | None]] = {}
        T, lengths = segment_transforms(drawing.segments(M[None])[0])
        for k, (Tk, length) in enumerate(zip(T, lengths)):
            out[f"robot/links/{k}"] = (Tk, [1.0, float(length), 1.0])
        for k, p in enumerate(drawing.joint_origins(M[None])[0]):
            P = np.eye(4)
            P[:3, 3] = p
            out[f"robot/joints/{k}"] = (P, None)
        for k, F in enumerate(drawing.frame_placements(M[None])[0]):
            out[f"robot/frames/{k}"] = (F, None)
        for k, (visual, V) in enumerate(zip(drawing.visuals, drawing.visual_placements(M[None])[0])):
            if visual.kind == "cylinder":  # meshcat cylinders run along y, URDF cylinders along z
                V = V @ np.array([[1.0, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])
            scale = list(map(float, visual.size)) if visual.kind == "mesh" else None
            out[f"robot/visuals/{k}"] = (V, scale)
        return out

    def show(self, x: np.ndarray) -> None:
        """Pose the robot at joint coordinates ``x`` ``(n,)`` [rad / m]."""
        M = self.drawing.world_frames(x)[0]
        for path, (T, scale) in self._transforms(M).items():
            self.vis[path].set_transform(T if scale is None else T @ np.diag([*scale, 1.0]))

    def animate(
        self, path: np.ndarray, *, fps: float = 30.0, repetitions: int = 1, play: bool = True
    ) -> None:
        """Animate a joint path ``(K, n)``, one waypoint per frame at ``fps``; the HTML export keeps it."""
        from meshcat.animation import Animation

        Q = self.robot.check_population(path, "joint path")
        M = self.drawing.world_frames(Q)
        animation = Animation(default_framerate=fps)
        for k in range(Q.shape[0]):
            with animation.at_frame(self.vis, k) as frame:
                for name, (T, scale) in self._transforms(M[k]).items():
                    frame[name].set_transform(T)
                    if scale is not None:
                        frame[name].set_property("scale", "vector3", scale)
        self.show(Q[0])
        self.vis.set_animation(animation, play=play, repetitions=repetitions)

    # ------------------------------------------------------------------ targets and paths
    def add_points(
        self, name: str, points: np.ndarray, *, color: Sequence[int] = TARGET_COLOR, radius: float = 0.02
    ) -> None:
        """Spheres at ``points`` ``(k, 3)`` [m, world] under ``markers/<name>``."""
        g = self._g
        self.vis[f"markers/{name}"].delete()
        material = g.MeshLambertMaterial(color=_hex(color))
        for k, p in enumerate(np.asarray(points, dtype=float).reshape(-1, 3)):
            node = self.vis[f"markers/{name}/{k}"]
            node.set_object(g.Sphere(radius), material)
            T = np.eye(4)
            T[:3, 3] = p
            node.set_transform(T)

    def add_path(self, name: str, points: np.ndarray, *, color: Sequence[int] = DESIRED_COLOR) -> None:
        """A polyline through ``points`` ``(K, 3)`` [m, world] under ``paths/<name>``."""
        g = self._g
        P = np.asarray(points, dtype=float).reshape(-1, 3)
        line = g.Line(
            g.PointsGeometry(P.T.astype(np.float32)), g.LineBasicMaterial(color=_hex(color), linewidth=2)
        )
        self.vis[f"paths/{name}"].set_object(line)

    def add_scene(self, scene, *, color: Sequence[int] = OBSTACLE_RGB) -> None:
        """A :class:`~framework.scene.Scene`'s obstacles under ``obstacles/<name>``."""
        g = self._g
        material = g.MeshLambertMaterial(color=_hex(color), opacity=0.8, transparent=True)
        for obstacle in scene:
            for sub, geometry, T in obstacle.meshcat(g):
                node = self.vis[f"obstacles/{obstacle.name}{sub}"]
                node.set_object(geometry, material)
                node.set_transform(T)

    def set_camera(self, position: Sequence[float] | None = None) -> None:
        """Place the camera at ``position`` [m, world, Z up], looking at the world origin (meshcat's orbit
        centre); default: in front of the robot, above it, at about twice its size."""
        if position is None:
            position = np.array([1.1, -1.5, 1.0]) * 1.3 * self._reach
        x, y, z = (float(c) for c in position)
        # the camera lives in meshcat's Y-up "rotated" frame: world (x, y, z) is (x, z, -y) there
        self.vis["/Cameras/default/rotated/<object>"].set_property("position", [x, z, -y])

    # ------------------------------------------------------------------ export
    def static_html(self) -> str:
        """The whole scene (and animation) as one self-contained HTML page (three.js inlined)."""
        return self.vis.static_html()

    def save_html(self, path: str | Path) -> Path:
        """Write :meth:`static_html` to ``path``."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(self.static_html())
        return path


# ---------------------------------------------------------------------------------------------- browser
CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


def find_chromium() -> str | None:
    """Path of a Chromium/Chrome executable on ``PATH``, or None."""
    return next((p for p in map(shutil.which, CHROMIUM_NAMES) if p), None)


def screenshot_command(
    html: str | Path,
    png: str | Path,
    *,
    chromium: str,
    size: tuple[int, int] = (800, 600),
    budget_ms: int = 5000,
) -> list[str]:
    """The headless-Chromium command that renders ``html`` into ``png`` (software WebGL, no network)."""
    return [
        chromium,
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        f"--user-data-dir={tempfile.mkdtemp(prefix='metaik-chromium-')}",
        f"--screenshot={Path(png).resolve()}",
        f"--window-size={size[0]},{size[1]}",
        f"--virtual-time-budget={budget_ms}",
        Path(html).resolve().as_uri(),
    ]


def screenshot(
    html: str | Path,
    png: str | Path,
    *,
    size: tuple[int, int] = (800, 600),
    budget_ms: int = 5000,
    timeout: float = 60.0,
) -> Path:
    """Render an exported page with headless Chromium into a PNG (for docs and tests)."""
    chromium = find_chromium()
    if chromium is None:
        raise ViewerError("no Chromium found on PATH (Debian: apt-get install -y chromium)")
    command = screenshot_command(html, png, chromium=chromium, size=size, budget_ms=budget_ms)
    profile = next(c.split("=", 1)[1] for c in command if c.startswith("--user-data-dir="))
    try:
        run = subprocess.run(command, capture_output=True, text=True, timeout=timeout, check=False)
    finally:
        shutil.rmtree(profile, ignore_errors=True)
    if run.returncode != 0 or not Path(png).is_file():
        raise ViewerError(f"chromium failed to render {html} (exit {run.returncode}): {run.stderr[-500:]}")
    return Path(png)
