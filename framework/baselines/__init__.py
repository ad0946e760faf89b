"""Conventional Jacobian IK baselines, for comparison with the optimizer (papers 001 and 003).

- :func:`jacobian_track`: pseudo-inverse (SVD) or damped least-squares closed-loop IK of one frame along a
  path (one arm, or a mobile arm: the base joints are columns of the same Jacobian);
- :func:`relative_jacobian_track`: paper 001's relative Jacobian with null-space task priority for two
  coordinated arms (gains 0.3 relative / 0.7 secondary, SVD pseudo-inverse).

Both return a :class:`~framework.tracking.TrackingResult`; ``result.smoothness(robot)`` says where they jump.
"""

from .jacobian import dls_inverse, jacobian_ik, svd_pinv
from .path import jacobian_track, relative_jacobian_track
from .relative import RELATIVE_GAIN, SECONDARY_GAIN, relative_jacobian_ik, relative_jacobian_step

__all__ = [
    "RELATIVE_GAIN",
    "SECONDARY_GAIN",
    "dls_inverse",
    "jacobian_ik",
    "jacobian_track",
    "relative_jacobian_ik",
    "relative_jacobian_step",
    "relative_jacobian_track",
    "svd_pinv",
]
