"""Helpers of the compiled code: how a function is compiled (numba), its disk cache keyed by content, functions
linked into their callers, entry points compiled side by side, sine and cosine at once."""
