"""The tutorial notebooks run top to bottom (nbclient, this interpreter's python3 kernel), so they never rot."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import same_framework_env


def _require_jupyter() -> None:
    """nbclient, nbformat and ipykernel are test dependencies: missing, the test fails (it never skips)."""
    try:
        import ipykernel  # noqa: F401
        import nbclient  # noqa: F401
        import nbformat  # noqa: F401
    except ImportError as err:
        pytest.fail(f"{err.name} is a test dependency (pip install -e .[test]): {err}")


NOTEBOOKS = sorted((Path(__file__).parent.parent / "notebooks").glob("*.ipynb"))
CELL_TIMEOUT = 600  # seconds per cell: a guard against hangs. Warm, the slowest cell (200 tracked waypoints)
# takes ~3 s; in a fresh install the first solve also compiles the engine (~35 s here, more on a loaded machine).


def test_the_learning_path_is_complete():
    assert [p.stem for p in NOTEBOOKS] == [
        "01_quickstart",
        "02_mobile_dual_arm",
        "03_new_robot",
        "04_compare_solvers",
        "05_real_robots",
        "06_collisions",
        "07_motion_limits",
    ]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_is_saved_without_outputs(path):
    _require_jupyter()
    import nbformat

    notebook = nbformat.read(path, as_version=4)
    nbformat.validate(notebook)
    for cell in notebook.cells:
        if cell.cell_type == "code":
            assert cell.outputs == [] and cell.execution_count is None, f"{path.name}: clear the outputs"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_runs(path, tmp_path):
    """Every cell runs without error in a fresh kernel (files the notebook writes go to a temporary folder)."""
    _require_jupyter()
    import nbformat
    from nbclient import NotebookClient

    notebook = nbformat.read(path, as_version=4)
    client = NotebookClient(
        notebook,
        timeout=CELL_TIMEOUT,
        kernel_name="python3",
        resources={"metadata": {"path": str(tmp_path)}},
    )
    client.execute(env=same_framework_env())  # the kernel imports this process's framework: its cache is warm
    errors = [
        o for c in notebook.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"
    ]
    assert errors == []
    if path.stem == "02_mobile_dual_arm":  # it records to rerun and exports a meshcat page
        assert (tmp_path / "mobile_dual_arm.rrd").stat().st_size > 10_000
        assert (tmp_path / "mobile_dual_arm.html").stat().st_size > 500_000
    figures = [o for c in notebook.cells for o in c.get("outputs", []) if "image/png" in o.get("data", {})]
    assert figures, f"{path.name} draws no figure"
