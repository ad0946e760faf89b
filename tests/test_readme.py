"""The README's two commands are what CI and users run."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def readme_commands() -> list[str]:
    lines = (ROOT / "README.md").read_text().splitlines()
    start = lines.index("```bash") + 1
    return lines[start : start + 2]


def test_ci_runs_the_readme_test_command():
    install_and_run, install_and_test = readme_commands()
    assert "metaik run" in install_and_run and "--record" in install_and_run and "pytest" in install_and_test
    assert install_and_test in (ROOT / ".ci" / "run").read_text().splitlines()


def test_the_main_job_names_a_shipped_task():
    from framework.cli import resolve_task

    task = readme_commands()[0].split("metaik run ")[1].split()[0]
    assert resolve_task(task).is_file()


def test_links_in_the_readme_exist():
    import re

    text = (ROOT / "README.md").read_text()
    for target in re.findall(r"\]\(([^)#]+)\)", text):
        if not target.startswith("http"):
            assert (ROOT / target).exists(), target
