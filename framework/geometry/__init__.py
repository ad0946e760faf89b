"""Shapes and what touches what: rotations given by users, solids, sphere covers, the obstacle scene, the broad
phase, the exact collision check (coal) and convex hulls."""
