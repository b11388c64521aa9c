"""inskit._numba_cache: numba's cache entries go when a compiled source changes (the cache of a function
that inlines another module's compiled code is keyed on its own file only), and stay otherwise."""

import os

from inskit import _numba_cache as NC


def _tree(tmp_path):
    root = tmp_path / "pkg"
    (root / "sub" / "__pycache__").mkdir(parents=True)
    (root / "__pycache__").mkdir()
    (root / "kernel.py").write_text("from numba import njit\n\n@njit(cache=True)\ndef f(x):\n    return x + 1\n")
    (root / "sub" / "user.py").write_text("import numba  # calls kernel.f\n")
    (root / "plain.py").write_text("X = 1\n")
    return root


def _entries(root):
    for d in ("__pycache__", "sub/__pycache__"):
        for ext in ("nbi", "nbc"):
            (root / d / f"m.f-1.py311.{ext}").write_bytes(b"cached")


def _count(root):
    return len(list(root.rglob("*.nb[ic]")))


def test_entries_go_when_a_compiled_source_changes_and_stay_otherwise(tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    root = _tree(tmp_path)
    assert [p.name for p in NC.numba_sources(root)] == ["kernel.py", "user.py"]
    _entries(root)
    assert NC.refresh(root) and _count(root) == 0  # no stamp yet: what is cached is of unknown sources
    _entries(root)
    assert not NC.refresh(root) and _count(root) == 4  # nothing changed
    (root / "plain.py").write_text("X = 2\n")  # no numba in it
    assert not NC.refresh(root) and _count(root) == 4
    k = root / "kernel.py"
    st = k.stat()
    os.utime(k, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))  # touched, the same text
    assert not NC.refresh(root) and _count(root) == 4
    k.write_text(k.read_text().replace("x + 1", "x + 2"))  # the callee changed, its callers' entries too
    assert NC.refresh(root) and _count(root) == 0
    _entries(root)
    assert not NC.refresh(root) and _count(root) == 4


def test_a_cache_under_numba_cache_dir_is_cleared_too(tmp_path, monkeypatch):
    root = _tree(tmp_path)
    alt = tmp_path / "alt"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(alt))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    mirror = alt / str(root).lstrip(os.sep) / "sub"
    mirror.mkdir(parents=True)
    (mirror / "m.f-1.py311.nbi").write_bytes(b"cached")
    assert NC.refresh(root) and not (mirror / "m.f-1.py311.nbi").exists()


def test_the_package_checks_its_own_cache_on_import():
    assert (NC.ROOT / "__pycache__" / NC.STAMP_NAME).is_file() or not os.access(NC.ROOT, os.W_OK)
    assert "integration/_kernel.py" in {str(p.relative_to(NC.ROOT)) for p in NC.numba_sources()}
