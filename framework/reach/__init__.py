"""Reach of a robot: capability maps and base placement, each a batch of solves."""
