"""numba's BLAS check without scipy.linalg's import (inskit._numba_blas)."""

import os
import subprocess
import sys

SCRIPT = r"""
import sys
import numpy as np
import inskit
from numba import njit
from inskit.rotations import quat_from_rotvec

quat_from_rotvec(np.zeros((2, 3)))  # a cached kernel: numba's set-up
print("linalg-after-setup", "scipy.linalg" in sys.modules)


@njit
def solve_and_dot(a, b):
    return np.linalg.solve(a, b), a @ b, np.linalg.inv(a)


a = np.array([[4.0, 1.0, 0.0], [1.0, 3.0, 0.5], [0.0, 0.5, 2.0]])
b = np.array([[1.0], [2.0], [3.0]])
x, ab, ai = solve_and_dot(a, b)  # compiled: numba's registries, its BLAS check
print("linalg-after-compile", "scipy.linalg" in sys.modules)
print("blas-loaded", "scipy.linalg.cython_blas" in sys.modules and "scipy.linalg.cython_lapack" in sys.modules)
print("numba-linalg", bool(np.allclose(a @ x, b, atol=1e-14) and np.allclose(ab, a @ b) and np.allclose(ai @ a, np.eye(3))))
import scipy.linalg
from scipy.linalg import cython_blas, lu_factor, lu_solve
print("scipy-linalg", bool(np.allclose(scipy.linalg.solve(a, b), x, atol=1e-14)
                          and np.allclose(lu_solve(lu_factor(a), b), x, atol=1e-14)
                          and cython_blas is sys.modules["scipy.linalg.cython_blas"]))
"""


def _run(env_extra):
    env = dict(os.environ, **env_extra)
    p = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, env=env, timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]
    return dict(line.rsplit(" ", 1) for line in p.stdout.splitlines())


def test_numba_sets_up_without_scipy_linalg_and_both_still_work():
    got = _run({})
    assert got == {"linalg-after-setup": "False", "linalg-after-compile": "False", "blas-loaded": "True",
                   "numba-linalg": "True", "scipy-linalg": "True"}


def test_the_finder_can_be_switched_off():
    got = _run({"INSKIT_SCIPY_LINALG": "1"})
    assert got["linalg-after-compile"] == "True"  # numba's own way: scipy.linalg imported by its BLAS check
    assert got["numba-linalg"] == "True" and got["scipy-linalg"] == "True"
