"""Where the shipped robot and task files live: inside the wheel (``framework/_data``) or in a checkout."""

from __future__ import annotations

from pathlib import Path

from .errors import ResourceError

_PACKAGE = Path(__file__).resolve().parent


def data_dir(kind: str) -> Path:
    """Directory of the shipped ``"robots"`` or ``"tasks"`` files.

    An installed wheel carries them in ``framework/_data/<kind>``; an editable install or a checkout
    reads them from ``<repository>/<kind>``.
    """
    for candidate in (_PACKAGE / "_data" / kind, _PACKAGE.parent / kind):
        if candidate.is_dir():
            return candidate
    raise ResourceError(f"cannot find the shipped {kind!r} directory next to {_PACKAGE}; reinstall metaik")
