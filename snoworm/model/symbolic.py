"""Symbolic floats and arrays for tracing the chain kernel into float code (:mod:`snoworm.model.floatkernel`).

:class:`Expr` is one symbolic float: arithmetic on it records a line of Python (``t12 = t7 * t3``)
in the active :class:`Trace`; :class:`SymArray` is an object array of them and of plain floats
whose NumPy operations are traced element by element (``maximum``/``minimum`` become conditional
expressions, ``tanh``/``sin``/``arctan``/``sqrt``/``exp`` the :mod:`math` functions, ``interp`` a
bisection with NumPy's formula, :func:`interp`); operations on floats alone are computed at once
by the same NumPy operation.  A Python branch on a symbol raises ``TypeError`` (the kernel cannot
be traced then).
"""

from __future__ import annotations

import bisect
from contextlib import contextmanager

import numpy as np

__all__ = ["Expr", "SymArray", "SymTable", "Trace", "interp", "slopes", "source", "symbols", "tracing"]

_TRACE = None  # the trace being recorded (tracing is single-threaded and short)


class Trace:
    """Lines recorded while the kernel runs on symbols, and the tables they refer to."""

    def __init__(self):
        self.lines = []  # (name, source, names used)
        self.consts = {}
        self.n = 0

    def emit(self, src, deps):
        name = f"t{self.n}"
        self.n += 1
        self.lines.append((name, src, deps))
        return Expr(name)

    def table(self, obj, prefix):
        name = f"_{prefix}{len(self.consts)}"
        self.consts[name] = obj
        return name


def _src(a):
    if isinstance(a, Expr):
        return a.name
    r = repr(float(a))
    return f"({r})" if r.startswith("-") or "e" in r or r in ("inf", "nan") else r


#: the Python source of a symbol or a float constant (for generated code)
source = _src


def _deps(*args):
    return tuple(a.name for a in args if isinstance(a, Expr))


def _num(a):
    return not isinstance(a, Expr)


def _operator(op, reflected=False):
    """``Expr``'s binary operator ``op`` (``reflected``: the Expr is the right operand)."""

    def f(self, other):
        return self._bin(op, other, self) if reflected else self._bin(op, self, other)

    return f


class Expr:
    """A symbolic float: the name of a generated variable; arithmetic on it records a line."""

    __slots__ = ("name",)

    def __init__(self, name):
        self.name = name

    def _bin(self, op, a, b):
        if op == "*" and (_num(a) and a == 1.0):
            return b
        if op in ("*", "/") and (_num(b) and b == 1.0):
            return a
        if op in ("+", "-") and _num(b) and b == 0.0:
            return a
        if op == "+" and _num(a) and a == 0.0:
            return b
        return _TRACE.emit(f"{_src(a)} {op} {_src(b)}", _deps(a, b))

    __add__, __radd__ = _operator("+"), _operator("+", reflected=True)
    __sub__, __rsub__ = _operator("-"), _operator("-", reflected=True)
    __mul__, __rmul__ = _operator("*"), _operator("*", reflected=True)
    __truediv__, __rtruediv__ = _operator("/"), _operator("/", reflected=True)
    __pow__, __rpow__ = _operator("**"), _operator("**", reflected=True)

    def __neg__(self):
        return _TRACE.emit(f"-{self.name}", (self.name,))

    def __pos__(self):
        return self

    def __abs__(self):
        return _TRACE.emit(f"abs({self.name})", (self.name,))

    def __float__(self):
        raise TypeError("a symbolic value has no float value: the kernel converted a state to float")

    def __bool__(self):
        raise TypeError("the kernel branches on a state value: it cannot be traced to float code")


class SymTable(Expr):
    """A symbolic table: a tuple of floats passed to the generated code at run time (an X_t or
    elevation table, a constant profile's one value).  Its length is known at trace time (it is
    part of the generated code's key); its items are symbols."""

    __slots__ = ("length",)

    def __init__(self, name, length):
        super().__init__(name)
        self.length = int(length)

    def __len__(self):
        return self.length

    def __getitem__(self, k):
        if not isinstance(k, int) or not -self.length <= k < self.length:
            raise TypeError(f"a symbolic table of length {self.length} is indexed with {k!r}")
        return _TRACE.emit(f"{self.name}[{k}]", (self.name,))

    def __iter__(self):
        return (self[k] for k in range(self.length))


def _unary(fname, ufunc):
    def f(a):
        return float(ufunc(a)) if _num(a) else _TRACE.emit(f"{fname}({a.name})", (a.name,))

    return f


def _maximum(a, b):
    if _num(a) and _num(b):
        return float(np.maximum(a, b))
    return _TRACE.emit(f"{_src(a)} if {_src(a)} >= {_src(b)} else {_src(b)}", _deps(a, a, b, b))


def _minimum(a, b):
    if _num(a) and _num(b):
        return float(np.minimum(a, b))
    return _TRACE.emit(f"{_src(a)} if {_src(a)} <= {_src(b)} else {_src(b)}", _deps(a, a, b, b))


#: NumPy ufuncs traced element by element (the others run on object arrays, calling Expr's operators)
_ELEMENTWISE = {
    np.maximum: _maximum,
    np.minimum: _minimum,
    np.tanh: _unary("_tanh", np.tanh),
    np.sin: _unary("_sin", np.sin),
    np.arctan: _unary("_atan", np.arctan),
    np.sqrt: _unary("_sqrt", np.sqrt),
    np.exp: _unary("_exp", np.exp),
}


def _plain(a):
    if isinstance(a, SymArray):
        return a.view(np.ndarray)
    if isinstance(a, (tuple, list)):
        return type(a)(_plain(x) for x in a)
    if isinstance(a, np.ndarray) and a.dtype != object and a.dtype.kind == "f":
        return a.astype(object)  # Python floats: arithmetic with symbols folds exactly
    return a


def _wrap(r):
    if isinstance(r, np.ndarray) and r.dtype == object:
        return r.view(SymArray)
    if isinstance(r, tuple):
        return tuple(_wrap(x) for x in r)
    return r


class SymArray(np.ndarray):
    """An object array of :class:`Expr` and floats whose NumPy operations are recorded."""

    def __array_ufunc__(self, ufunc, method, *inputs, **kwargs):
        if method == "__call__" and ufunc in _ELEMENTWISE and not kwargs:
            f = np.frompyfunc(_ELEMENTWISE[ufunc], ufunc.nin, 1)
            return _wrap(np.asarray(f(*[_plain(a) for a in inputs]), dtype=object))
        if ufunc in _ELEMENTWISE or (
            ufunc in (np.greater, np.less, np.equal, np.not_equal, np.greater_equal, np.less_equal)
        ):
            raise TypeError(f"cannot trace {ufunc.__name__}.{method} on states to float code")
        kw = {k: _plain(v) for k, v in kwargs.items()}
        return _wrap(getattr(ufunc, method)(*[_plain(a) for a in inputs], **kw))

    def __array_function__(self, func, types, args, kwargs):
        if func is np.interp:
            return _interp_traced(*args, **kwargs)
        return _wrap(func(*_plain(args), **{k: _plain(v) for k, v in kwargs.items()}))


def interp(x, xp, fp, slopes):
    """``numpy.interp(x, xp, fp)`` for one float (the same formula, table held beyond its ends)."""
    if x <= xp[0]:
        return fp[0]
    if x >= xp[-1]:
        return fp[-1]
    j = bisect.bisect_right(xp, x) - 1
    return slopes[j] * (x - xp[j]) + fp[j]


def slopes(xp, fp):
    """The slopes of the segments of the table ``(xp, fp)``, as :func:`interp` reads them."""
    return tuple((fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j]) for j in range(len(xp) - 1))


def _interp_traced(x, xp, fp, left=None, right=None, period=None):
    """``np.interp`` on symbols: literal tables become constants of the generated code, symbolic
    tables (:class:`SymTable`, run-time parameters) are read by name and their slopes computed once
    per model (a line on parameters alone)."""
    if left is not None or right is not None or period is not None:
        raise TypeError("float kernel: interp with left/right/period is not supported")
    symbolic = isinstance(xp, SymTable) or isinstance(fp, SymTable)
    if not symbolic:
        xp, fp = tuple(float(v) for v in xp), tuple(float(v) for v in fp)
    names = None

    def table_names():
        if symbolic:
            xs, fs = (t.name if isinstance(t, SymTable) else _TRACE.table(t, p) for t, p in ((xp, "XP"), (fp, "FP")))
            sl = _TRACE.emit(f"_slopes({xs}, {fs})", _deps(*(t for t in (xp, fp) if isinstance(t, SymTable))))
            return [xs, fs, sl.name]
        return [_TRACE.table(v, p) for v, p in ((xp, "XP"), (fp, "FP"), (slopes(xp, fp), "SL"))]

    def one(a):
        nonlocal names
        if _num(a) and not symbolic:
            return float(np.interp(a, xp, fp))
        if names is None:
            names = table_names()
        deps = tuple(n for n in names if not n.startswith("_")) + _deps(a)
        return _TRACE.emit(f"_interp({_src(a)}, {', '.join(names)})", deps)

    return _wrap(np.asarray(np.frompyfunc(one, 1, 1)(_plain(x)), dtype=object))


def symbols(prefix, shape):
    arr = np.empty(shape, dtype=object)
    flat = arr.reshape(-1)
    for k in range(flat.size):
        flat[k] = Expr(f"{prefix}{k}")
    return arr.view(SymArray)


@contextmanager
def tracing():
    """Record the operations on symbols made inside the block into a new :class:`Trace` (yielded)."""
    global _TRACE
    _TRACE = tr = Trace()
    try:
        yield tr
    finally:
        _TRACE = None
