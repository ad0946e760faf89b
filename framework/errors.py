"""Exceptions raised by metaik. Every error the user can cause is a subclass of :class:`MetaikError`.

Messages name the file, frame, joint or value at fault and, where it helps, what to do instead.
"""

from __future__ import annotations


class MetaikError(Exception):
    """Base class of every error metaik raises on bad input."""


class RobotFileError(MetaikError):
    """A robot description is missing, unreadable, malformed XML, or a xacro file failed to expand."""


class UnknownRobotError(MetaikError):
    """A robot name is neither in the robot index nor a path to a file."""


class UnknownFrameError(MetaikError):
    """A frame name is not in the robot model."""


class UnknownJointError(MetaikError):
    """A joint or joint-group name is not in the robot model."""


class UnsupportedJointError(MetaikError):
    """A joint type cannot be part of the search space (e.g. a free-flyer); lock it instead."""


class LimitsError(MetaikError):
    """Joint limits or search bounds are inverted, non-finite, or of the wrong shape."""


class ConfigurationError(MetaikError):
    """A configuration or population has the wrong shape or holds NaN/inf."""


class TaskError(MetaikError):
    """A task, cost term or target is invalid (NaN target, wrong shape, bad weight, unknown key)."""


class SolverError(MetaikError):
    """A solver name is unknown or its settings are invalid."""


class ResourceError(MetaikError):
    """A packaged resource (robot index, task file) cannot be found."""


class RecordingError(MetaikError):
    """A recording cannot be written, read or replayed (missing file, not an .rrd file)."""


class ViewerError(MetaikError):
    """The meshcat viewer or the headless browser cannot do what was asked."""


#: Exit codes of the ``metaik`` command: success; the run finished but a case missed its tolerance;
#: bad input (one clear line on stderr, no traceback); interrupted by Ctrl-C.
EXIT_OK, EXIT_MISSED, EXIT_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 130
