"""numba's cache loads without its registries' refresh (inskit._numba_load)."""

import os
import subprocess
import sys
import textwrap

MODULE = '''
import numpy as np
from numba import njit


@njit(cache=True)
def ar1(w, phi):
    y = np.empty_like(w)
    y[0] = w[0]
    for k in range(1, w.shape[0]):
        y[k] = w[k] + phi * y[k - 1]
    return y


@njit(cache=True)
def matmul(a, b):
    return a @ b
'''

SCRIPT = r"""
import sys
import numpy as np
import inskit
import cached_kernels as ck

y = ck.ar1(np.ones(4), 0.5)
print("ar1-exact", bool(np.array_equal(y, [1.0, 1.5, 1.75, 1.875])))
print("refreshed-after-load", "numba.np.arraymath" in sys.modules)
print("blas-after-plain-load", "scipy.linalg.cython_blas" in sys.modules)
a = np.array([[4.0, 1.0], [1.0, 3.0]])
print("matmul-exact", bool(np.array_equal(ck.matmul(a, a), [[17.0, 7.0], [7.0, 10.0]])))
print("blas-loaded", "scipy.linalg.cython_blas" in sys.modules)
print("linalg-imported", "scipy.linalg" in sys.modules)
from numba import njit


@njit
def twice(x):  # not cached: compiled (and numba refreshes for that itself)
    return 2.0 * x


print("compiled-exact", bool(np.array_equal(twice(np.ones(2)), [2.0, 2.0])))
print("refreshed-after-compile", "numba.np.arraymath" in sys.modules)
"""


def _run(folder, env_extra=None):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(folder), *sys.path]), **(env_extra or {}))
    p = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, env=env, timeout=300,
                       cwd=folder)
    assert p.returncode == 0, p.stderr[-2000:]
    return dict(line.rsplit(" ", 1) for line in p.stdout.splitlines())


def _cached(tmp_path):
    (tmp_path / "cached_kernels.py").write_text(textwrap.dedent(MODULE))
    _run(tmp_path)  # compiles the two kernels into the cache beside the module
    return tmp_path


def test_cached_kernels_load_without_the_refresh_and_give_the_same_numbers(tmp_path):
    got = _run(_cached(tmp_path))
    assert got["ar1-exact"] == "True" and got["matmul-exact"] == "True" and got["compiled-exact"] == "True"
    assert got["refreshed-after-load"] == "False"       # the loads imported none of the compiler's registries
    assert got["blas-after-plain-load"] == "False"      # nor scipy's BLAS for code that does not call it
    assert got["blas-loaded"] == "True"                 # code that does: loaded the light way ...
    assert got["linalg-imported"] == "False"            # ... not through scipy.linalg's __init__
    assert got["refreshed-after-compile"] == "True"     # a compilation still has everything


def test_the_light_load_can_be_switched_off(tmp_path):
    got = _run(_cached(tmp_path), {"INSKIT_NUMBA_REFRESH": "1"})
    assert got["refreshed-after-load"] == "True"        # numba's own way: the refresh at the first load
    assert got["ar1-exact"] == "True" and got["matmul-exact"] == "True" and got["compiled-exact"] == "True"


def test_a_cache_that_loads_otherwise_falls_back_to_numbas_own_load():
    """A numba whose ``_load_overload`` fails (another version's cache) is not
    a crash: the wrapped load hands the call to numba's own method."""
    import contextlib

    from numba.core.registry import cpu_target

    from inskit._numba_load import _light_load_overload

    class Cache:
        def _guard_against_spurious_io_errors(self):
            return contextlib.nullcontext()

        def _load_overload(self, sig, target_context):
            raise AttributeError("no such index in this numba")

    calls = []

    def original(self, sig, target_context):
        calls.append(sig)
        return "numba's own load"

    load = _light_load_overload(original)
    assert load(Cache(), "sig", cpu_target.target_context) == "numba's own load" and calls == ["sig"]
