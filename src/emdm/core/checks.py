"""One-line checks of values: a scenario's raw data (:mod:`emdm.core.validation`) and the
arguments of the Python API (``emdm.simulate``, ``emdm.PlanarArm``, ``emdm.QP``, ...).

Every failed check is a :class:`~emdm.errors.ScenarioError` naming the source (the file, or the
function of the API), the key (or the argument) and what is wrong, on one line:
``"simulate: fallback: must be a list of solver names, got 'daqp'"``. The checks run once at
the entry of a public function, never in the compiled kernels.
"""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import ScenarioError

F64 = NDArray[np.float64]


def memory_available() -> int:
    """The machine's physical memory (bytes), or 0 when the system does not say."""
    try:
        return int(os.sysconf("SC_PHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return 0


def _name(key: Any) -> str:
    """A key as written in messages: plain when it looks like one, else quoted (repr)."""
    text = str(key)
    return text if text.isidentifier() else repr(key)


def _show(value: Any) -> str:
    if isinstance(value, np.ndarray):
        return f"an array of shape {value.shape}"
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _expect(shape: tuple[int | None, ...] | None) -> str:
    """What an array of ``shape`` is called in a message (None: any length on that axis)."""
    if shape is None:
        return "numbers"
    if len(shape) == 1:
        return "a list of numbers" if shape[0] is None else f"a list of {shape[0]} numbers"
    if len(shape) == 2 and shape[0] is None:
        return "rows of numbers" if shape[1] is None else f"rows of {shape[1]} numbers"
    return " x ".join("any" if s is None else str(s) for s in shape) + " numbers"


class _Checker:
    """Reads one raw value at a time, raising ScenarioError with the source and the key."""

    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, key: str, problem: str) -> ScenarioError:
        return ScenarioError(self.source, key, problem)

    # ------------------------------------------------------------------ scenario data (TOML)
    def number(self, key: str, value: Any) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(key, f"must be a number, got {_show(value)}")
        try:
            number = float(value)
        except OverflowError:  # an integer beyond the float range
            digits = len(str(abs(value)))
            raise self.fail(key, f"must be finite, got an integer of {digits} digits") from None
        if not math.isfinite(number):
            raise self.fail(key, f"must be finite, got {value}")
        return number

    def table(self, key: str, value: Any, rows: int, cols: int) -> F64:
        if not isinstance(value, list) or len(value) != rows:
            raise self.fail(key, f"must be a list of {rows} rows of {cols} numbers")
        out = []
        for i, row in enumerate(value):
            if not isinstance(row, list) or len(row) != cols:
                raise self.fail(f"{key}[{i}]", f"must be a row of {cols} numbers, got {_show(row)}")
            out.append([self.number(f"{key}[{i}][{j}]", v) for j, v in enumerate(row)])
        return _frozen(out)

    def vector(self, key: str, value: Any, size: int, scalar_ok: bool) -> F64:
        if isinstance(value, list):
            if len(value) != size:
                raise self.fail(key, f"must have {size} values, got {len(value)}")
            return _frozen([self.number(f"{key}[{i}]", v) for i, v in enumerate(value)])
        if scalar_ok:
            return _frozen(np.full(size, self.number(key, value)))
        raise self.fail(key, f"must be a list of {size} numbers, got {_show(value)}")

    # ------------------------------------------------------------- arguments of the Python API
    def real(
        self, key: str, value: Any, *, positive: bool = False, nonnegative: bool = False
    ) -> float:
        """A finite number (numpy scalars too, never a bool), ``> 0`` (``positive``) or ``>= 0``
        (``nonnegative``) when asked."""
        if type(value) is float and math.isfinite(value):  # the common case first
            number = value
        elif isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
            raise self.fail(key, f"must be a number, got {_show(value)}")
        else:
            raw: Any = value  # a Real: int, float, or another number that float() reads
            number = self.number(key, raw if isinstance(raw, int | float) else float(raw))
        if positive and not number > 0.0:
            raise self.fail(key, f"must be > 0, got {number:g}")
        if nonnegative and not number >= 0.0:
            raise self.fail(key, f"must be >= 0, got {number:g}")
        return number

    def count(self, key: str, value: Any, low: int, high: int) -> int:
        """An integer (numpy integers too, never a bool) in ``[low, high]``."""
        if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Integral):
            raise self.fail(key, f"must be an integer, got {_show(value)}")
        if not low <= int(value) <= high:
            raise self.fail(key, f"must be between {low} and {high}, got {int(value)}")
        return int(value)

    def flag(self, key: str, value: Any) -> bool:
        """True or False (a numpy bool too)."""
        if not isinstance(value, bool | np.bool_):
            raise self.fail(key, f"must be True or False, got {_show(value)}")
        return bool(value)

    def text(self, key: str, value: Any, what: str) -> str:
        """A non-empty string, described as ``what`` when it is not one."""
        if not isinstance(value, str) or not value:
            raise self.fail(key, f"must be {what}, got {_show(value)}")
        return value

    def names(self, key: str, value: Any, what: str) -> list[str]:
        """A list (or tuple) of strings; one string alone is refused (it is not a list)."""
        if not isinstance(value, list | tuple):  # a string alone is not a list of them
            raise self.fail(key, f"must be a list of {what}, got {_show(value)}")
        for item in value:
            if not isinstance(item, str):
                raise self.fail(key, f"must be a list of {what}, got {_show(item)} in it")
        return value if type(value) is list else list(value)

    def mapping(self, key: str, value: Any, what: str) -> Mapping[str, Any]:
        """A mapping whose keys are strings."""
        if not isinstance(value, Mapping):
            raise self.fail(key, f"must be a mapping of {what}, got {_show(value)}")
        for item in value:
            if not isinstance(item, str):
                raise self.fail(key, f"must be a mapping of {what}, got the key {_show(item)}")
        return value

    def instance(self, key: str, value: Any, kind: type | tuple[type, ...], what: str) -> None:
        """``value`` is a ``kind`` (described as ``what`` in the message)."""
        if not isinstance(value, kind):
            raise self.fail(key, f"must be {what}, got {_show(value)}")

    def array(
        self,
        key: str,
        value: Any,
        shape: tuple[int | None, ...] | None,
        *,
        finite: bool | None = True,
        what: str | Callable[[], str] | None = None,
    ) -> F64:
        """``value`` (an array, a list or nested lists of numbers) as a float array of ``shape``
        (None: any shape; an axis None: any length on it), every entry finite (``finite``), not
        NaN (``False``) or unchecked (``None``); ``what`` describes it in messages (a function
        giving the text: formatted only for a message). A float64 array is returned as it is
        (no copy)."""
        if isinstance(value, np.ndarray) and value.dtype.char == "d":
            arr = value
        else:
            if value is None or isinstance(value, str | bytes | Mapping | bool | np.bool_):
                raise self.fail(key, f"must be {_described(what, shape)}, got {_show(value)}")
            try:
                raw = np.asarray(value)
            except (TypeError, ValueError):  # ragged nested lists
                raise self.fail(
                    key, f"must be {_described(what, shape)}, got {_show(value)}"
                ) from None
            if raw.dtype.kind not in "iuf":  # bools, strings, objects (None, ragged), complex
                raise self.fail(key, f"must be {_described(what, shape)}, got {_show(value)}")
            arr = raw.astype(np.float64)
        if shape is not None and arr.shape != shape:  # or an axis of any length
            got = arr.shape
            if len(got) != len(shape) or any(
                want is not None and size != want for size, want in zip(got, shape, strict=True)
            ):
                raise self.fail(key, f"must be {_described(what, shape)}, got shape {got}")
        if finite is not None:
            if arr.size <= 16:  # a few values: faster in Python than through numpy's ufuncs
                clean = all(map(math.isfinite, arr.ravel().tolist()))
            else:
                clean = bool(np.isfinite(arr).all())
            if not clean:  # NaN or inf somewhere
                if finite:
                    raise self.fail(key, f"must be finite, got {_first_bad(arr, np.isfinite)}")
                if np.isnan(arr).any():
                    bad = _first_bad(arr, lambda a: ~np.isnan(a))
                    raise self.fail(key, f"must not be NaN, got {bad}")
        return arr


def _described(what: str | Callable[[], str] | None, shape: tuple[int | None, ...] | None) -> str:
    """What an argument must be, for a message: ``what`` (called if a function) or its shape."""
    if what is None:
        return _expect(shape)
    return what() if callable(what) else what


def _first_bad(arr: F64, good: Any) -> str:
    """The first entry of ``arr`` that is not ``good``, and where it is."""
    index = tuple(int(i) for i in np.argwhere(~good(arr))[0])
    where = f" at {list(index)}" if arr.ndim else ""
    return f"{arr[index]}{where}"


def _frozen(values: Any) -> F64:
    arr = np.array(values, dtype=float)
    arr.setflags(write=False)
    return arr
