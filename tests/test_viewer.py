"""What viewers draw of a robot, the meshcat scene, and its exported page rendered by a real headless browser."""

from __future__ import annotations

import os

import numpy as np
import pytest

import framework as fw
from framework.viz.drawing import LINK_COLOR, RobotDrawing, robot_visuals
from framework.viz.viewer import Viewer, find_chromium, screenshot, screenshot_command, segment_transforms


def test_segment_transforms_map_the_unit_cylinder_onto_each_segment():
    rng = np.random.default_rng(0)
    segments = rng.normal(size=(50, 2, 3))
    segments[0, 1] = segments[0, 0] - [0.0, 0.7, 0.0]  # pointing down -y: the degenerate rotation
    segments[1, 1] = segments[1, 0] + [0.0, 0.3, 0.0]  # along +y
    T, length = segment_transforms(segments)
    np.testing.assert_allclose(length, np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1))
    for Tk, L, (a, b) in zip(T, length, segments):
        R = Tk[:3, :3]
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0)
        ends = [Tk[:3, :3] @ np.array([0.0, y * L, 0.0]) + Tk[:3, 3] for y in (-0.5, 0.5)]
        np.testing.assert_allclose(ends, [a, b], atol=1e-12)


def test_drawing_joins_frames_as_pinocchio_places_them():
    robot = fw.load_robot("youbot_dual_mobile")
    drawing = RobotDrawing(robot)
    x = robot.random_configurations(np.random.default_rng(3), 1)[0]
    M = drawing.world_frames(x)
    segments = drawing.segments(M)[0]
    for frame in robot.end_effectors:  # every end-effector is the end of a drawn link
        p = robot.frame_placement(x, frame).translation
        assert np.min(np.linalg.norm(segments[:, 1] - p, axis=1)) < 1e-12
    np.testing.assert_allclose(
        drawing.frame_placements(M)[0, 0], robot.frame_placement(x, "arm1_ee").homogeneous
    )
    assert drawing.joint_origins(M).shape == (1, robot.n, 3)  # one origin per joint (13 one-DOF joints)
    assert np.all(np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1) > 0)  # no zero-length links drawn
    assert drawing.visuals == () and drawing.missing == ()  # the DH-generated robots have no meshes


def test_visuals_of_example_robot_data_resolve(erd):
    robot = fw.load_robot(str(erd / "ur_description" / "urdf" / "ur5_robot.urdf"))
    visuals, missing = robot_visuals(robot)
    assert missing == ()
    assert len(visuals) == 7 and all(v.kind == "mesh" and v.path.is_file() for v in visuals)
    assert {v.path.suffix for v in visuals} == {".dae"}


def test_viewer_draws_the_urdf_meshes(erd):
    """UR5: its seven Collada meshes become meshcat meshes, placed where Pinocchio puts their links."""
    robot = fw.load_robot(str(erd / "ur_description" / "urdf" / "ur5_robot.urdf"))
    x = np.array([0.0, -1.2, 1.5, -0.3, 1.57, 0.0])
    with Viewer(robot) as viewer:
        viewer.show(x)
        commands = _commands(viewer.static_html())
    meshes = {c["path"]: c for c in commands if c["type"] == "set_object" and "/robot/visuals/" in c["path"]}
    assert len(meshes) == 7
    for command in meshes.values():  # real meshes: hundreds of vertices (float32 x, y, z) each
        vertices = command["object"]["geometries"][0]["data"]["attributes"]["position"]["array"].data
        assert len(vertices) >= 300 * 3 * 4
    placed = {
        c["path"]: np.array(c["matrix"]).reshape(4, 4).T for c in commands if c["type"] == "set_transform"
    }
    drawing = RobotDrawing(robot)
    for k, visual in enumerate(drawing.visuals):
        expected = robot.frame_placement(x, visual.link).homogeneous @ visual.origin
        np.testing.assert_allclose(placed[f"/meshcat/robot/visuals/{k}"], expected, atol=1e-6)


def test_viewer_draws_animates_and_stops_its_server(tmp_path):
    robot = fw.load_robot("youbot_arm")
    Q = robot.middle + np.linspace(0, 0.5, 5)[:, None]
    with Viewer(robot) as viewer:
        process = viewer.vis.window.server_proc
        viewer.show(Q[0])
        viewer.add_points("targets", [[0.2, 0.1, 0.3]])
        viewer.add_path("desired", np.c_[np.linspace(0, 0.3, 10), np.zeros(10), np.full(10, 0.3)])
        viewer.animate(Q, fps=10)
        html = viewer.static_html()
        assert viewer.url.startswith("http://127.0.0.1:")
    assert process.poll() is not None  # the server is gone
    assert "MeshCat.Viewer" in html and len(html) > 500_000  # three.js inlined: a self-contained page
    commands = _commands(html)
    drawing = RobotDrawing(robot)
    objects = [c["path"] for c in commands if c["type"] == "set_object"]
    assert sum("/robot/links/" in p for p in objects) == len(drawing.segment_frame_ids)
    assert sum("/markers/targets/" in p for p in objects) == 1 and any("/paths/desired" in p for p in objects)
    (animation,) = [c for c in commands if c["type"] == "set_animation"]
    clips = {a["path"]: a["clip"] for a in animation["animations"]}
    link = clips["/meshcat/robot/links/0"]
    assert link["fps"] == 10
    tracks = {t["name"]: t["keys"] for t in link["tracks"]}
    assert set(tracks) == {".position", ".quaternion", ".scale"} and len(tracks[".position"]) == len(Q)


def test_viewer_draws_every_obstacle_kind_at_its_place(tmp_path):
    import trimesh

    path = tmp_path / "block.stl"
    trimesh.creation.box(extents=[0.1, 0.1, 0.1]).export(path)
    scene = fw.Scene((fw.Box([0.5, 0.0, 0.3], [0.4, 0.2, 0.1], name="table"), fw.Sphere([0, 0, 1], 0.1),
                      fw.Capsule([0, 1, 0], 0.05, 0.4), fw.Plane([0, 0, -0.1], [0, 0, 1]),
                      fw.Mesh(path, center=[1, 1, 0])))
    with Viewer(fw.load_robot("youbot_arm")) as viewer:
        viewer.add_scene(scene)
        html = viewer.static_html()
    commands = _commands(html)
    objects = {c["path"] for c in commands if c["type"] == "set_object"}
    assert {"/meshcat/obstacles/table", "/meshcat/obstacles/sphere", "/meshcat/obstacles/capsule/body",
            "/meshcat/obstacles/capsule/end0", "/meshcat/obstacles/plane", "/meshcat/obstacles/mesh"} <= objects
    placed = {c["path"]: np.array(c["matrix"]).reshape(4, 4).T for c in commands if c["type"] == "set_transform"}
    np.testing.assert_allclose(placed["/meshcat/obstacles/table"][:3, 3], [0.5, 0.0, 0.3])
    np.testing.assert_allclose(placed["/meshcat/obstacles/capsule/end1"][:3, 3], [0, 1, 0.2], atol=1e-12)


def _commands(html: str) -> list[dict]:
    """The meshcat commands embedded in an exported page (base64 msgpack, as meshcat writes them)."""
    import base64
    import re

    import umsgpack

    blobs = re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html)
    return [umsgpack.unpackb(base64.b64decode(b)) for b in blobs]


# ---------------------------------------------------------------------------------------------- browser
def _chromium_or_skip() -> None:
    if find_chromium() is None:
        if os.environ.get("CI"):
            pytest.fail("chromium is required in CI (apt-get install -y chromium)")
        pytest.skip("chromium is not installed (apt-get install -y chromium); CI installs it")


def _png_pixels(path) -> np.ndarray:
    """RGB pixels ``(h, w, 3)`` of a PNG (Pillow ships with meshcat)."""
    from PIL import Image

    with Image.open(path) as image:
        return np.asarray(image.convert("RGB"), dtype=int)


def test_exported_page_renders_in_headless_chromium(tmp_path):
    """The exported page of the mobile dual youBot loads in Chromium and draws the robot's orange links."""
    _chromium_or_skip()
    robot = fw.load_robot("youbot_dual_mobile")
    with Viewer(robot) as viewer:
        viewer.show(robot.middle)
        viewer.add_points("targets", [[0.5, -0.2, 0.45], [0.7, -0.5, 0.25]])
        viewer.set_camera()
        html = viewer.save_html(tmp_path / "scene.html")
    png = screenshot(html, tmp_path / "scene.png", size=(800, 600), budget_ms=2000)
    pixels = _png_pixels(png)
    assert pixels.shape == (600, 800, 3)
    assert pixels.reshape(-1, 3).std(axis=0).max() > 10  # not blank
    r, g, b = (pixels[..., i] for i in range(3))
    orange = (r > 150) & (g > 50) & (g < 190) & (b < 90) & (r - b > 120)  # LINK_COLOR under Lambert shading
    assert LINK_COLOR == (255, 127, 14)
    assert orange.sum() > 300, f"only {orange.sum()} link-coloured pixels: the robot was not drawn"


def test_empty_scene_has_no_link_pixels(tmp_path):
    """The check above can fail: a page without the robot has no link-coloured pixels."""
    _chromium_or_skip()
    robot = fw.load_robot("youbot_arm")
    with Viewer(robot) as viewer:
        viewer.vis["robot"].delete()
        html = viewer.save_html(tmp_path / "empty.html")
    pixels = _png_pixels(screenshot(html, tmp_path / "empty.png", size=(400, 300), budget_ms=1000))
    r, g, b = (pixels[..., i] for i in range(3))
    assert ((r > 150) & (g > 50) & (g < 190) & (b < 90) & (r - b > 120)).sum() == 0


def test_screenshot_command_is_headless_and_offline(tmp_path):
    command = screenshot_command(tmp_path / "a.html", tmp_path / "a.png", chromium="chromium")
    for flag in (
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-background-networking",
        "--virtual-time-budget=5000",
        "--window-size=800,600",
    ):
        assert flag in command
    assert command[-1].startswith("file://")
