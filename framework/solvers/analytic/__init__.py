"""Closed-form inverse kinematics of 6R arms whose axes allow it (a spherical wrist, three parallel axes): the
Paden-Kahan subproblems (:mod:`~.subproblems`), the families' compiled solutions (:mod:`~.families`), and what a
user calls (:mod:`~.solutions`: :func:`closed_form`, :func:`analytic_ik`)."""

from .solutions import AnalyticBatch, AnalyticIK, AnalyticSolutions, ClosedForm, analytic_ik, analytic_ik_batch, closed_form

__all__ = ["AnalyticBatch", "AnalyticIK", "AnalyticSolutions", "ClosedForm", "analytic_ik", "analytic_ik_batch", "closed_form"]
