"""The compiler behind every per-step formula: numba, with an on-disk cache and a cycle counter.

Every kernel is compiled with ``cache=True``: the first process on a machine compiles those its
run needs (on two cores 15 s for a plain planar run, 40 s for any other, announced by
:func:`ensure_compiled` in one line, a helper process compiling a share of them into the same
folder meanwhile) and writes the machine code to a cache folder, where every later process, and every
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

import contextlib
import functools
import hashlib
import importlib
import os
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from types import FunctionType
from typing import Any, TypeVar, cast, overload

from llvmlite import ir
from numba import types
from numba.core import caching, sigutils
from numba.core.compiler_lock import global_compiler_lock
from numba.core.registry import CPUDispatcher
from numba.extending import intrinsic

try:
    import fcntl
except ImportError:  # Windows: one process compiles, without the lock files
    fcntl = None  # type: ignore[assignment]

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
_normalize: Callable[[Any], Any] = sigutils.normalize_signature


class Kernel(CPUDispatcher):
    """numba's dispatcher, with two changes that cut the compile time of a first use.

    A kernel called from another with a constant argument (``f(x, 0)``), or with a variable
    numba has typed only in part so far (``f = 0`` before the ``f += 1`` of a loop), would be
    compiled once for that literal value and again for its type: a kernel called from kernels
    is compiled for the plain types only (no kernel needs a literal argument).

    An internal kernel (``@kernel(internal=True)``) has no entry point for Python: numba
    builds none (the CPython wrapper that unboxes every argument) and a call from Python raises
    ``TypeError`` instead of calling it. With the literal types, 12 % of a plain planar first use
    (42.0 to 37.1 s).
    """

    def get_call_template(self, args: Any, kws: Any) -> Any:
        plain_args = tuple(_unliteral(a) for a in args)
        return super().get_call_template(plain_args, {k: _unliteral(v) for k, v in kws.items()})

    def compile(self, sig: Any) -> Any:
        args, _ = _normalize(sig)
        if tuple(args) in self.overloads:  # compiled or loaded in this process
            return super().compile(sig)
        with global_compiler_lock, _shared_lock(self):
            return super().compile(sig)

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
    warm_up: Callable[[], object],
    *,
    what: str = "the control loop",
    notice_after: float = 2.0,
    helper: Callable[[], object] | None = None,
) -> None:
    """Run ``warm_up`` (which calls a group of kernels once) the first time in this process.

    When it takes longer than ``notice_after`` seconds (a compile, not a cache load), one line on
    stderr says so and, when done, how long it took.

    ``helper`` (a module-level function) compiles a share of the same kernels: when ``warm_up``
    compiles, a second process runs it at the same time, filling the cache folder that both
    share (see :func:`_start_helper`).
    """
    if warm_up in _compiled:
        return
    with _lock:
        if warm_up not in _compiled:
            _first_use(warm_up, what, notice_after, helper)
            _compiled.add(warm_up)


def _first_use(
    warm_up: Callable[[], object],
    what: str,
    notice_after: float,
    helper: Callable[[], object] | None = None,
) -> None:
    start = time.perf_counter()
    failure: list[BaseException] = []

    def run() -> None:
        try:
            warm_up()
        except BaseException as exc:  # handed to the caller's thread below
            failure.append(exc)

    worker = threading.Thread(target=run, daemon=True)
    process = None
    try:
        worker.start()
        if helper is not None and _empty_cache():  # a first use: no need to wait and see
            process = _start_helper(helper)
        worker.join(notice_after)
        if worker.is_alive():
            if helper is not None and process is None:
                process = _start_helper(helper)
            print(
                f"emdm: compiling {what} (once per installation; cached for later runs)...",
                end="",
                file=sys.stderr,
                flush=True,
            )
            worker.join()
            print(f" done in {time.perf_counter() - start:.1f} s", file=sys.stderr, flush=True)
    finally:  # also on Ctrl-C: no process outlives this one's need of it
        _stop_helper(process)
    if failure:
        raise failure[0]


# ---------------------------------------------------------------- two processes, one cache
def _empty_cache() -> bool:
    """Whether the kernel cache folder holds no compiled kernel yet (False: unknown, as when
    ``NUMBA_CACHE_DIR`` chooses the folder)."""
    folder = _cache_folder()
    return folder is not None and not any(Path(folder).rglob("*.nbi"))


def _start_helper(helper: Callable[[], object]) -> subprocess.Popen[bytes] | None:
    """Start a Python process that runs ``helper`` (and nothing else: no output, no input).

    numba compiles on one core, and a first use is a tree of kernels whose root links the machine
    code of the rest: a second process that compiles a subtree into the shared cache folder
    halves the time of that share on a machine with two cores, the first process loading from
    the cache what it finds there when it gets to it. Both processes hold a lock file per kernel
    while they compile or load it (:func:`_shared_lock`), so a kernel the other process is
    compiling is waited for, not compiled twice. The helper ends when its share is compiled, when
    it fails (the first process then compiles that share itself), when this process is done
    (:func:`_stop_helper`) and when this process ends in any way (it watches its parent). None
    where the kernels are compiled in memory only (no cache folder to share) or the process
    cannot start."""
    if _uncached or fcntl is None:
        return None
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(PACKAGE.parent), env.get("PYTHONPATH")]))
    code = "from emdm.core.jit import _helper_main; _helper_main()"
    args = [helper.__module__, helper.__qualname__, str(os.getpid())]
    try:
        return subprocess.Popen(
            [sys.executable, "-c", code, *args],
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    except OSError:
        return None


def _stop_helper(process: subprocess.Popen[bytes] | None) -> None:
    """End the helper process if it still runs (its share is no longer needed)."""
    if process is None or process.poll() is not None:
        return
    process.terminate()
    try:
        process.wait(timeout=5)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


def _helper_main() -> None:
    """The helper process of :func:`_start_helper`: ``python -c ... module function parent``."""
    module, name, parent = sys.argv[1], sys.argv[2], int(sys.argv[3])

    def watch() -> None:  # the parent gone (killed, crashed), this process ends too
        while os.getppid() == parent:
            time.sleep(0.2)
        os._exit(1)

    threading.Thread(target=watch, daemon=True).start()
    getattr(importlib.import_module(module), name)()


LOCK_WAIT = 300.0
"""Seconds a process waits for another one's compile of a kernel before it compiles it too."""

_held: set[str] = set()


@contextlib.contextmanager
def _shared_lock(compiled: Any) -> Iterator[None]:
    """Hold the lock file of kernel ``compiled`` in its cache folder (exclusive, across
    processes) while it is loaded or compiled and saved.

    numba's cache is an index file per kernel, naming one data file per compiled signature, which
    every process reads and rewrites without a lock: two processes saving two signatures of one
    kernel at once could each number its data file 1, leaving an index that names the other's
    machine code. Holding this lock makes a save whole, and lets a process that needs a kernel
    the other one is compiling wait for it and load it. The locks are taken in the order of the
    calls (a kernel is compiled before the kernels that call it are done), so two processes
    cannot wait for each other; the system releases a lock when its process ends. No lock (and
    no wait) where the platform has no ``flock`` or the folder is not writable."""
    path = _lock_path(compiled)
    if path is None:
        yield
        return
    if path in _held:  # this process holds it (the kernel is being compiled further up)
        yield
        return
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError:
        yield
        return
    try:
        deadline = time.monotonic() + LOCK_WAIT
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except OSError:
                if time.monotonic() > deadline:
                    break
                time.sleep(0.01)
        _held.add(path)
        try:
            yield
        finally:
            _held.discard(path)
    finally:
        os.close(fd)  # releases the lock


def _lock_path(compiled: Any) -> str | None:
    """The lock file of kernel ``compiled`` in its cache folder (None: no cache folder or no
    ``flock`` on this platform)."""
    folder = getattr(compiled._cache, "cache_path", None)
    if fcntl is None or folder is None:
        return None
    return os.path.join(
        folder, f"{compiled.py_func.__module__}.{compiled.py_func.__qualname__}.lock"
    )


def compile_for(compiled: Any, *args: Any, unless_busy: bool = False) -> None:
    """Compile (or load) kernel ``compiled`` for the types of ``args``, without calling it: for
    internal kernels (:class:`Kernel`) in a helper's share. ``unless_busy``: not when another
    process holds its lock (it is compiling that kernel: the helper goes on to the next)."""
    if unless_busy and _busy(compiled):
        return
    compiled.compile(tuple(compiled.typeof_pyval(a) for a in args))


def _busy(compiled: Any) -> bool:
    """Whether another process holds the lock of kernel ``compiled`` (:func:`_shared_lock`)."""
    path = _lock_path(compiled)
    if path is None or path in _held:
        return False
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return True
    finally:
        os.close(fd)  # releases the lock when this process took it
    return False


def plain(compiled: F) -> F:
    """The Python function behind a kernel, calling the Python functions behind the kernels it
    calls: for builders of buffers called from Python, which would otherwise pay numba's cost of
    boxing the NamedTuple they return, and the compile of every builder (with its entry point for
    Python) on a first use. Their arrays are the same as the compiled builders' (numpy's)."""
    return cast(F, _python(compiled))


@functools.cache
def _python(compiled: Any) -> Any:
    function = getattr(compiled, "py_func", compiled)
    namespace = function.__globals__
    kernels = {
        name: _python(namespace[name])
        for name in function.__code__.co_names
        if isinstance(namespace.get(name), Kernel)
    }
    if not kernels:
        return function
    return FunctionType(
        function.__code__,
        {**namespace, **kernels},
        function.__name__,
        function.__defaults__,
        function.__closure__,
    )
