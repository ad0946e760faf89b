"""Obstacles: the compiled signed distances against coal, their gradients and the Obstacles term's Jacobian against
finite differences, solves against a brute-force grid, the exact check deciding success, and task-file tables."""

from __future__ import annotations

import warnings

import coal
import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from framework.costs import Program
from framework.geometry.solids import solid_distance
from tests.compiled import curvature_at, linearize_in, make_workspaces, python_callable, rows_in, \
    set_jacobian_rows

solid_distance = python_callable(solid_distance)
from framework.engine import residuals
from framework.errors import TaskError
from framework.geometry.spheres import SphereCover
from framework.io.taskfile import load_task, resolve_task
from tests.test_collision import SPHERES, L, R

TURNED = pin.rpy.rpyToMatrix(0.3, -0.5, 1.1)
SOLIDS = [
    fw.Sphere([0.2, -0.1, 0.3], 0.15),
    fw.Box([0.1, 0.2, -0.1], [0.4, 0.2, 0.3], TURNED),
    fw.Capsule([-0.2, 0.1, 0.2], 0.1, 0.5, TURNED),
    fw.Plane([0.0, 0.0, 0.1], [0.2, -0.3, 1.0]),
]


def _sd(obstacle, point) -> tuple[float, np.ndarray]:
    g = np.empty(3)
    return solid_distance(*point, obstacle.solids()[0], 0, g), g


def _coal_distance(obstacle, point) -> float:
    """coal's distance from a point (a sphere of radius 1e-6) to the obstacle's exact geometry; a half-space is
    coal's own Halfspace here, not the box the exact check uses."""
    if isinstance(obstacle, fw.Plane):
        shape, placement = coal.Halfspace(obstacle.normal, float(obstacle.normal @ obstacle.point)), pin.SE3.Identity()
    else:
        shape, placement = obstacle.coal()
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    probe = coal.Sphere(1e-6)
    coal.distance(probe, coal.Transform3s(np.eye(3), np.asarray(point, float)), shape,
                  coal.Transform3s(placement.rotation, placement.translation), request, result)
    return result.min_distance + 1e-6


@pytest.mark.parametrize("obstacle", SOLIDS, ids=lambda o: o.name)
def test_signed_distances_equal_coal_outside_and_the_depth_inside(obstacle, rng):
    """Outside: coal's exact distance. Inside: minus the depth, brute-forced as the distance to the nearest of
    many surface samples (so a kernel returning 0 inside, or the outside formula, fails)."""
    from framework.geometry.spheres import surface_points

    points = rng.uniform(-0.8, 0.8, size=(300, 3))
    outside = inside = 0
    for p in points:
        sd, _ = _sd(obstacle, p)
        if sd > 1e-3:
            assert sd == pytest.approx(_coal_distance(obstacle, p), abs=1e-6)
            outside += 1
        elif sd < -1e-3 and not isinstance(obstacle, fw.Plane):
            shape, placement = obstacle.coal()
            surface = surface_points(shape, 40000, np.random.default_rng(1)) @ placement.rotation.T \
                + placement.translation
            depth = np.min(np.linalg.norm(surface - p, axis=1))
            assert -sd == pytest.approx(depth, abs=4e-3)
            inside += 1
    assert outside > 20
    assert inside > 0 or isinstance(obstacle, fw.Plane)


@pytest.mark.parametrize("obstacle", SOLIDS, ids=lambda o: o.name)
def test_signed_distance_gradients_match_differences(obstacle, rng):
    h = 1e-7
    for p in rng.uniform(-0.8, 0.8, size=(40, 3)):
        sd, g = _sd(obstacle, p)
        fd = np.array([(_sd(obstacle, p + e)[0] - _sd(obstacle, p - e)[0]) / (2 * h) for e in np.eye(3) * h])
        if np.linalg.norm(fd) > 0.5:  # away from the box's medial planes (a kink) the gradient is a unit vector
            np.testing.assert_allclose(g, fd, atol=1e-5)
        assert np.linalg.norm(g) == pytest.approx(1.0, abs=1e-12)


def _hinge_jacobian_matches_differences(robot, program, rng, samples: int) -> int:
    """Jacobian rows against central differences at random configurations, rows away from the hinge's corner
    (``|r| > 1e-5``); returns how many rows were compared."""
    h = 1e-7
    active = 0
    for x in robot.random_configurations(rng, samples):
        r, J = residuals(program, x)
        fd = np.column_stack([(residuals(program, x + e)[0] - residuals(program, x - e)[0]) / (2 * h)
                              for e in np.eye(robot.n) * h])
        rows = np.abs(r) > 1e-5
        np.testing.assert_allclose(J[rows], fd[rows], atol=1e-5)
        active += int(rows.sum())
    return active


def test_obstacles_jacobian_matches_differences_on_the_mobile_dual_youbot(rng):
    robot = fw.load_robot("youbot_dual_mobile")
    shape = fw.RobotShape(robot)
    scene = fw.Scene((fw.Box([0.5, 0.0, 0.3], [0.4, 0.8, 0.05]), fw.Capsule([0.0, 0.4, 0.4], 0.05, 0.6, TURNED),
                      fw.Plane([0, 0, 0.02], [0, 0, 1])))
    program = Program(robot, 1.0 * fw.Obstacles(shape, scene, margin=0.05))
    assert _hinge_jacobian_matches_differences(robot, program, rng, 6) > 10


def test_self_collision_jacobian_matches_differences_on_the_mobile_dual_youbot(rng):
    """SPHERES rows (sphere pairs of two bodies) and SOLIDS rows on a frame (arm spheres against the platform's
    box) against central differences (rows away from the hinge's corner; the closest pair switching within ±h
    would show here, and does not on these samples)."""
    robot = fw.load_robot("youbot_dual_mobile")
    shape = fw.RobotShape(robot)
    term = fw.SelfCollision(shape, margin=0.05)
    kinds = {b.kind for b in term.blocks(robot)}
    from framework.costs.sphere_rows import SOLIDS, SPHERES

    assert kinds == {SPHERES, SOLIDS}
    program = Program(robot, 1.0 * term)
    assert _hinge_jacobian_matches_differences(robot, program, rng, 8) > 10


def test_sphere_pair_curvature_matches_differences_on_the_mobile_dual_youbot(rng):
    """μ ∇²r of each violated SPHERES row (the closest pair's distance: the Newton phase's Lagrangian curvature of a
    held contact) against central differences of μ J_row, at random configurations (rows whose closest pair stays
    the same within ±h; a trivial zero curvature misses by the rows' own curvature, ~1/‖v‖ on the Jacobian)."""
    from framework.costs.blocks import CONTACT

    robot = fw.load_robot("youbot_dual_mobile")
    program = Program(robot, 1.0 * fw.SelfCollision(fw.RobotShape(robot), margin=0.05))
    table = program.packed.blocks
    assert set(table["rows"]) == {1} and set(table["level"]) == {1}  # block b is row b
    spheres = table["curvature"] != 0  # SPHERES rows (SOLIDS rows have no curvature kernel)
    assert np.all(table["flags"] & CONTACT) and 0 < spheres.sum() < table.size
    h, compared, largest = 1e-6, 0, 0.0
    for x in robot.random_configurations(rng, 12):
        r, _ = residuals(program, x)
        for b in np.flatnonzero(spheres & (r < -1e-4)):
            mu = rng.standard_normal()
            H = curvature_at(x, program.packed, np.int64(1), np.int64(b), np.int64(b), np.array([mu]))
            plus = [residuals(program, x + e)[1][b] for e in np.eye(robot.n) * h]
            minus = [residuals(program, x - e)[1][b] for e in np.eye(robot.n) * h]
            fd = mu * (np.array(plus) - np.array(minus)) / (2 * h)  # row i: d(J_row)/dx_i
            if np.abs(fd - fd.T).max() > 1e-4:
                continue  # the closest pair switches within ±h: not a smooth row here
            np.testing.assert_allclose(H, fd, atol=1e-5)
            compared += 1
            largest = max(largest, np.abs(fd).max())
    assert compared >= 5 and largest > 1e-2


def test_box_obstacle_solve_matches_a_brute_force_grid(sphere_arm):
    """Motion towards (π/4, π/4) with a box in the way of the forearm sphere: the feasible optimum found by
    the default solver equals the best point of a 601 x 601 grid that keeps the sphere clear (by the box's
    closed-form distance), to the grid's resolution; the unconstrained optimum is infeasible."""
    robot, shape, exact = sphere_arm
    box = fw.Box([0.0, 0.45, 0.0], [0.3, 0.2, 0.3])
    margin = 0.01
    goal = np.array([np.pi / 4, np.pi / 4])
    problem = fw.Problem(robot, fw.Obstacles(shape, [box], margin=margin, cover=exact) + fw.Motion("all", goal))

    def clearance(t1, t2):  # the forearm sphere's centre is at L (cos, sin)(t1 + t2): both joints at the origin
        c = np.stack([L * np.cos(t1 + t2), L * np.sin(t1 + t2), 0 * t1], axis=-1)
        q = np.abs(c - box.center) - box.size / 2
        return np.linalg.norm(np.maximum(q, 0), axis=-1) + np.minimum(q.max(axis=-1), 0)

    grid = np.linspace(-3, 3, 601)
    t1, t2 = np.meshgrid(grid, grid, indexing="ij")
    motion = np.hypot(t1 - goal[0], t2 - goal[1])
    feasible = clearance(t1, t2) >= R + margin
    assert not clearance(*goal) >= R + margin
    best = np.unravel_index(np.argmin(np.where(feasible, motion, np.inf)), motion.shape)
    result = fw.solve(problem, seed=0, tolerance=1e-7)
    assert result.success and result.collisions is not None and not result.collisions.colliding
    assert clearance(*result.configuration) >= R + margin - 1e-6
    assert np.hypot(*(result.configuration - goal)) <= motion[best] + 1e-9
    assert np.hypot(*(result.configuration - goal)) >= motion[best] - 0.015  # the grid's step is 0.01


def test_success_needs_the_exact_check_clear(sphere_arm):
    """A cover of tiny spheres keeps its centres apart but not the real links: the sphere term is met, coal
    finds the contact, and the solve is not a success."""
    robot, shape, _ = sphere_arm
    tiny = SphereCover(np.array([0, 2]), np.array([[L, 0, 0], [L, 0, 0]]), np.array([1e-3, 1e-3]),
                       ("base_0", "fore_0"))
    problem = fw.Problem(robot, fw.SelfCollision(shape, cover=tiny) + fw.Motion("all", [0.05, 0.0]))
    result = fw.solve(problem, seed=0, tolerance=1e-7, initial=np.array([0.05, 0.0]))
    assert result.errors and all(e <= 1e-7 for e in result.errors.values())
    assert result.collisions.colliding and not result.success
    assert {frozenset((c.a, c.b)) for c in result.collisions.contacts} == {frozenset(("base_0", "fore_0"))}
    batch = fw.solve_batch(fw.Problem(robot, fw.SelfCollision(shape, cover=tiny) + fw.Position("fore", [0.1, 0, 0])),
                           [[L * np.cos(0.05), L * np.sin(0.05), 0.0]] * 2, seed=0)
    assert not batch.success.any()


def test_scene_tables_and_their_errors(tmp_path):
    scene = fw.Scene.from_tables([
        {"type": "box", "center": [0.5, 0, 0.3], "size": [0.8, 1.2, 0.05], "rpy": [0, 0, 0.3], "name": "table"},
        {"type": "sphere", "center": [0, 0, 1], "radius": 0.1},
        {"type": "capsule", "center": [0, 0, 1], "radius": 0.1, "length": 0.4, "rotation": [1, 0, 0, 0],
         "quaternion": "wxyz"},
        {"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 2]},
    ])
    assert [o.name for o in scene] == ["table", "sphere", "capsule", "plane"]
    np.testing.assert_allclose(scene.obstacles[0].rotation, pin.rpy.rpyToMatrix(0, 0, 0.3))
    np.testing.assert_allclose(scene.obstacles[3].normal, [0, 0, 1])
    assert scene.solids().shape == (4, 16)
    bad = [
        ({"type": "cube"}, "type must be one of"),
        ({"type": "box", "center": [0, 0, 0]}, "needs size"),
        ({"type": "box", "center": [0, 0, 0], "size": [1, 1, 1], "colour": "red"}, "unknown keys"),
        ({"type": "box", "center": [0, 0, 0], "size": [1, -1, 1]}, "edge lengths > 0"),
        ({"type": "box", "center": [0, 0], "size": [1, 1, 1]}, "center must be 3"),
        ({"type": "box", "center": [0, 0, 0], "size": [1, 1, 1], "rpy": [0, 0, 0], "rotation": [0, 0, 0, 1],
          "quaternion": "xyzw"}, "either rpy or rotation"),
        ({"type": "box", "center": [0, 0, 0], "size": [1, 1, 1], "rotation": [0, 0, 0, 1]}, "name their order"),
        ({"type": "sphere", "center": [0, 0, 0], "radius": 0}, "radius must be"),
        ({"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 0]}, "normal must not be zero"),
        ({"type": "mesh", "path": "missing.stl"}, "does not exist"),
    ]
    for table, message in bad:
        with pytest.raises(TaskError, match=message):
            fw.Scene.from_tables([table])
    with pytest.raises(TaskError, match="must be a Sphere"):
        fw.Scene(("box",))
    same = fw.Scene((fw.Sphere([0, 0, 0], 1), fw.Sphere([1, 0, 0], 1)))
    assert [o.name for o in same] == ["sphere1", "sphere2"]


def test_mesh_obstacle_is_covered_and_checked_exactly(tmp_path, sphere_arm):
    """A mesh obstacle (a box written as STL): its sphere cover holds its surface, and the exact check finds the
    forearm sphere inside it."""
    import trimesh

    from framework.geometry.spheres import surface_points

    path = tmp_path / "block.stl"
    trimesh.creation.box(extents=[0.2, 0.2, 0.2]).export(path)
    mesh = fw.Mesh(path, center=[0.12, L, 0.0], spheres=8)  # a face through the forearm sphere at (0, L) at π/4, π/4
    centers, radii = mesh.cover()
    surface = surface_points(coal.Box(0.2, 0.2, 0.2), 5000, np.random.default_rng(3)) + [0.12, L, 0.0]
    inside = np.min(np.linalg.norm(surface[:, None] - centers[None], axis=2) - radii[None], axis=1)
    assert inside.max() <= 0 and len(radii) <= 8
    robot, shape, _ = sphere_arm
    assert shape.check([np.pi / 4, np.pi / 4], scene=fw.Scene((mesh,)), self_pairs=False).colliding
    assert not shape.check([-np.pi / 4, -np.pi / 4], scene=fw.Scene((mesh,)), self_pairs=False).colliding


def test_obstacles_in_a_task_file(tmp_path, sphere_arm):
    """[[obstacles]] and the collision terms from a task file: the same answer as the same problem in code."""
    robot, shape, _ = sphere_arm
    urdf = tmp_path / "spheres.urdf"
    urdf.write_text(SPHERES)
    (tmp_path / "task.toml").write_text(f"""
[task]
robot = "spheres.urdf"
[[obstacles]]
type = "box"
name = "block"
center = [0.0, 0.45, 0.0]
size = [0.3, 0.2, 0.3]
[[terms]]
type = "obstacles"
margin = 0.01
[[terms]]
type = "self_collision"
[[terms]]
type = "motion"
group = "all"
previous = [{np.pi / 4}, {np.pi / 4}]
""")
    task = load_task(tmp_path / "task.toml")
    problem = task.cases[0].problem
    result = fw.solve(problem, seed=0, tolerance=1e-7)
    assert result.success and not result.collisions.colliding
    world = problem.objective.terms[0][1].cover.world_centers(problem.objective.terms[0][1].shape,
                                                               result.configuration)
    for c, r in zip(world, problem.objective.terms[0][1].cover.radii):
        g = np.empty(3)
        assert solid_distance(*c, fw.Box([0.0, 0.45, 0.0], [0.3, 0.2, 0.3]).solids()[0], 0, g) >= r + 0.01 - 1e-6
    (tmp_path / "bad.toml").write_text("""
[task]
robot = "spheres.urdf"
[[terms]]
type = "obstacles"
""")
    with pytest.raises(TaskError, match="no \\[\\[obstacles\\]\\] entries"):
        load_task(tmp_path / "bad.toml")


def test_task_file_disabled_collisions_and_free_at_reach_the_shape(tmp_path):
    """``[task] disabled_collisions`` and ``free_at`` build the shape a collision term uses as RobotShape's own
    arguments do; malformed values are named."""
    zero = [0.0] * 5
    head = """[task]
robot = "youbot_arm"
{extra}
[[terms]]
type = "self_collision"
"""
    (tmp_path / "task.toml").write_text(head.format(extra=f'disabled_collisions = [["link1_z", "link4_z"]]\nfree_at = {zero}'))
    task = load_task(tmp_path / "task.toml")
    shape = task.cases[0].problem.objective.terms[0][1].shape
    robot = fw.load_robot("youbot_arm")
    reference = fw.RobotShape(robot, disabled=[("link1_z", "link4_z")], free_at=np.clip(zero, robot.lower, robot.upper))
    assert set(shape.pairs) == set(reference.pairs) and shape.unchecked == reference.unchecked
    assert shape.unchecked["disabled"] and shape.unchecked["free_at"]
    for extra, message in (('disabled_collisions = [["link1"]]', "pairs of link names"),
                           ('free_at = ["zero"]', "free_at must be a configuration"),
                           ("free_at = [0.0, 0.0]", "free_at"),
                           ('disabled_collisions = "link1"', "must be a list")):
        (tmp_path / "bad.toml").write_text(head.format(extra=extra))
        with pytest.raises(fw.MetaikError, match=message):
            load_task(tmp_path / "bad.toml").cases[0].problem


def test_recordings_draw_the_obstacles_and_the_spheres(tmp_path, sphere_arm):
    """Every obstacle kind is a static entity of the recording, at its place; the sphere cover is drawn at the
    solution with its radii."""
    import trimesh

    from framework.io.recording import Recorder, read_recording

    robot, shape, exact = sphere_arm
    path = tmp_path / "block.stl"
    trimesh.creation.box(extents=[0.1, 0.1, 0.1]).export(path)
    scene = fw.Scene((fw.Box([0.5, 0.0, 0.3], [0.4, 0.2, 0.1], name="table"), fw.Sphere([0, 0, 1], 0.1),
                      fw.Capsule([0, 1, 0], 0.05, 0.4), fw.Plane([0, 0, -0.1], [0, 0, 1]),
                      fw.Mesh(path, center=[1, 1, 0])))
    x = np.array([0.3, -0.2])
    with Recorder(tmp_path / "scene.rrd", robot) as recorder:
        recorder.log_scene(scene)
        recorder.log_spheres(exact, shape, x)
    rec = read_recording(tmp_path / "scene.rrd")
    _, centres = rec.values("/world/obstacles/table", "Boxes3D:centers")
    np.testing.assert_allclose(np.array(centres[0]).ravel(), [0.5, 0.0, 0.3], atol=1e-6)
    _, halves = rec.values("/world/obstacles/table", "Boxes3D:half_sizes")
    np.testing.assert_allclose(np.array(halves[0]).ravel(), [0.2, 0.1, 0.05], atol=1e-6)
    for entity, component in (("sphere", "Ellipsoids3D:half_sizes"), ("capsule", "Capsules3D:radii"),
                              ("plane", "Boxes3D:half_sizes"), ("mesh/mesh", "Mesh3D:vertex_positions")):
        assert rec.values(f"/world/obstacles/{entity}", component)[1], entity
    _, points = rec.values("/world/spheres", "Points3D:positions", "solution")
    np.testing.assert_allclose(np.array(points[0]), exact.world_centers(shape, x), atol=1e-6)


def test_tracking_paper000_circle_around_a_table():
    """tasks/paper000_circular_table.toml: the table cuts the unconstrained solution at every point (coal), the
    collision-aware run at none, and still follows the path (a few points at the arms' reach give up to 2 mm)."""
    from framework.tracking import track

    results = {}
    for name in ("paper000_circular", "paper000_circular_table"):
        task = load_task(resolve_task(name), points=20)
        case = task.cases[0]
        results[name] = track(task.robot, case.trajectory, case.builder, initial=case.initial, tolerance=1e-6)
    table_task = load_task(resolve_task("paper000_circular_table"), points=20)
    shape = fw.RobotShape(table_task.robot)
    free, safe = results["paper000_circular"], results["paper000_circular_table"]
    assert all(shape.check(q, scene=table_task.scene, self_pairs=False, distances=False).colliding
               for q in free.configurations)
    assert not any(shape.check(q, scene=table_task.scene, distances=False).colliding for q in safe.configurations)
    assert len(safe.configurations) == 20
    assert np.mean(safe.position_error <= 1e-6) >= 0.85 and safe.position_error.max() <= 2e-3


def test_m_fabrik_plans_around_the_shadows_of_the_same_scene():
    """Environment.from_scene: every obstacle's floor shadow contains its exact projection (dense surface
    samples; a ball's and an upright capsule's shadow is their disc, exactly; a prism's its polygon), a floor plane
    casts none, a wall is an error; an Obstacles term's scene is M-FABRIK's and its base stays out of the shadows."""
    import shapely.geometry as sg

    from framework.solvers.fabrik import Environment
    from framework.geometry.spheres import surface_points

    prism = fw.Prism([[1.0, -1.0], [1.4, -1.0], [1.2, -0.6]], height=0.5, bottom=0.1)
    scene = fw.Scene((fw.Box([0.8, 0.2, 0.3], [0.3, 0.4, 0.6], TURNED), fw.Sphere([-0.5, 0.5, 0.2], 0.2),
                      fw.Capsule([0.0, -0.8, 0.3], 0.1, 0.6, TURNED), prism,
                      fw.Capsule([-0.8, -0.8, 0.5], 0.15, 1.0), fw.Plane([0, 0, 0], [0, 0, 1])))
    environment = Environment.from_scene(scene, margin=0.1)
    assert len(environment.obstacles) == 5
    for obstacle, shadow in zip(scene.obstacles[:5], environment.obstacles):
        if obstacle is prism:  # its corners (its surface's convex hull)
            points = prism.vertices()
        else:
            shape, placement = obstacle.coal()
            points = surface_points(shape, 4000, np.random.default_rng(0)) @ placement.rotation.T + placement.translation
        assert max(shadow.distance(p[0], p[1]) for p in points) <= 1e-9
    np.testing.assert_allclose(environment.obstacles[3].vertices, prism.points)  # a prism's shadow is its polygon
    assert environment.obstacles[4].radius == 0.15  # an upright capsule's: its disc
    with pytest.raises(TaskError, match="wall"):
        Environment.from_scene(fw.Scene((fw.Plane([0, 0, 0], [1, 0, 0]),)))
    robot = fw.load_robot("youbot_mobile")
    shape = fw.RobotShape(robot)
    box = fw.Box([0.6, 0.0, 0.3], [0.3, 0.3, 0.6])
    footprint = sg.box(0.45, -0.15, 0.75, 0.15)
    rng = np.random.default_rng(0)
    targets = robot.frame_poses(robot.random_configurations(rng, 20), "arm_ee").positions[:, 0]
    reached = 0
    for target in targets:
        problem = fw.Problem(robot, fw.Position("arm_ee", target) + fw.Obstacles(shape, [box]))
        result = fw.solve(problem, "mfabrik", initial=robot.random_configurations(rng, 1)[0], seed=0)
        x, y = result.configuration[:2]
        assert footprint.distance(sg.Point(x, y)) >= 0.2 - 1e-6 or result.settings["reason"].startswith("unreachable")
        reached += result.errors["position[arm_ee]"] <= 1e-6
    assert reached >= 15


def test_frames_added_by_a_collision_term_after_a_drawing_was_made():
    """A drawing made first, a collision term adding its body frames to the model after: the drawing still poses
    every frame (Pinocchio sizes its Data once; writing past it corrupted memory)."""
    from framework.viz.drawing import RobotDrawing

    robot = fw.load_robot("youbot_dual")
    drawing = RobotDrawing(robot)
    before = robot.model.nframes
    fw.Problem(robot, fw.SelfCollision(fw.RobotShape(robot))).program  # noqa: B018 - packs: adds frames
    assert robot.model.nframes > before
    M = drawing.world_frames(robot.middle)
    assert M.shape[1] == robot.model.nframes
    np.testing.assert_allclose(M[0, robot.frame_id("arm1_ee")], robot.frame_placement(robot.middle, "arm1_ee").homogeneous)


def _pr2_with_srdf(erd) -> tuple[fw.Robot, fw.RobotShape]:
    joints = ["torso_lift_joint"] + [f"{side}_{name}_joint" for side in "lr" for name in
                                     ("shoulder_pan", "shoulder_lift", "upper_arm_roll", "elbow_flex", "forearm_roll",
                                      "wrist_flex", "wrist_roll")]
    robot = fw.load_robot(erd / "pr2_description" / "urdf" / "pr2.urdf", joints=joints)
    return robot, fw.RobotShape(robot, srdf=erd / "pr2_description" / "srdf" / "pr2.srdf")


@pytest.mark.parametrize("name", ["youbot_dual", "pr2"])
def test_population_values_equal_a_direct_computation(name, rng, request):
    """The self-collision and obstacle terms' values over a population equal a numpy computation from Pinocchio's
    sphere centres: per pair of bodies the most negative of (centre distance − radii − margin) over every sphere
    pair of their checked geometry pairs, summed as |min(0, ·)|; per body and obstacle the same with the box's
    closed-form signed distance. The compiled rows skip bodies and spheres by bounding spheres and list a body
    pair's spheres once with a mask of the checked pairs (youbot_dual has such masked pairs, PR2's 612 spheres
    make the pruning count); none of it may change a value."""
    if name == "pr2":
        robot, shape = _pr2_with_srdf(request.getfixturevalue("erd"))
    else:
        robot = fw.load_robot(name)
        shape = fw.RobotShape(robot)
    from framework.costs.sphere_rows import CLEARANCE

    cover = shape.cover()
    given = 0.01
    margin = given + CLEARANCE  # the rows hold this much beyond the margin given
    box = fw.Box([0.3, 0.0, 0.35], [0.3, 0.6, 0.1])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # PR2's shoulder pans: left to the exact check
        self_term = fw.SelfCollision(shape, margin=given)
        values = fw.Problem(robot, self_term + fw.Obstacles(shape, [box], margin=given)).values(
            X := robot.random_configurations(rng, 40))
    skipped = shape.inseparable(cover)
    index = {name: [k for k, g in enumerate(cover.geometries) if g == name] for name in set(cover.geometries)}
    solids = shape.solids()
    for m, x in enumerate(X):
        C = cover.world_centers(shape, x)
        worst: dict[tuple, float] = {}
        data = robot.model.createData()
        pin.forwardKinematics(robot.model, data, robot.to_pinocchio(x))
        for a, b in shape.pairs:
            if (a, b) in skipped:
                continue
            if a in solids and (b not in solids or solids[a][3] > solids[b][3]):
                a, b = b, a
            if b in solids:  # a link's own box: a's spheres against it, in its frame, one row per (box, body)
                joint, placement, solid, _ = solids[b]
                frame = data.oMi[joint] * placement
                d = min(solid_distance(*frame.actInv(C[i]), solid, 0, np.empty(3)) - cover.radii[i] - margin
                        for i in index[a])
                key = (b, int(cover.joints[index[a][0]]))
                worst[key] = min(worst.get(key, np.inf), d)
                continue
            D = np.linalg.norm(C[index[a]][:, None] - C[index[b]][None], axis=2) \
                - cover.radii[index[a]][:, None] - cover.radii[index[b]][None] - margin
            key = tuple(sorted((int(cover.joints[index[a][0]]), int(cover.joints[index[b][0]]))))
            worst[key] = min(worst.get(key, np.inf), D.min())
        expected_self = sum(-min(0.0, d) for d in worst.values())
        q = np.abs(C - box.center) - box.size / 2
        sd = np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(axis=1), 0) - cover.radii - margin
        moving = cover.joints != 0
        expected_box = sum(-min(0.0, sd[moving & (cover.joints == j)].min()) for j in set(cover.joints[moving]))
        assert values[m, 0] == pytest.approx(expected_self, abs=1e-12)
        assert values[m, 1] == pytest.approx(expected_box, abs=1e-12)
    assert (values[:, 0] > 0).sum() >= 5 and (values[:, 1] > 0).sum() >= 5  # both terms active on some members


def test_jacobians_from_kept_poses_equal_a_full_linearization(rng):
    """The engine's accepted-step path (poses and residuals first, then Jacobians from the kept poses, where
    clear hinge rows keep a zero Jacobian without a second evaluation) gives the rows and Jacobian of one full
    call, on configurations with both clear and active collision rows."""
    from framework.costs.kernels import COMPUTE, JACOBIANS_FROM_POSES, NO, TASK, YES

    robot = fw.load_robot("youbot_dual_mobile")
    shape = fw.RobotShape(robot)
    objective = fw.Position("arm1_ee", [0.5, 0.1, 0.4]) + fw.SelfCollision(shape, margin=0.02) \
        + fw.Obstacles(shape, [fw.Box([0.4, 0.0, 0.3], [0.3, 0.6, 0.05])], margin=0.02)
    program = fw.Problem(robot, objective).program
    n = robot.n
    active = clear = 0
    FULL, KEPT = 0, 1
    for x in robot.random_configurations(rng, 30):
        owners, records = make_workspaces(program.packed, n, 2)
        m = linearize_in(records, FULL, x, TASK, YES, COMPUTE)
        linearize_in(records, KEPT, x, TASK, NO, COMPUTE)
        set_jacobian_rows(records, KEPT, np.nan)  # nothing of a previous Jacobian may survive
        assert linearize_in(records, KEPT, x, TASK, YES, JACOBIANS_FROM_POSES) == m
        (r_full, J_full, *_), (r_kept, J_kept, *_) = rows_in(records, FULL, m), rows_in(records, KEPT, m)
        np.testing.assert_array_equal(r_kept, r_full)
        np.testing.assert_array_equal(J_kept, J_full)
        active += int((r_full[3:] != 0).sum())
        clear += int((r_full[3:] == 0).sum())
    assert active >= 10 and clear >= 100
