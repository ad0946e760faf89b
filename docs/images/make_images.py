"""Draw the README pictures: paper 000's sinusoidal path tracked by the mobile dual-arm youBot.

python docs/images/make_images.py      # writes tracking_mobile_dual_youbot.png (and, with Chromium,
                                        # meshcat_mobile_dual_youbot.png)
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

import framework as fw
from framework.tracking import TrackingTask, track
from framework.trajectory import paper000
from framework.drawing import RobotDrawing
from framework.viewer import Viewer, find_chromium, screenshot

HERE = Path(__file__).parent


def main() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    robot = fw.load_robot("youbot_dual_mobile")
    q_prev = robot.middle.copy()
    q_prev[robot.group("base")] = [0.0, 0.0, np.pi / 2]
    q_prev[robot.group("arm1")] = [-np.pi / 2, np.pi / 2, -np.pi / 4, np.pi / 4, 0.0]
    q_prev[robot.group("arm2")] = [np.pi / 2, np.pi / 2, -np.pi / 4, np.pi / 4, 0.0]
    path = paper000("sinusoidal")
    task = TrackingTask(
        frame="arm1_ee",
        follower="arm2_ee",
        offset=(0.25, 0.0, 0.0),
        position_weight=1.2,
        motion={"base": 0.1, "arm1": 0.4, "arm2": 0.4},
    )
    result = track(robot, path, task, solver="hybrid", initial=q_prev, progress=False)

    tracked = result.frame_positions(robot, ["arm1_ee", "arm2_ee"])
    drawing = RobotDrawing(robot)
    fig = plt.figure(figsize=(7.5, 5.2))
    ax = fig.add_subplot(projection="3d")
    drawn = [tracked.reshape(-1, 3)]
    for k in (0, 66, 133, 199):
        segments = drawing.segments(drawing.world_frames(result.configurations[k]))[0]
        for a, b in segments:
            ax.plot(*np.c_[a, b], color="tab:orange", alpha=0.3 + 0.6 * k / 199, lw=2)
        drawn.append(segments.reshape(-1, 3))
    for desired in (path.positions, path.positions + task.offset):
        ax.plot(*desired.T, color="tab:blue", lw=5, alpha=0.3)
    for j in range(2):
        ax.plot(*tracked[:, j].T, color="tab:green", lw=1.2)
    ax.plot([], [], color="tab:blue", lw=5, alpha=0.3, label="desired paths (paper 000, sinusoidal)")
    ax.plot(
        [], [], color="tab:green", lw=1.2, label=f"tracked: max error {result.position_error.max():.0e} m"
    )
    ax.plot([], [], color="tab:orange", lw=2, label="youBot at waypoints 0, 66, 133, 199")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_box_aspect(np.ptp(np.vstack(drawn), axis=0))
    ax.view_init(elev=25, azim=-50)
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title("Mobile dual-arm youBot, coordinated tracking (hybrid solver, 200 waypoints)", fontsize=10)
    fig.tight_layout()
    fig.savefig(HERE / "tracking_mobile_dual_youbot.png", dpi=100)
    plt.close(fig)

    if find_chromium() is not None:
        with Viewer(robot) as viewer, tempfile.TemporaryDirectory() as tmp:
            viewer.show(result.configurations[100])
            viewer.add_path("desired_1", path.positions)
            viewer.add_path("desired_2", path.positions + task.offset)
            viewer.vis["/Grid"].set_property("visible", False)
            viewer.set_camera([0.9, -1.1, 0.7])
            html = viewer.save_html(Path(tmp) / "scene.html")
            screenshot(html, HERE / "meshcat_mobile_dual_youbot.png", size=(640, 420), budget_ms=2000)


if __name__ == "__main__":
    main()
