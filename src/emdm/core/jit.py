"""The compiler behind every per-step formula: numba, with an on-disk cache and a cycle counter.

Every kernel is compiled with ``cache=True``: the first process on a machine compiles those its
run needs (37 s for a plain planar run, 58 s for any other, announced by :func:`ensure_compiled`
in one line) and writes the machine code to a cache folder, where every later process, and every
Dask worker on the same machine, loads it in a fraction of a second. The folder is
``$XDG_CACHE_HOME/emdm/kernels-<hash>`` (``~/.cache`` by default), the hash covering every module
that defines kernels: numba checks only the file of a kernel itself, so a change to a kernel it
calls would otherwise load stale machine code. Setting
``NUMBA_CACHE_DIR`` chooses the folder instead.

:func:`ticks` reads the processor's cycle counter from inside a kernel (``llvm.readcyclecounter``,
the time-stamp counter on x86), so a compiled loop can time each solve without leaving compiled
code; :func:`seconds_per_tick` converts ticks to seconds, calibrated once per process against
``time.perf_counter``. Where the platform has no such counter, ticks are 0 and solve times NaN.
"""

from __future__ import annotations

import functools
import hashlib
import os
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar, cast, overload

from llvmlite import ir
from numba import types
from numba.core import caching
from numba.core.registry import CPUDispatcher
from numba.extending import intrinsic

F = TypeVar("F", bound=Callable[..., Any])


PACKAGE = Path(__file__).resolve().parent.parent


@functools.cache
def _cache_folder() -> str | None:
    """``$XDG_CACHE_HOME/emdm/kernels-<hash of the compiled sources>``, or None when
    ``NUMBA_CACHE_DIR`` is set (numba's own choice then stands). The compiled sources are the
    modules that define kernels (they mention ``@kernel``), this one and the tolerances they read
    (``tolerances.py``) included."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    digest = hashlib.sha256()
    for path in sorted(PACKAGE.rglob("*.py")):
        text = path.read_bytes()
        if b"@kernel" in text or path.name in ("jit.py", "tolerances.py"):
            digest.update(path.relative_to(PACKAGE).as_posix().encode())
            digest.update(text)
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return str(base / "emdm" / f"kernels-{digest.hexdigest()[:16]}")


def _register_cache_locator() -> None:
    """Make numba cache emdm's kernels (and only those) in :func:`_cache_folder`."""
    base = getattr(caching, "UserProvidedCacheLocator", None) or getattr(
        caching, "_UserProvidedCacheLocator", None
    )
    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    if base is None or impl is None:  # another numba layout: its default locators stand
        return

    class SourceHashLocator(base):  # type: ignore[misc, valid-type]
        def __init__(self, py_func: Any, py_file: str, folder: str) -> None:
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            self._cache_path = os.path.join(folder, self.get_suitable_cache_subpath(py_file))

        @classmethod
        def from_function(cls, py_func: Any, py_file: str) -> Any:
            folder = _cache_folder()
            if folder is None or not Path(py_file).resolve().is_relative_to(PACKAGE):
                return None
            try:
                locator = cls(py_func, py_file, folder)
                locator.ensure_cache_path()
            except OSError:  # not writable: numba's next locator
                return None
            return locator

    impl._locator_classes.insert(0, SourceHashLocator)


_register_cache_locator()  # before any kernel below (or in other modules) is decorated


_uncached: list[str] = []
BORROWING: list[Any] = []
"""The kernels compiled without reference counting (``@kernel(refcount=False)``)."""


_unliteral: Callable[[Any], Any] = types.unliteral


class Kernel(CPUDispatcher):
    """numba's dispatcher, with two changes that cut the compile time of a first use.

    A kernel called from another with a constant argument (``f(x, 0)``), or with a variable
    numba has typed only in part so far (``f = 0`` before the ``f += 1`` of a loop), would be
    compiled once for that literal value and again for its type: a kernel called from kernels
    is compiled for the plain types only (no kernel needs a literal argument).

    An internal kernel (``@kernel(internal=True)``) has no entry point for Python: numba
    builds none (the CPython wrapper that unboxes every argument, about 10 % of the compile
    time of a first use) and a call from Python raises ``TypeError`` instead of calling it.
    """

    def get_call_template(self, args: Any, kws: Any) -> Any:
        plain_args = tuple(_unliteral(a) for a in args)
        return super().get_call_template(plain_args, {k: _unliteral(v) for k, v in kws.items()})

    def add_overload(self, cres: Any) -> None:
        if self.targetoptions.get("no_cpython_wrapper"):
            self.overloads[tuple(cres.signature.args)] = cres  # callable from kernels only
        else:
            super().add_overload(cres)

    def _compile_for_args(self, *args: Any, **kws: Any) -> Any:
        if self.targetoptions.get("no_cpython_wrapper"):
            raise TypeError(f"{self.py_func.__qualname__} is a kernel called only from kernels")
        return super()._compile_for_args(*args, **kws)  # type: ignore[misc]


def _dispatcher(function: Callable[..., Any], options: dict[str, Any], cache: bool) -> Kernel:
    """``numba.njit(cache=cache, **options)(function)``, as a :class:`Kernel`."""
    compiled = Kernel(
        py_func=function,
        locals={},
        targetoptions={"nopython": True, "boundscheck": None, **options},
    )
    if cache:
        compiled.enable_caching()
    return compiled


@overload
def kernel(function: F) -> F: ...
@overload
def kernel(
    *, refcount: bool = True, inline: bool = False, internal: bool = False
) -> Callable[[F], F]: ...
def kernel(
    function: F | None = None,
    *,
    refcount: bool = True,
    inline: bool = False,
    internal: bool = False,
) -> Any:
    """Compile ``function`` in nopython mode, cached on disk (the one decorator of every kernel).

    ``@kernel(inline=True)`` compiles the function into each kernel that calls it (numba's
    ``inline="always"``): for the small helpers that return views of a work buffer to kernels
    that borrow, which then count no reference for them either.

    ``@kernel(internal=True)`` marks a kernel that only other kernels call: it is compiled
    without an entry point for Python (:class:`Kernel`).

    ``@kernel(refcount=False)`` marks a kernel that only borrows arrays: it allocates none and
    returns none (nor a tuple holding one), so numba's reference counting is compiled out of it.
    That counting is an atomic increment and decrement, each a call, for every array a kernel is
    passed, work tuples included (a ``QPWork`` is 27 arrays): it was two thirds of the active
    set's warm solve (docs/architecture.md, "Kernels that borrow"). numba refuses to compile an
    allocation without it, and ``tests/test_sim.py`` checks that no such kernel returns
    an array. The hot path's kernels are all of this kind; those that allocate (buffers, the
    ``*_of`` entry points, the rare paths that call ``np.linalg``) keep the counting.

    Where no cache folder is writable (a read-only install and home, no ``NUMBA_CACHE_DIR``),
    numba refuses ``cache=True`` with a long traceback; the kernel is then compiled in memory for
    this process only, and one line on stderr says so (once) and how to keep the machine code.
    """
    if function is None:
        return functools.partial(kernel, refcount=refcount, inline=inline, internal=internal)
    # numba hands a caller's flags down to the kernels it calls unless they set their own: a
    # kernel that counts says so, so that it may allocate when a borrowing kernel calls it.
    # No kernel is called through a C function pointer: numba's wrapper for that is not built
    options: dict[str, Any] = {
        "nogil": True,
        "error_model": "numpy",
        "_nrt": refcount,
        "no_cfunc_wrapper": True,
        "no_cpython_wrapper": internal,
    }
    if inline:
        options["inline"] = "always"
    try:
        compiled = _dispatcher(function, options, cache=True)
    except RuntimeError as exc:  # "cannot cache function ...: no locator available"
        if "cache" not in str(exc):
            raise
        if not _uncached:
            print(
                "emdm: no writable cache folder for the compiled kernels; compiling in memory for "
                "this process (set NUMBA_CACHE_DIR to a writable folder to keep them)",
                file=sys.stderr,
            )
        _uncached.append(function.__name__)
        compiled = _dispatcher(function, options, cache=False)
    if not refcount:
        BORROWING.append(compiled)
    return cast(F, compiled)


@intrinsic
def _read_cycle_counter(typingctx: Any) -> Any:
    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        fn = builder.module.declare_intrinsic(
            "llvm.readcyclecounter", fnty=ir.FunctionType(ir.IntType(64), [])
        )
        return builder.call(fn, [])

    return types.int64(), codegen


@kernel
def ticks() -> int:
    """The processor's cycle counter (an arbitrary origin; 0 where the platform has none)."""
    return _read_cycle_counter()  # type: ignore[call-arg]


@functools.cache
def seconds_per_tick() -> float:
    """Seconds per :func:`ticks` unit, measured over 2 ms against ``time.perf_counter`` (NaN: no counter)."""
    ticks()  # compile or load before timing
    t0, c0 = time.perf_counter(), ticks()
    while time.perf_counter() - t0 < 2e-3:
        pass
    t1, c1 = time.perf_counter(), ticks()
    return (t1 - t0) / (c1 - c0) if c1 > c0 else float("nan")


_compiled: set[Callable[[], object]] = set()
_lock = threading.Lock()


def ensure_compiled(
    warm_up: Callable[[], object], *, what: str = "the control loop", notice_after: float = 2.0
) -> None:
    """Run ``warm_up`` (which calls a group of kernels once) the first time in this process.

    When it takes longer than ``notice_after`` seconds (a compile, not a cache load), one line on
    stderr says so and, when done, how long it took.
    """
    if warm_up in _compiled:
        return
    with _lock:
        if warm_up not in _compiled:
            _first_use(warm_up, what, notice_after)
            _compiled.add(warm_up)


def _first_use(warm_up: Callable[[], object], what: str, notice_after: float) -> None:
    start = time.perf_counter()
    failure: list[BaseException] = []

    def run() -> None:
        try:
            warm_up()
        except BaseException as exc:  # handed to the caller's thread below
            failure.append(exc)

    worker = threading.Thread(target=run, daemon=True)
    worker.start()
    worker.join(notice_after)
    if worker.is_alive():
        print(
            f"emdm: compiling {what} (once per installation; cached for later runs)...",
            end="",
            file=sys.stderr,
            flush=True,
        )
        worker.join()
        print(f" done in {time.perf_counter() - start:.1f} s", file=sys.stderr, flush=True)
    if failure:
        raise failure[0]


def plain(compiled: F) -> F:
    """The Python function behind a kernel: for builders of buffers called from Python, which
    would otherwise pay numba's cost of boxing the NamedTuple they return."""
    return cast(F, getattr(compiled, "py_func", compiled))
