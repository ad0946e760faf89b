"""Second-order kinematics for the curvature kernels of the block kinds: ``m·∂²v/∂x_i∂x_j`` of vectors attached to a
frame, from the product of exponentials.

With ``ω_i`` the world axis of coordinate ``i`` (zero for translations) and ``V_j`` the first derivatives of a
vector attached to the frame (a point's position Jacobian column, or ``ω_j × w`` for an axis ``w``), for ``i``
before or at ``j`` on the frame's chain ``∂²v/∂x_i∂x_j = ω_i × V_j`` — exact for points and axes; a rotation
vector's second derivative on its target is ``½ ω_i × ω_j``.
"""

from __future__ import annotations

from ..compiled.native import internal


@internal
def chain_curvature(f, m0, m1, m2, V, jacobians, chain_ptr, chain_idx, H) -> None:
    """Add ``m·(ω_i × V_j)`` to ``H[i, j]`` (and ``H[j, i]``) for ``i`` before or at ``j`` on frame ``f``'s chain:
    the second derivative of a vector attached to the frame whose first derivatives are the columns ``V (3, n)``."""
    lo, hi = chain_ptr[f], chain_ptr[f + 1]
    for s in range(lo, hi):
        i = chain_idx[s]
        wx, wy, wz = jacobians[f, 3, i], jacobians[f, 4, i], jacobians[f, 5, i]
        if wx == 0.0 and wy == 0.0 and wz == 0.0:
            continue
        for t in range(s, hi):
            j = chain_idx[t]
            vx, vy, vz = V[0, j], V[1, j], V[2, j]
            h = m0 * (wy * vz - wz * vy) + m1 * (wz * vx - wx * vz) + m2 * (wx * vy - wy * vx)
            H[i, j] += h
            if j != i:
                H[j, i] += h


@internal
def position_curvature(f, m0, m1, m2, jacobians, chain_ptr, chain_idx, H) -> None:
    """Add ``m·∂²p_f/∂x_i∂x_j`` (``∂²p/∂x_i∂x_j = ω_i × J_j`` for ``i`` before ``j``) to ``H``."""
    chain_curvature(f, m0, m1, m2, jacobians[f, 0:3], jacobians, chain_ptr, chain_idx, H)


@internal
def projected_curvature(k, u, D, H) -> None:
    """Add ``k Dᵀ(I − uuᵀ)D`` to ``H``: a distance ``‖v‖``'s curvature through its direction ``u`` (``D = ∂v``,
    ``(3, n)``; ``k = μ / ‖v‖``)."""
    n = H.shape[0]
    for i in range(n):
        ui = u[0] * D[0, i] + u[1] * D[1, i] + u[2] * D[2, i]
        for j in range(n):
            uj = u[0] * D[0, j] + u[1] * D[1, j] + u[2] * D[2, j]
            H[i, j] += k * (D[0, i] * D[0, j] + D[1, i] * D[1, j] + D[2, i] * D[2, j] - ui * uj)
