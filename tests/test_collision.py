"""Collision checks on the exact geometry: distances against a closed form (two spheres on a two-joint arm),
pairs (adjacent bodies and bodies fixed to each other excluded, SRDF pairs removed) and real robots."""

from __future__ import annotations

import re

import numpy as np
import pytest

import framework as fw
from framework.geometry.collision import RobotShape
from framework.errors import RobotFileError

R, L = 0.1, 0.3
SPHERES = f"""<robot name="spheres">
  <link name="base"><collision><origin xyz="{L} 0 0"/><geometry><sphere radius="{R}"/></geometry></collision></link>
  <link name="upper"/>
  <link name="fore"><collision><origin xyz="{L} 0 0"/><geometry><sphere radius="{R}"/></geometry></collision></link>
  <link name="cap"><collision><geometry><sphere radius="0.01"/></geometry></collision></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="fixed" type="fixed"><parent link="fore"/><child link="cap"/></joint>
</robot>"""


def test_sphere_distances_equal_the_closed_form():
    """The forearm's sphere turns about z at L from the axis; the base's sits at L: distance
    2 L |sin((θ1 + θ2)/2)| − 2R, contacts exactly when that is negative."""
    robot = fw.robot_from_urdf(SPHERES)
    shape = RobotShape(robot)
    assert shape.pairs == (("base_0", "fore_0"), ("base_0", "cap_0"))
    for theta in np.linspace(-2.9, 2.9, 41):
        x = np.array([theta / 2, theta / 2])
        expected = 2 * L * abs(np.sin(theta / 2)) - 2 * R
        report = shape.check(x)
        distances = {frozenset((c.a, c.b)): c.distance for c in shape.check(x, margin=10.0).contacts}
        assert distances[frozenset(("base_0", "fore_0"))] == pytest.approx(expected, abs=1e-9)
        assert report.colliding == (expected < 0)


def test_pairs_leave_out_adjacent_and_fixed_together_bodies():
    robot = fw.robot_from_urdf(SPHERES)
    pairs = {frozenset(p) for p in RobotShape(robot).pairs}
    assert frozenset(("fore_0", "cap_0")) not in pairs  # the same body (a fixed joint between them)
    assert frozenset(("base_0", "fore_0")) in pairs  # two joints apart
    locked = fw.robot_from_urdf(SPHERES, locked={"elbow": 0.0})
    assert {frozenset(p) for p in RobotShape(locked).pairs} == set()  # base and fore: one joint apart now


def test_panda_srdf_pairs_are_not_checked(erd):
    path = erd / "panda_description" / "urdf" / "panda.urdf"
    srdf = erd / "panda_description" / "srdf" / "panda.srdf"
    robot = fw.load_robot(path)
    every = RobotShape(robot)
    reduced = RobotShape(robot, srdf=srdf)
    disabled = {frozenset(m) for m in re.findall(r'link1="([^"]+)"\s+link2="([^"]+)"', srdf.read_text())}
    link = {g.name: robot.model.frames[g.parentFrame].name for g in reduced.geometry.geometryObjects}
    assert len(reduced.pairs) < len(every.pairs)
    assert not [p for p in reduced.pairs if frozenset((link[p[0]], link[p[1]])) in disabled]
    assert not reduced.check(robot.middle).colliding
    with pytest.raises(RobotFileError, match="SRDF"):
        RobotShape(robot, srdf=path.parent / "none.srdf")


def test_panda_pairs_disabled_in_code_equal_its_srdf(erd):
    """``disabled=`` link pairs leave out exactly what an SRDF listing them does."""
    path = erd / "panda_description" / "urdf" / "panda.urdf"
    srdf = erd / "panda_description" / "srdf" / "panda.srdf"
    robot = fw.load_robot(path)
    listed = re.findall(r'link1="([^"]+)"\s+link2="([^"]+)"', srdf.read_text())
    in_code = RobotShape(robot, disabled=listed)
    assert set(in_code.pairs) == set(RobotShape(robot, srdf=srdf).pairs)
    assert len(in_code.unchecked["disabled"]) == len(RobotShape(robot).pairs) - len(in_code.pairs) > 0
    with pytest.raises(fw.UnknownFrameError, match="did you mean 'panda_link5'"):
        RobotShape(robot, disabled=[("panda_link1", "panda_link_5")])
    with pytest.raises(fw.TaskError, match="two link names"):
        RobotShape(robot, disabled=[("panda_link1",)])


def test_pairs_in_contact_where_the_robot_is_declared_free_are_not_checked():
    """The DH youBot arm's zero pose is folded: its link 3 and link 5 spheres overlap there (kept by default: a
    real contact). ``free_at=zero`` leaves out exactly the pairs Pinocchio's own collision pass finds in contact at
    zero, and nothing else; the check then finds zero clear."""
    import pinocchio as pin

    robot = fw.load_robot("youbot_arm")
    zero = np.clip(np.zeros(robot.n), robot.lower, robot.upper)
    every = RobotShape(robot)
    assert every.check(zero).colliding and "free_at" not in every.unchecked
    geometry, data = every.geometry, every.geometry.createData()
    pin.computeCollisions(robot.model, robot.model.createData(), geometry, data, robot.to_pinocchio(zero), False)
    objects = geometry.geometryObjects
    touching = {(objects[p.first].name, objects[p.second].name)
                for p, result in zip(geometry.collisionPairs, data.collisionResults) if result.isCollision()}
    declared = RobotShape(robot, free_at=zero)
    assert set(declared.unchecked["free_at"]) == touching and touching
    assert set(declared.pairs) == set(every.pairs) - touching
    assert not declared.check(zero).colliding
    assert not RobotShape(robot, free_at=np.stack([zero, robot.middle])).check(robot.middle).colliding


def test_no_collision_geometry_is_our_error():
    bare = re.sub(r"<collision>.*?</collision>", "", SPHERES, flags=re.S)
    with pytest.raises(RobotFileError, match="no <collision>"):
        RobotShape(fw.robot_from_urdf(bare))


@pytest.mark.parametrize("name", ["youbot_dual_mobile", "baxter_dual", "puma_scara", "stanford_dual"])
def test_dh_robots_have_spheres_along_their_links(name):
    """The generated URDFs' collision spheres cover each DH link's path — from the joint along z by d, then
    along x by a, to the next DH frame (Pinocchio's frame placement) — at most one radius apart, so every point of
    the path is within r/2 of a sphere centre (the union holds a capsule of radius r√3/2 around it)."""
    import pinocchio as pin

    robot = fw.load_robot(name)
    shape = RobotShape(robot)
    model, data = robot.model, robot.model.createData()
    gdata = shape.geometry.createData()
    pin.forwardKinematics(model, data, robot.to_pinocchio(robot.middle))
    pin.updateGeometryPlacements(model, data, shape.geometry, gdata)
    spheres = [(m.translation, o.geometry.radius) for m, o in zip(gdata.oMg, shape.geometry.geometryObjects)
               if o.geometry.__class__.__name__ == "Sphere"]
    centres, radii = np.array([c for c, _ in spheres]), np.array([r for _, r in spheres])
    checked = 0
    for frame in model.frames:
        joint = frame.parentJoint
        if not re.fullmatch(r".*link\d+", frame.name) or not model.names[joint].split("_")[-1].startswith("joint"):
            continue
        a, _, d = frame.placement.translation
        path = [(0, 0, t * d) for t in np.linspace(0, 1, 20)] + [(t * a, 0, d) for t in np.linspace(0, 1, 20)]
        for p in path:
            world = data.oMi[joint].act(np.array(p, dtype=float))
            gaps = np.linalg.norm(centres - world, axis=1)
            assert np.min(gaps - radii / 2) <= 1e-9, (frame.name, p)
        checked += 1
    assert checked >= 8
