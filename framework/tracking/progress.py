"""The progress bar of a tracked path."""


from __future__ import annotations


# ---------------------------------------------------------------------------------------------- progress
class Progress:
    """A rich progress bar over waypoints, or nothing (not a terminal, or ``enabled=False``)."""

    def __init__(self, enabled: bool | None, total: int, description: str):
        self.total, self.description = total, description
        self.enabled = enabled
        self._bar = None

    def __enter__(self) -> Progress:  # noqa: PYI034
        from rich.console import Console

        console = Console(stderr=True)
        enabled = console.is_terminal if self.enabled is None else self.enabled
        if enabled:
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

            self._bar = Progress(
                TextColumn("{task.description}"),
                BarColumn(),
                MofNCompleteColumn(),
                TimeRemainingColumn(),
                TextColumn("error {task.fields[error]}"),
                console=console,
                transient=True,
            )
            self._bar.__enter__()
            self._task = self._bar.add_task(self.description, total=self.total, error="-")
        return self

    def advance(self, error: float) -> None:
        if self._bar is not None:
            self._bar.update(self._task, advance=1, error=f"{error:.1e}")

    def __exit__(self, *exc) -> None:
        if self._bar is not None:
            self._bar.__exit__(*exc)
