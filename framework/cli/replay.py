"""``metaik replay FILE.rrd``: open a recording in the rerun viewer, or summarize it."""

from __future__ import annotations

import argparse
from typing import Any

from ..io.recording.reader import read_recording
from ..io.recording.replay import replay, replay_command_line


def add_replay_command(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``replay FILE.rrd [--summary]`` to the CLI's subparsers; dispatch to :func:`replay_command`."""
    parser = subparsers.add_parser("replay", help="open a recording (.rrd) in the rerun viewer")
    parser.add_argument("recording", help="a .rrd file written by `metaik run --record`")
    parser.add_argument(
        "--summary", action="store_true", help="print what the recording holds instead of opening the viewer"
    )
    return parser


def replay_command(args: argparse.Namespace, console: Any) -> int:
    """``metaik replay``: open the viewer (exit 0), or print a summary with ``--summary``."""
    recording = read_recording(args.recording)
    if not args.summary:
        console.print(
            f"opening {recording.path} in the rerun viewer: {' '.join(replay_command_line(recording.path))}"
        )
        replay(recording.path)
        return 0
    console.print(
        f"{recording.path}: {len(recording.entities)} entities, timelines "
        f"{', '.join(sorted(recording.timelines))}{'' if recording.complete else ' (incomplete file)'}",
        markup=False,
    )
    if recording.torn:
        console.print(f"  torn: {recording.torn}", markup=False)
    if "/summary/task_error" in recording.entities:
        _, errors = recording.scalars("/summary/task_error", "solution")
        _, names = recording.values("/summary/name", "TextDocument:text", "solution")
        for name, error in zip(names, errors):
            console.print(f"  {name[0]}: task error {error:.3e}")
    for entity in recording.entities:
        if entity.startswith("/tracking/") and "settings" not in entity:
            _, values = recording.scalars(entity, "waypoint")
            spread = f", mean {values.mean():.3e}, max {values.max():.3e}" if values.size else ""
            console.print(f"  {entity}: {len(values)} waypoints{spread}", markup=False)
    return 0
