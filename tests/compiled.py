"""Compiled trampolines for the tests: the package's compiled-only functions (``framework.compiled.native.internal``: linked
into their callers, no Python entry point) called from Python through a function compiled here, and the engine's
workspaces made and read from Python."""

from __future__ import annotations

import numba
import numpy as np

from framework.costs.kernels import linearize
from framework.costs.workspace import views, workspaces
from framework.engine.derivatives import add_curvature
from framework.compiled.native import keep_alive


def python_callable(function):
    """``function`` (compiled for compiled callers only) callable from Python, with the same arguments."""

    @numba.njit
    def call(*args):
        return function(*args)

    return call


@numba.njit
def make_workspaces(packed, n, count):
    """``(owners, records)``: ``count`` workspaces of a problem (keep ``owners`` and ``packed`` alive while the
    records are used)."""
    return workspaces(packed, n, count)


@numba.njit
def linearize_in(records, i, x, level, want_jacobian, kinematics) -> int:
    """:func:`~framework.costs.kernels.linearize` in workspace ``records[i]``."""
    return linearize(x, records[i], level, want_jacobian, kinematics)


@numba.njit
def rows_in(records, i, m):
    """Copies of the first ``m`` residual rows and Jacobian rows of workspace ``records[i]``, its poses and frame
    Jacobians."""
    v = views(records[i])
    return v.r[:m].copy(), v.J[:m].copy(), v.poses.copy(), v.jacobians.copy()


@numba.njit
def set_jacobian_rows(records, i, value) -> None:
    """Every entry of workspace ``records[i]``'s residual Jacobian set to ``value``."""
    v = views(records[i])
    v.J[:, :] = value


@numba.njit
def use_table(records, i, table) -> None:
    """Workspace ``records[i]`` reads the block table ``table`` (keep it alive)."""
    records[i].blocks = table.ctypes.data


@numba.njit
def curvature_at(x, packed, level, block, row, mu):
    """``Σ_c mu_c ∇²r_c`` ``(n, n)`` of block ``block`` of ``packed`` (its rows from ``row`` on among the rows of
    ``level``) at ``x``, by its kind's curvature kernel."""
    owners, records = workspaces(packed, x.shape[0], 1)
    ws = records[0]
    linearize(x, ws, level, True, 1)
    H = np.zeros((x.shape[0], x.shape[0]))
    add_curvature(ws, block, row, mu, H)
    keep_alive(owners, packed)  # (numba frees a local after its last use: the workspace's memory is in owners)
    return H
