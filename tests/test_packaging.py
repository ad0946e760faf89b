"""The built wheel carries the robot and task files, so a non-checkout install can load them by name."""

from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_wheel_ships_robots_and_tasks(tmp_path):
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", str(ROOT), "--no-deps", "--no-build-isolation", "-q", "-w", str(tmp_path)],
        check=True,
    )
    (wheel,) = tmp_path.glob("metaik-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    for path in (ROOT / "robots").rglob("*"):
        if path.is_file() and "__pycache__" not in path.parts:
            assert f"framework/_data/robots/{path.relative_to(ROOT / 'robots').as_posix()}" in names
    for path in (ROOT / "tasks").glob("*.toml"):
        assert f"framework/_data/tasks/{path.name}" in names
    assert "framework/model/kinematics.py" in names
