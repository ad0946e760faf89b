"""Entry points compiled side by side: the first in this process, the others in a helper process that writes them
to the disk cache, from which this process loads them; without a helper (turned off, or failing) all here."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

_PROBE = """
import json, sys
import numpy as np
from framework.optimizers import base, cmaes_fast
from framework.compiled.cache import has_signature
from framework.compiled.parallel import entry_points
if sys.argv[1] == "failing":
    sys.executable = "/bin/false"  # a helper that exits with an error at once
rng = np.random.default_rng(3)
jobs = [(base._outside, (rng.normal(size=(5, 3)), -np.ones(3), np.ones(3))),
        (cmaes_fast._sample, (rng.normal(size=3), 0.5, np.eye(3), rng.uniform(1, 2, 3), rng.normal(size=(4, 3))))]
points = entry_points(jobs)
copy = lambda args: tuple(a.copy() if isinstance(a, np.ndarray) else a for a in args)
same = [bool(np.array_equal(point(*copy(args)), dispatcher.py_func(*copy(args))))
        for point, (dispatcher, args) in zip(points, jobs)]
print(json.dumps({"misses": [sum(d.stats.cache_misses.values()) for d, _ in jobs],
                  "hits": [sum(d.stats.cache_hits.values()) for d, _ in jobs],
                  "cached": [has_signature(d, tuple(d.typeof_pyval(a) for a in args)) for d, args in jobs],
                  "same": same}))
"""


def _probe(cache: Path, mode: str = "", **environment: str) -> tuple[dict, str]:
    env = {**os.environ, "METAIK_CACHE_DIR": str(cache), "METAIK_COMPILE_NOTICE": "0", **environment}
    done = subprocess.run([sys.executable, "-c", _PROBE, mode], capture_output=True, text=True, env=env, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.splitlines()[-1]), done.stderr


def test_the_second_entry_point_compiles_in_a_helper_and_loads_from_the_cache(tmp_path):
    """With an empty cache: the first job compiled here (a miss), the second loaded from the cache (a hit: the
    helper compiled it), both in the cache and computing what their Python functions compute."""
    result, errors = _probe(tmp_path)
    assert result == {"misses": [1, 0], "hits": [0, 1], "cached": [True, True], "same": [True, True]}, errors
    again, _ = _probe(tmp_path)  # a second process loads both
    assert again["misses"] == [0, 0] and again["hits"] == [1, 1]


def test_without_a_helper_everything_compiles_here(tmp_path):
    result, errors = _probe(tmp_path, METAIK_COMPILE_HELPER="0")
    assert result == {"misses": [1, 1], "hits": [0, 0], "cached": [True, True], "same": [True, True]}, errors


def test_a_failing_helper_is_reported_and_its_jobs_compile_here(tmp_path):
    result, errors = _probe(tmp_path, "failing")
    assert result == {"misses": [1, 1], "hits": [0, 0], "cached": [True, True], "same": [True, True]}, errors
    assert "the helper process compiling optimizers.cmaes_fast._sample failed (exit 1)" in errors


_MODULE = '''
from framework.compiled.native import compiled, internal

@internal
def inner(a, b):
    s = 0.0
    for i in range(a.shape[0]):
        s += a[i] * b[i] + 1.0
    return s

@internal
def other(a):
    return a.sum()

@compiled
def outer(a, b):
    return inner(a, b) - 2.0 * other(a)
'''

_CALLEES = """
import json, sys
import numpy as np
import callees_probe as m
from framework.compiled.parallel import entry_points
a, b = np.arange(4.0), np.linspace(0, 1, 4)
(point,) = entry_points([(m.outer, (a, b))], [(m.inner, (a, b)), (m.other, (a,))])
stats = lambda f: [sum(f.dispatcher.stats.cache_misses.values()), sum(f.dispatcher.stats.cache_hits.values())]
print(json.dumps({"value": point(a, b), "inner": stats(m.inner), "other": stats(m.other)}))
"""


def _callees(folder: Path, **environment: str) -> dict:
    env = {**os.environ, "METAIK_CACHE_DIR": str(folder / "cache"), "METAIK_COMPILE_NOTICE": "0",
           "PYTHONPATH": os.pathsep.join([str(folder), str(ROOT)]), **environment}
    done = subprocess.run([sys.executable, "-c", _CALLEES], capture_output=True, text=True, env=env, cwd=folder)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.splitlines()[-1])


def test_the_largest_callee_compiles_in_the_helper_and_the_entry_point_links_it_from_the_cache(tmp_path):
    """A linked-only callee compiled by the helper, cached as bitcode, is loaded (not compiled) here when the entry
    point that calls it compiles, and the entry point computes what Python computes; the other callee compiles
    here. Without a helper, both compile here."""
    (tmp_path / "callees_probe.py").write_text(_MODULE)
    a, b = np.arange(4.0), np.linspace(0, 1, 4)
    expected = float(np.sum(a * b + 1.0) - 2.0 * a.sum())
    result = _callees(tmp_path)
    assert result == {"value": expected, "inner": [0, 1], "other": [1, 0]}
    (tmp_path / "callees_probe.py").write_text(_MODULE + "\n# an edit\n")  # new sources: new cache entries
    alone = _callees(tmp_path, METAIK_COMPILE_HELPER="0")
    assert alone == {"value": expected, "inner": [1, 0], "other": [1, 0]}
