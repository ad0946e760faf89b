"""A live meshcat scene of a robot (:class:`Viewer`): show a configuration or animate a joint path, with targets
and paths, and export the scene (animation included) as one self-contained HTML page; screenshots through a
headless chromium. What is drawn comes from :class:`~framework.viz.drawing.RobotDrawing`. Every drawn object is a
rigid body whose world transform is set per configuration, so a still and an animation use one code path.
meshcat is imported only here, when a viewer is created.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .drawing import DESIRED_COLOR, JOINT_COLOR, LINK_COLOR, TARGET_COLOR, VISUAL_COLOR, RobotDrawing, Visual
from ..errors import ViewerError

if TYPE_CHECKING:  # pragma: no cover
    from ..model.robot import Robot


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
        """A :class:`~framework.geometry.scene.Scene`'s obstacles under ``obstacles/<name>``."""
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
