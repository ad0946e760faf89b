"""docs/taskfile.md is what the readers accept: written by its command from the term types and key tables, every
term type's keys documented, and every example a valid entry of its type."""

from __future__ import annotations

from pathlib import Path

import pytest

from framework.costs.registry import TERM_CLASSES
from framework.io.taskfile import load_task
from framework.io.taskfile_doc import DOCUMENT, reference

ROOT = Path(__file__).resolve().parents[1]


def test_the_reference_is_up_to_date():
    assert (ROOT / DOCUMENT).read_text() == reference(), "run python -m framework.io.taskfile_doc"


@pytest.mark.parametrize("cls", TERM_CLASSES, ids=[c.task_type for c in TERM_CLASSES])
def test_every_key_is_documented_and_the_example_reads(cls, tmp_path):
    assert set(cls.task_doc) == set(cls.task_keys)
    robot, example = cls.task_example
    if robot.startswith("pybullet_data/"):  # a robot with masses (no shipped robot has <inertial>)
        data = pytest.importorskip("pybullet_data")
        robot = str(Path(data.getDataPath()) / robot.removeprefix("pybullet_data/"))
    path = tmp_path / "example.toml"
    path.write_text(f'[task]\nname = "example"\nrobot = "{robot}"\n\n[[terms]]\n{example}\n')
    terms = [t for _, t in load_task(path).cases[0].problem.objective.terms]
    assert any(type(t) is cls for t in terms)
    assert f"### `{cls.task_type}`" in reference()
