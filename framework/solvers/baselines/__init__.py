"""Conventional Jacobian IK baselines, for comparison with the optimizer (papers 001 and 003).

- :func:`jacobian_ik`: pseudo-inverse (SVD) or damped least-squares closed-loop IK of one frame (one arm, or a
  mobile arm: the base joints are columns of the same Jacobian), registered as the IK solvers ``pinv`` and ``dls``;
- :func:`relative_jacobian_ik`: paper 001's relative Jacobian with null-space task priority for two coordinated
  arms (gains 0.3 relative / 0.7 secondary, SVD pseudo-inverse).

Along paths: :mod:`framework.tracking.jacobian_paths` (``jacobian_track``, ``relative_jacobian_track``).
"""

from .jacobian import dls_inverse, jacobian_ik, svd_pinv
from .relative import RELATIVE_GAIN, SECONDARY_GAIN, relative_jacobian_ik, relative_jacobian_step

__all__ = [
    "RELATIVE_GAIN",
    "SECONDARY_GAIN",
    "dls_inverse",
    "jacobian_ik",
    "relative_jacobian_ik",
    "relative_jacobian_step",
    "svd_pinv",
]
