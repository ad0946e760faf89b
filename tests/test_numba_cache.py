"""The package's numba cache is dropped when what its machine code came from changes: the sources, or numba's
code-generation settings (which numba's own index does not key on)."""

from __future__ import annotations

from framework import numba_cache


def _package(tmp_path):
    package = tmp_path / "pkg"
    (package / "__pycache__").mkdir(parents=True)
    (package / "kernels.py").write_text("def f():\n    return 1\n")
    return package, package / "__pycache__" / "stamp"


def _cache_an_entry(package):
    entry = package / "__pycache__" / "kernels.f-1.py311.nbi"
    entry.write_bytes(b"")
    return entry


def test_entries_survive_an_unchanged_package_and_go_when_a_source_changes(tmp_path):
    package, stamp = _package(tmp_path)
    numba_cache.drop_stale_entries(package, stamp)  # stamped
    entry = _cache_an_entry(package)
    assert numba_cache.drop_stale_entries(package, stamp) == 0 and entry.exists()
    (package / "kernels.py").write_text("def f():\n    return 2\n")
    assert numba_cache.drop_stale_entries(package, stamp) == 1 and not entry.exists()


def test_entries_go_when_a_code_generation_setting_changes(tmp_path, monkeypatch):
    """A run with NUMBA_ENABLE_PROFILING=1 (or another optimization level) must not leave its machine code to
    later runs, nor load theirs."""
    package, stamp = _package(tmp_path)
    numba_cache.drop_stale_entries(package, stamp)
    for name, value in (("ENABLE_PROFILING", 1), ("OPT", 0), ("BOUNDSCHECK", 1), ("DEBUGINFO_DEFAULT", 1)):
        entry = _cache_an_entry(package)
        with monkeypatch.context() as patched:
            patched.setattr(numba_cache.numba_config, name, value)
            assert numba_cache.drop_stale_entries(package, stamp) == 1 and not entry.exists(), name
        entry = _cache_an_entry(package)  # back to the settings before: their code is stale in turn
        assert numba_cache.drop_stale_entries(package, stamp) == 1 and not entry.exists(), name
        assert numba_cache.drop_stale_entries(package, stamp) == 0
