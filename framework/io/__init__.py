"""Files in and out: task files (IK, tracking, base placement, M-FABRIK), their value syntax, rerun recordings."""
