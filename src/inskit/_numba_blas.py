"""numba's BLAS check without the import of ``scipy.linalg``.

On its first compiled call (a function loaded from the cache included) numba
imports ``numba.np.arraymath``, which checks for a BLAS by importing
``scipy.linalg.cython_blas``.  Python imports the parent package first, and
``scipy.linalg``'s ``__init__`` loads most of scipy.linalg with its array-API
layer and ``numpy.f2py``: 0.3 s of every inskit command that runs compiled
code (``python -X importtime``: 0.31 s of the 0.32 s of
``numba.np.arraymath``), for a module of function pointers.

:func:`install` puts a finder on ``sys.meta_path`` that, the moment
``numba.np.arraymath`` is looked for, loads the ``cython_blas`` and
``cython_lapack`` extension modules from scipy's directory by their file
names into ``sys.modules`` under their own names, and steps aside; numba's
import then finds them loaded.  The modules are scipy's own, nothing is
replaced: numba binds the same BLAS and LAPACK routines, and a later
``import scipy.linalg`` runs its ``__init__`` as usual and finds the two
modules loaded.  Any failure leaves numba to import them its own way.  Set
``INSKIT_SCIPY_LINALG=1`` to switch the finder off.
"""

from __future__ import annotations

import os
import sys

_MODULES = ("scipy.linalg.cython_blas", "scipy.linalg.cython_lapack")
_TRIGGER = "numba.np.arraymath"


def preload() -> bool:
    """Load scipy's ``cython_blas`` and ``cython_lapack`` into ``sys.modules``
    without ``scipy.linalg``'s ``__init__``; True when both are loaded
    (already, or now)."""
    import importlib.machinery
    import importlib.util

    if all(m in sys.modules for m in _MODULES):
        return True
    spec0 = importlib.util.find_spec("scipy")
    if spec0 is None or spec0.origin is None:
        return False
    import scipy  # noqa: F401  (the parent package itself is light: its __init__ imports no subpackage)

    folder = os.path.join(os.path.dirname(spec0.origin), "linalg")
    for name in _MODULES:
        if name in sys.modules:
            continue
        leaf = name.rsplit(".", 1)[1]
        path = next((os.path.join(folder, leaf + s) for s in importlib.machinery.EXTENSION_SUFFIXES
                     if os.path.isfile(os.path.join(folder, leaf + s))), None)
        if path is None:
            break
        spec = importlib.util.spec_from_file_location(name, path)
        if spec is None or spec.loader is None:
            break
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        try:
            spec.loader.exec_module(module)
        except BaseException:
            del sys.modules[name]
            raise
    return all(m in sys.modules for m in _MODULES)


class _Finder:
    """A ``sys.meta_path`` finder that finds nothing: it runs :func:`preload`
    when numba's ``arraymath`` is first looked for, then removes itself."""

    def find_spec(self, name, path=None, target=None):
        if name != _TRIGGER:
            return None
        try:
            sys.meta_path.remove(self)
        except ValueError:
            pass
        try:
            preload()
        except Exception:  # noqa: BLE001 (numba then imports scipy.linalg its own way)
            pass
        return None


def install() -> None:
    """Put the finder on ``sys.meta_path`` (once; not when numba's arraymath
    is loaded already or ``INSKIT_SCIPY_LINALG=1``)."""
    if os.environ.get("INSKIT_SCIPY_LINALG") == "1" or _TRIGGER in sys.modules:
        return
    if any(isinstance(f, _Finder) for f in sys.meta_path):
        return
    sys.meta_path.insert(0, _Finder())
