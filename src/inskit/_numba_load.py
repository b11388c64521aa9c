"""numba's cache loads without the refresh of its compiler's registries.

Before it loads a compiled function from the cache, numba refreshes its
CPU target (``numba.core.caching.Cache.load_overload`` calls
``target_context.refresh()``): it imports some forty modules of lowering
and typing implementations (``numba.np.arraymath``, ``numba.typed``,
``numba.cpython.unicode`` ...), installs their registries and looks up
third-party extensions.  A compiler needs all that; a function loaded from
the cache needs none of it: its machine code is linked as it was saved,
and only numba's runtime (NRT, the allocator that compiled code calls for
a new array) must be up, and, for code that calls BLAS or LAPACK, scipy's
``cython_blas`` be loaded the light way (:mod:`._numba_blas`; the
refresh's import of ``numba.np.arraymath`` did that).  The refresh took 0.15-0.2 s of every inskit
command that runs compiled code (``inskit simulate`` of the hour-long car:
0.15 s of its 1.2 s; ``python -X importtime`` shows the modules, cProfile
``numba/core/base.py:refresh``).

:func:`install` wraps ``load_overload`` of numba's function cache
(``FunctionCache``: the cache of ``@njit(cache=True)``) so that a load
initialises the runtime (what the refresh does first) and loads; only
when the cache holds no entry for the call's types does numba compile,
and its compiler refreshes the target itself
(``numba.core.compiler.CompilerBase.__init__``), so nothing a compilation
needs is skipped.  The wrapping waits for ``numba.core.caching`` to be
imported (a ``sys.meta_path`` finder, as :mod:`._numba_blas`): ``import
inskit`` still imports no numba.  Any failure leaves numba's own method in
place.  Set ``INSKIT_NUMBA_REFRESH=1`` to switch it off.
"""

from __future__ import annotations

import os
import sys

_TRIGGER = "numba.core.caching"


def _light_load_overload(original):
    """``FunctionCache.load_overload`` without the target's refresh."""

    def load_overload(self, sig, target_context):
        try:
            from numba.core.runtime import rtsys

            rtsys.initialize(target_context)  # what the refresh does first: the runtime compiled code calls
        except Exception:  # noqa: BLE001 (numba's own way then)
            return original(self, sig, target_context)
        try:
            with self._guard_against_spurious_io_errors():
                cres = self._load_overload(sig, target_context)
        except Exception:  # noqa: BLE001 (a numba whose cache loads otherwise: its own way, refresh and all)
            return original(self, sig, target_context)
        if cres is not None and _calls_blas(cres.library):
            _preload_blas()
        return cres  # None: not in the cache (or a spurious I/O error): numba compiles, and refreshes first

    load_overload.__doc__ = original.__doc__
    load_overload._inskit_light = True
    return load_overload


#: the names of numba's BLAS and LAPACK helpers start so (``numba._helperlib.c_helpers``: ``xxgemm``, ``ez_gesdd``)
_BLAS_PREFIXES = ("numba_x", "numba_ez_")


def _calls_blas(library) -> bool:
    """Whether the machine code of a ``library`` loaded from the cache may
    call numba's BLAS or LAPACK helpers: whether its module for linking
    declares one (True when it cannot tell)."""
    try:
        return any(f.is_declaration and f.name.startswith(_BLAS_PREFIXES) for f in library._shared_module.functions)
    except Exception:  # noqa: BLE001 (no such module: assume it may)
        return True


#: what loads scipy's BLAS and LAPACK the light way (:func:`install`'s ``preload_blas``), or None
_PRELOAD_BLAS = None


def _preload_blas():
    """scipy's BLAS and LAPACK modules loaded without ``scipy.linalg``'s
    ``__init__`` (``preload_blas`` of :func:`install`:
    :func:`._numba_blas.preload`), as the refresh's import of
    ``numba.np.arraymath`` had them: at its first call numba's helper
    imports ``scipy.linalg.cython_blas``, which would otherwise import all
    of ``scipy.linalg`` (0.3 s)."""
    if _PRELOAD_BLAS is None or os.environ.get("INSKIT_SCIPY_LINALG") == "1":
        return
    try:
        _PRELOAD_BLAS()
    except Exception:  # noqa: BLE001 (numba's helper then imports it its own way)
        pass


def patch(caching) -> bool:
    """Wrap ``caching.FunctionCache.load_overload`` (once); True when it is
    wrapped (now or already)."""
    cls = getattr(caching, "FunctionCache", None)
    original = getattr(cls, "load_overload", None)
    if original is None or not hasattr(cls, "_load_overload") or not hasattr(cls, "_guard_against_spurious_io_errors"):
        return False  # a numba whose cache is built otherwise: left alone
    if getattr(original, "_inskit_light", False):
        return True
    cls.load_overload = _light_load_overload(original)
    return True


class _Loader:
    """The loader of ``numba.core.caching`` that patches it once executed."""

    def __init__(self, inner):
        self.inner = inner

    def create_module(self, spec):
        return self.inner.create_module(spec)

    def exec_module(self, module):
        self.inner.exec_module(module)
        try:
            patch(module)
        except Exception:  # noqa: BLE001 (a speed-up only)
            pass

    def __getattr__(self, name):  # get_code, get_source, is_package ... of the module's own loader
        return getattr(self.inner, name)


class _Finder:
    """A ``sys.meta_path`` finder that, when ``numba.core.caching`` is first
    looked for, finds it through the other finders with a loader that
    patches it (:func:`patch`), then removes itself."""

    def find_spec(self, name, path=None, target=None):
        if name != _TRIGGER:
            return None
        try:
            sys.meta_path.remove(self)
        except ValueError:
            pass
        try:
            import importlib.util

            spec = importlib.util.find_spec(name)
            if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
                return None
            spec.loader = _Loader(spec.loader)
            return spec
        except Exception:  # noqa: BLE001 (numba then imports it its own way)
            return None


def install(preload_blas=None) -> None:
    """Patch numba's function cache now if it is imported, else when it is
    (not with ``INSKIT_NUMBA_REFRESH=1``); ``preload_blas()`` loads scipy's
    BLAS for a loaded function that calls it (:func:`._numba_blas.preload`:
    passed in, the two modules being of one layer)."""
    global _PRELOAD_BLAS
    if os.environ.get("INSKIT_NUMBA_REFRESH") == "1":
        return
    _PRELOAD_BLAS = preload_blas
    if _TRIGGER in sys.modules:
        try:
            patch(sys.modules[_TRIGGER])
        except Exception:  # noqa: BLE001 (a speed-up only)
            pass
        return
    if any(isinstance(f, _Finder) for f in sys.meta_path):
        return
    sys.meta_path.insert(0, _Finder())
