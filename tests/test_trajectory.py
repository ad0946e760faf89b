"""Trajectories as data: the papers' formulas, composition, files, and bad input."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import framework as fw
from framework.tracking import paths
from framework.tracking import trajectory as tr
from framework.tracking.trajectory import Trajectory


def test_paper000_paths_match_their_formulas():
    K = 200
    s = paths.paper000("sinusoidal", K)
    y = np.linspace(-0.25, 0.75, K)
    np.testing.assert_allclose(
        s.positions, np.c_[np.full(K, 0.5), y, 0.4 + 0.05 * np.sin(30 * y)], atol=1e-15
    )

    c = paths.paper000("circular", K)
    th = np.linspace(0, 2 * np.pi, K)
    np.testing.assert_allclose(
        c.positions, np.c_[np.full(K, 0.5), 0.25 + 0.05 * np.cos(th), 0.45 + 0.05 * np.sin(th)], atol=1e-15
    )

    t = paths.paper000("trapezoidal", K)
    r = 0.45 + 0.1 * np.sin(30 * y)
    z = np.where(r > 0.5, 0.5, np.where(r < 0.4, 0.4, r))
    np.testing.assert_allclose(t.positions, np.c_[np.full(K, 0.5), y, z], atol=1e-15)

    rose = paths.paper000("rose", K)
    rr = 0.035 + 0.015 * np.cos(3 * th)
    np.testing.assert_allclose(
        rose.positions, np.c_[np.full(K, 0.5), 0.25 + rr * np.cos(th), 0.35 + rr * np.sin(th)], atol=1e-15
    )
    assert all(p.K == K and not p.has_orientation for p in (s, c, t, rose))
    with pytest.raises(fw.TaskError, match="paper 000 has no path"):
        paths.paper000("spiral")


def test_paper002_paths_carry_ry_half_pi_and_the_lemniscate_is_bernoulli():
    circle = paths.paper002("puma560", "circle", 32)
    centre, radius = np.array([0.5, 0.0, 0.4]), 0.3
    np.testing.assert_allclose(np.linalg.norm(circle.positions - centre, axis=1), radius, atol=1e-15)
    np.testing.assert_allclose(circle.positions[:, 0], 0.5)  # in the plane x = C_x
    np.testing.assert_allclose(circle.rotations, np.broadcast_to(tr.Ry(np.pi / 2), (32, 3, 3)))
    np.testing.assert_allclose(tr.Ry(np.pi / 2) @ [0, 0, 1], [1, 0, 0], atol=1e-15)  # tool z along world x

    lem = paths.paper002("fanuc_am120ib", "lemniscate", 73)
    a = 0.5
    u, v = lem.positions[:, 1] - 0.0, lem.positions[:, 2] - 0.25
    # Bernoulli: (u² + v²)² = a² (u² − v²), through the centre, half-width a
    np.testing.assert_allclose((u**2 + v**2) ** 2, a**2 * (u**2 - v**2), atol=1e-14)
    assert np.max(np.abs(u)) == pytest.approx(a) and lem.K == 73
    with pytest.raises(fw.TaskError):
        paths.paper002("youbot_arm", "square")


def test_generic_shapes():
    c = paths.circle((1, 2, 3), 0.5, 9, plane="xy", start_angle=np.pi / 2)
    np.testing.assert_allclose(c.positions[0], [1, 2.5, 3], atol=1e-15)
    np.testing.assert_allclose(c.positions[-1], c.positions[0], atol=1e-15)  # closed: θ ∈ [0, 2π] inclusive
    ln = paths.line((0, 0, 0), (1, 0, 0), 11)
    np.testing.assert_allclose(ln.spacing, 0.1)
    assert ln.length == pytest.approx(1.0)
    wave = paths.sinusoid((0, 0, 0), (1, 0, 0), 0.1, 2 * np.pi, 101, saturation=0.05)
    assert wave.positions[:, 2].max() == pytest.approx(0.05) and wave.positions[:, 2].min() == pytest.approx(
        -0.05
    )
    tilted = paths.circle((0, 0, 0), 1.0, 5, plane=((1, 0, 0), (0, np.sqrt(0.5), np.sqrt(0.5))))
    np.testing.assert_allclose(tilted.positions[1], [0, np.sqrt(0.5), np.sqrt(0.5)], atol=1e-15)


def test_composition():
    circle = paths.circle((0.5, 0.25, 0.45), 0.05, 20)
    approach = paths.line((0.5, 0.25, 0.3), circle.positions[0], 5)
    path = approach.then(circle)
    assert path.K == 5 + 20 - 1  # the shared junction waypoint is kept once
    np.testing.assert_allclose(
        path.offset((0, 0, 0.1)).positions - path.positions, np.tile([0, 0, 0.1], (24, 1))
    )
    np.testing.assert_allclose(path.reversed().positions[0], path.positions[-1])
    assert path[::2].K == 12 and path[3].K == 1
    oriented = path.with_orientation(tr.Rz(0.3))
    moved = oriented.transformed(tr.Rz(np.pi / 2), (1, 0, 0))
    np.testing.assert_allclose(moved.positions[0], tr.Rz(np.pi / 2) @ path.positions[0] + [1, 0, 0])
    np.testing.assert_allclose(moved.rotations[0], tr.Rz(np.pi / 2 + 0.3), atol=1e-15)
    with pytest.raises(fw.TaskError, match="with and without orientation"):
        tr.concatenate(oriented, circle)


@pytest.mark.parametrize("suffix", [".csv", ".npy", ".npz"])
@pytest.mark.parametrize("oriented", [False, True])
def test_file_round_trip(tmp_path, suffix, oriented):
    path = paths.lemniscate(
        (0.6, 0.6, 0.5), 0.3, 17, orientation=tr.Ry(np.pi / 2) @ tr.Rx(0.2) if oriented else None
    )
    file = tmp_path / f"path{suffix}"
    path.save(file)
    back = Trajectory.from_file(file)
    np.testing.assert_allclose(back.positions, path.positions, rtol=0, atol=1e-15)
    assert back.has_orientation == oriented
    if oriented:
        np.testing.assert_allclose(back.rotations, path.rotations, atol=1e-14)


def test_csv_without_header_and_with_comments(tmp_path):
    file = tmp_path / "user.csv"
    file.write_text("# my path\n0.1,0.2,0.3\n0.2,0.2,0.3\n")
    assert Trajectory.from_file(file).K == 2


@pytest.mark.parametrize(
    ("positions", "match"),
    [
        (np.array([[0.0, 0.0, np.nan]]), "NaN"),
        (np.zeros((4, 2)), "shape"),
        (np.zeros(3), "shape"),
        (np.zeros((0, 3)), "shape"),
    ],
)
def test_bad_positions_raise_task_error(positions, match):
    with pytest.raises(fw.TaskError, match=match):
        Trajectory(positions)


def test_bad_rotations_and_files_raise_task_error(tmp_path):
    with pytest.raises(fw.TaskError, match="not rotation matrices"):
        Trajectory(np.zeros((2, 3)), np.tile(2 * np.eye(3), (2, 1, 1)))
    with pytest.raises(fw.TaskError, match="shape"):
        Trajectory(np.zeros((2, 3)), np.zeros((3, 3, 3)))
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y,z\n0,0,nan\n")
    with pytest.raises(fw.TaskError, match="NaN"):
        Trajectory.from_file(bad)
    bad.write_text("x,y\n0,0\n")
    with pytest.raises(fw.TaskError, match="shape"):
        Trajectory.from_file(bad)
    bad.write_text("a,b,c\n0,0,0\n")
    with pytest.raises(fw.TaskError, match="header"):
        Trajectory.from_file(bad)
    bad.write_text("0,0,0\n1,1\n")
    with pytest.raises(fw.TaskError, match="columns"):
        Trajectory.from_file(bad)
    with pytest.raises(fw.TaskError, match="does not exist"):
        Trajectory.from_file(tmp_path / "missing.csv")
    with pytest.raises(fw.TaskError, match="points"):
        paths.circle((0, 0, 0), 1.0, 1)
    with pytest.raises(fw.TaskError, match="radius"):
        paths.circle((0, 0, 0), -1.0, 10)


def test_trajectories_are_immutable():
    path = paths.circle((0, 0, 0), 1.0, 5)
    with pytest.raises(ValueError):
        path.positions[0, 0] = 1.0


@settings(max_examples=30, deadline=None)
@given(
    st.lists(st.tuples(*(st.floats(-2, 2, allow_nan=False) for _ in range(3))), min_size=1, max_size=20),
    st.tuples(*(st.floats(-1, 1, allow_nan=False) for _ in range(3))),
)
def test_offset_then_back_is_identity(points, delta):
    path = Trajectory(np.array(points))
    np.testing.assert_allclose(
        path.offset(delta).offset(-np.array(delta)).positions, path.positions, atol=1e-12
    )
