"""Capability maps and base placement, checked against brute force: dense FK sampling, pinned-base solves, FK."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import framework as fw
from framework.errors import ConfigurationError, TaskError
from framework.solvers.settings import MAPS
from framework.reach.capability import (ReachabilityMap, base_placements, manipulability,
                                    reachability_map, sample_rotations)


@pytest.fixture(scope="module")
def arm():
    return fw.load_robot("youbot_arm")


@pytest.fixture(scope="module")
def position_map(arm):
    return reachability_map(arm, "ee", voxel=0.08, box=([-0.6, -0.6, -0.2], [0.6, 0.6, 0.6]))


def test_position_map_against_dense_fk_sampling(arm, position_map):
    m = position_map
    # every voxel the map reaches: its solution's FK (Pinocchio) is at the centre (within the map's tolerance)
    assert m.reached.any() and not m.reached.all()
    # brute force: 200,000 random configurations; a centre within 5 mm of an FK sample is reachable
    X = arm.random_configurations(np.random.default_rng(1), 200_000)
    points = arm.frame_poses(X, "ee").positions[:, 0]
    from scipy.spatial import cKDTree

    distance, _ = cKDTree(points).query(m.centers)
    reachable = distance <= 0.005
    unreachable = distance >= 0.05  # 5 cm from every sample: no configuration gets there
    assert reachable.sum() >= 50
    assert m.reached[reachable, 0].mean() >= 0.95  # a trivial "nothing reaches" map scores 0 here
    assert not m.reached[unreachable, 0].any()
    # a centre 5 mm from a sample may still lie just outside the workspace: each one the map misses is missed
    # by a thorough solve too (the hybrid, 20x the map's iterations, then its global phase)
    for c in m.centers[reachable & ~m.reached[:, 0]]:
        thorough = fw.solve(fw.Problem(arm, fw.Position("ee", c)), tolerance=MAPS.tolerance, max_iterations=6000)
        assert not thorough.success, c


def test_map_solutions_hold_by_fk_and_manipulability_by_pinocchio(arm):
    m = reachability_map(arm, "ee", voxel=0.2, box=([-0.4, -0.4, 0.0], [0.4, 0.4, 0.4]))
    problem = fw.Problem(arm, fw.Position("ee", m.centers[0]))
    batch = fw.solve_batch(problem, m.centers, "multistart_lm", tolerance=MAPS.tolerance, max_iterations=300)
    np.testing.assert_array_equal(batch.success, m.reached[:, 0])
    for x, c in zip(batch.configurations[batch.success], m.centers[batch.success]):
        assert np.linalg.norm(arm.frame_placement(x, "ee").translation - c) <= MAPS.tolerance
    x = batch.configurations[batch.success][0]
    data = arm.model.createData()
    J = pin.computeFrameJacobian(arm.model, data, arm.to_pinocchio(x[None])[0], arm.model.getFrameId("ee"),
                                 pin.LOCAL_WORLD_ALIGNED)[:3]
    assert manipulability(arm, x[None], "ee", slice(0, 3))[0] == pytest.approx(np.sqrt(np.linalg.det(J @ J.T)),
                                                                               rel=1e-9)


def test_orientation_map_of_a_six_axis_arm_and_files(tmp_path):
    puma = fw.load_robot("puma560")
    m = reachability_map(puma, "ee", voxel=0.25, orientations=6, box=([-0.5, -0.5, 0.0], [0.5, 0.5, 0.5]))
    assert m.reached.shape == (len(m.centers), 6)
    assert 0 < m.fraction.mean() < 1
    R = sample_rotations(500, seed=3)
    np.testing.assert_allclose(R @ R.transpose(0, 2, 1), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)
    assert abs(R[:, 2, 2].mean()) < 0.1  # uniform on SO(3): E[R33] = 0
    back = ReachabilityMap.load(m.save(tmp_path / "map.npz"))
    np.testing.assert_array_equal(back.reached, m.reached)
    assert back.shape == m.shape and back.frame == "ee"
    assert m.slice_png(tmp_path / "slice.png").stat().st_size > 5_000


def test_base_placement_against_pinned_base_solves():
    robot = fw.load_robot("youbot_dual_mobile")
    targets = {"arm1_ee": np.array([1.0, 0.5, 0.35]), "arm2_ee": np.array([1.0, 0.75, 0.35])}
    placements = base_placements(robot, targets, radius=0.5, step=0.25, headings=4)
    assert placements.reached.any() and not placements.reached.all()
    # every reaching candidate: the whole robot's configuration (base included) reaches both targets by FK
    for k in np.flatnonzero(placements.reached):
        x = placements.configurations[k]
        np.testing.assert_allclose(x[placements.base], placements.candidates[k])
        for frame, target in targets.items():
            assert np.linalg.norm(robot.frame_placement(x, frame).translation - target) <= MAPS.tolerance
    # brute force: the whole robot with its base pinned at each candidate, world targets, no transform, a
    # thorough solve (the hybrid: 5000 iterations, then its global phase)
    agree = 0
    for k, (x, y, theta) in enumerate(placements.candidates):
        pinned = robot.with_bounds({"base_x": (x - 1e-12, x + 1e-12), "base_y": (y - 1e-12, y + 1e-12),
                                    "base_theta": (theta - 1e-12, theta + 1e-12)})
        problem = fw.Problem(pinned, fw.Position("arm1_ee", targets["arm1_ee"])
                             + fw.Position("arm2_ee", targets["arm2_ee"]))
        result = fw.solve(problem, seed=k, tolerance=MAPS.tolerance, max_iterations=5000)
        agree += result.success == placements.reached[k]
    share = placements.reached.mean()
    assert agree / len(placements.candidates) >= 0.95 > max(share, 1 - share)  # beats a constant answer
    best, x = placements.best
    assert placements.score[placements.ranking[0]] == placements.score[placements.reached].max()


def test_base_placement_errors():
    with pytest.raises(ConfigurationError, match="no group 'base'"):
        base_placements(fw.load_robot("youbot_arm"), {"ee": [0.3, 0, 0.2]})
    robot = fw.load_robot("youbot_dual_mobile")
    with pytest.raises(TaskError, match="at least one hand"):
        base_placements(robot, {})
    far = base_placements(robot, {"arm1_ee": [0.0, 0.0, 3.0]}, radius=0.2, step=0.2, headings=2)
    with pytest.raises(TaskError, match="no candidate base pose reaches"):
        far.best


def test_reach_command(tmp_path, capsys):
    from framework.cli import EXIT_INPUT, EXIT_OK, main

    out, png, rrd = tmp_path / "map.npz", tmp_path / "slice.png", tmp_path / "map.rrd"
    assert main(["reach", "youbot_arm", "--voxel", "0.15", "--out", str(out), "--png", str(png), "--record",
                 str(rrd), "--no-progress"]) == EXIT_OK
    saved = ReachabilityMap.load(out)
    direct = reachability_map(fw.load_robot("youbot_arm"), "ee", voxel=0.15)
    np.testing.assert_array_equal(saved.reached, direct.reached)
    assert png.stat().st_size > 5_000 and rrd.stat().st_size > 1_000
    assert main(["reach", "youbot_arm", "--voxel", "0.15", "--self-collision", "--out", str(out),
                 "--no-progress"]) == EXIT_OK
    assert "clear of itself" in capsys.readouterr().out
    robot = fw.load_robot("youbot_arm")
    clear = reachability_map(robot, "ee", voxel=0.15, collisions=fw.SelfCollision(fw.RobotShape(robot)))
    loaded = ReachabilityMap.load(out)
    np.testing.assert_array_equal(loaded.reached, clear.reached)
    assert loaded.clear_of == ("self_collision",) and direct.clear_of == ()
    assert clear.reached.sum() < direct.reached.sum()
    assert main(["reach", "youbot_dual_mobile", "--place", "arm1_ee=1,0.5,0.35", "--place", "arm2_ee=1,0.75,0.35",
                 "--radius", "0.3", "--step", "0.15", "--headings", "4", "--no-progress"]) == EXIT_OK
    assert "reach every target" in capsys.readouterr().out
    assert main(["reach", "youbot_dual_mobile", "--place", "arm1_ee=1,0.5"]) == EXIT_INPUT
    assert "FRAME=X,Y,Z" in capsys.readouterr().err


def test_placement_task_file_runs_and_records(tmp_path, capsys):
    from framework.cli import EXIT_INPUT, EXIT_OK, main
    from framework.io.placement import PlacementTask
    from framework.io.recording import read_recording
    from framework.io.taskfile import load_task, resolve_task

    task = load_task(resolve_task("youbot_dual_base_placement"))
    assert isinstance(task, PlacementTask) and set(task.targets) == {"arm1_ee", "arm2_ee"}
    rrd = tmp_path / "placed.rrd"
    assert main(["run", "youbot_dual_base_placement", "--record", str(rrd), "--no-progress"]) == EXIT_OK
    out = capsys.readouterr().out
    assert "success True" in out and "position[arm1_ee]" in out
    assert read_recording(rrd).count("/world/robot/skeleton", "solution") == 1
    bad = tmp_path / "bad.toml"
    bad.write_text('[task]\nrobot = "youbot_dual_mobile"\n[placement]\nradius = 0.5\nstpe = 0.1\n'
                   '[placement.targets]\narm1_ee = [1, 0.5, 0.3]\n')
    assert main(["run", str(bad)]) == EXIT_INPUT
    assert "unknown keys ['stpe']" in capsys.readouterr().err
    bad.write_text('[task]\nrobot = "youbot_dual_mobile"\n[placement]\n[placement.targets]\nhand = [1, 0.5, 0.3]\n')
    assert main(["run", str(bad)]) == EXIT_INPUT
    assert "hand" in capsys.readouterr().err


def test_a_map_with_self_collision_reaches_only_where_a_configuration_is_clear(arm):
    """Brute force: 40,000 random configurations checked by coal; a voxel centre within 1 cm of a collision-free
    sample's hand is reached (a map reaching nothing scores 0), one 5 cm or more from every collision-free sample
    is not — and the map without the term reaches some of those (one ignoring the term fails here)."""
    from scipy.spatial import cKDTree

    shape = fw.RobotShape(arm)
    box = ([-0.6, -0.6, -0.2], [0.6, 0.6, 0.6])
    plain = reachability_map(arm, "ee", voxel=0.1, box=box)
    clear = reachability_map(arm, "ee", voxel=0.1, box=box, collisions=fw.SelfCollision(shape))
    X = arm.random_configurations(np.random.default_rng(1), 40_000)
    free = np.array([not shape.check(x, distances=False).colliding for x in X])
    distance, _ = cKDTree(arm.frame_poses(X[free], "ee").positions[:, 0]).query(clear.centers)
    near, far = distance <= 0.01, distance >= 0.05
    assert near.sum() >= 30
    assert clear.reached[near, 0].mean() >= 0.9
    assert not clear.reached[far, 0].any()
    assert plain.reached[far, 0].sum() >= 10  # reachable in contact only: the term is what leaves them out
    with pytest.raises(TaskError, match="collision terms"):
        reachability_map(arm, "ee", voxel=0.2, collisions=fw.Position("ee", [0.0, 0.0, 0.3]))
