"""Declarative validation of nested mappings into frozen dataclasses.

A config dataclass subclasses :class:`Config` and declares each field with :func:`field`, giving
its bounds, allowed choices, unit and help text.  Validation runs when the object is
constructed (values converted before the frozen object is made, by the metaclass of
:class:`Config`; rules across fields in ``Config.__post_init__``), however it is constructed:
from a mapping by :func:`build` (parsed YAML, which also rejects unknown keys with "did you mean" suggestions and
missing required values), directly from Python, or by :func:`dataclasses.replace`.  Wrong types
and values out of bounds raise a one-paragraph :class:`ScenarioError` that names the dotted
field and says how to fix it.  NumPy scalars and arrays are accepted where numbers and lists
are.  :func:`dump` turns the dataclass back into plain YAML-able data.
"""

from __future__ import annotations

import contextvars
import dataclasses
import difflib
import functools
import math
import numbers
import operator
import os
import reprlib
import types
import typing
from collections.abc import Callable, Collection, Mapping
from typing import Any, NoReturn

import numpy as np

__all__ = [
    "Config",
    "ScenarioError",
    "field",
    "internal",
    "build",
    "dump",
    "suggest",
    "quote",
    "short_path",
    "short_key",
    "check_field",
    "domain_text",
]

_MISSING = dataclasses.MISSING
_C = typing.TypeVar("_C")


class ScenarioError(ValueError):
    """Bad user input: the message names the field and the fix (CLI exit status 2)."""


def field(
    default: Any = _MISSING,
    *,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
    choices: Collection[Any] | None = None,
    unit: str = "",
    doc: str = "",
    default_factory: Any = _MISSING,
    search: tuple[float, float] | None = None,
    why: str = "",
    convert: Callable[[Any, str], Any] | None = None,
) -> Any:
    """A dataclass field with validation metadata.

    Parameters
    ----------
    default : optional
        Default value; omit for a required field.
    gt, ge, lt, le : float, optional
        Strict/inclusive bounds for numbers (applied to each element of a sequence).
    choices : sequence, optional
        Allowed values.
    unit : str
        SI unit, shown in messages.
    doc : str
        One-line meaning, shown in messages.
    search : (float, float), optional
        Bounds of a parameter search over this value (``snoworm calibrate``); ``None``: not fitted.
    why : str
        Why the bounds are what they are (the physical domain, or what a larger value would cost),
        shown when a value is out of bounds.
    convert : callable, optional
        ``convert(value, path) -> value`` validates the value instead of its type annotation (e.g.
        the scenario's ``mode``, whose class depends on its ``type``).
    """
    md = dict(gt=gt, ge=ge, lt=lt, le=le, choices=choices, unit=unit, doc=doc, search=search, why=why, convert=convert)
    kw: dict[str, Any] = {"metadata": md}
    if default is not _MISSING:
        kw["default"] = default
    if default_factory is not _MISSING:
        kw["default_factory"] = default_factory
    return dataclasses.field(**kw)


#: Unit suffixes of the project's names (``force_N``, ``speed_mps``) -> the unit they stand for.
UNIT_SUFFIXES = {
    "N": "N",
    "Nm": "N m",
    "mps": "m/s",
    "m": "m",
    "s": "s",
    "kg": "kg",
    "W": "W",
    "J": "J",
    "Ns_per_m": "N s/m",
    "N_per_m": "N/m",
    "rad": "rad",
    "deg": "deg",
    "Hz": "Hz",
    "J_per_m": "J/m",
    "radps": "rad/s",
    "kgm2": "kg m2",
    "mps2": "m/s2",
    "Nms_per_rad": "N m s/rad",
    "Nm_per_rad": "N m/rad",
}


def split_unit(name: str) -> tuple[str, str | None]:
    """``(stem, unit)`` of a name ending in a unit suffix (``"force_N"`` -> ``("force", "N")``);
    ``(name, None)`` without one."""
    for suffix in sorted(UNIT_SUFFIXES, key=len, reverse=True):
        if name.endswith("_" + suffix) and len(name) > len(suffix) + 1:
            return name[: -len(suffix) - 1], UNIT_SUFFIXES[suffix]
    return name, None


def suggest(word: str, options: Collection[Any]) -> str:
    """A ' Did you mean ...?' suffix for a misspelt key, or ''."""
    if len(str(word)) > 100:  # no key or choice is that long (and difflib would take its time)
        return ""
    close = difflib.get_close_matches(str(word), [str(o) for o in options], n=3, cutoff=0.6)
    if not close:
        return ""
    return " Did you mean " + " or ".join(repr(c) for c in close) + "?"


def short_path(path: str | os.PathLike[str], limit: int = 200) -> str:
    """``path`` as text for a message, cut in its middle to about ``limit`` characters (its head
    and its file name kept): a 4 kB path is not echoed whole, once or several times."""
    text = os.fspath(path) if isinstance(path, os.PathLike) else str(path)
    if len(text) <= limit:
        return text
    tail = max(limit * 2 // 3, 1)
    return f"{text[: limit - tail]}...[{len(text) - limit} characters]...{text[-tail:]}"


def quote(value: Any, limit: int = 100) -> str:
    """The repr of ``value`` cut to ``limit`` characters, for error messages.

    Parameters
    ----------
    value : object
        Offending value; may be huge (a 2 MB string, a long list).
    limit : int
        Most characters of the repr kept.

    Returns
    -------
    str
        ``repr(value)`` if short, else its head and the total length: ``'xxxx...' (2000000 characters)``.
    """
    is_text = isinstance(value, (str, bytes, bytearray))
    try:  # reprlib shortens containers and other objects; only the head of a string is repr'd
        text = repr(value[: limit + 1]) if is_text else reprlib.repr(value)
    except ValueError:  # an int beyond Python's str-digit limit
        text = f"<{type(value).__name__}>"
    if len(text) <= limit and not (is_text and len(value) > limit):
        return text
    unit = "characters" if isinstance(value, str) else "bytes" if is_text else "items"
    return f"{text[:limit]}... ({len(value) if hasattr(value, '__len__') else '?'} {unit})"


def short_key(key: object, limit: int = 60) -> str:
    """A mapping key as written in a dotted path of a message, cut to ``limit`` characters."""
    text = str(key)
    return text if len(text) <= limit else f"{text[:limit]}..."


def domain_text(md: Mapping[str, Any]) -> str:
    """The interval of a field's bounds, e.g. ``(0, 1]`` or ``[0, 1e+06]``; '' when unbounded."""
    lo = md.get("gt") if md.get("gt") is not None else md.get("ge")
    hi = md.get("lt") if md.get("lt") is not None else md.get("le")
    if lo is None and hi is None:
        return ""
    left = "(" if md.get("gt") is not None or lo is None else "["
    right = ")" if md.get("lt") is not None or hi is None else "]"
    return f"{left}{'-inf' if lo is None else f'{lo:g}'}, {'inf' if hi is None else f'{hi:g}'}{right}"


def _fail(path: str, msg: str) -> NoReturn:
    raise ScenarioError(f"{path}: {msg}")


def _describe(md: Mapping[str, Any]) -> str:
    bits = []
    if md.get("doc"):
        bits.append(md["doc"])
    if md.get("unit"):
        bits.append(f"in {md['unit']}")
    return f" ({', '.join(bits)})" if bits else ""


#: The bounds a field may declare: metadata key, comparison that must hold, word for messages.
_BOUNDS = (
    ("gt", operator.gt, "greater than"),
    ("ge", operator.ge, "at least"),
    ("lt", operator.lt, "less than"),
    ("le", operator.le, "at most"),
)


def _check_number(path: str, value: Any, md: Mapping[str, Any], kind: type) -> Any:
    t = type(value)
    if t is not float and t is not int:  # plain YAML numbers skip straight to the checks below
        if isinstance(value, np.ndarray) and value.ndim == 0:
            value = value.item()
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
            if isinstance(value, str):
                try:
                    value = float(value)
                except ValueError:
                    _fail(
                        path,
                        f"expected a number{_describe(md)}, got the text {quote(value)}. Write a plain number, e.g. 1.5.",
                    )
            else:
                _fail(
                    path,
                    f"expected a number{_describe(md)}, got {type(value).__name__} {quote(value)}. Write a plain number.",
                )
    if isinstance(value, numbers.Integral):
        value = int(value)
        if abs(value) > 1e300:  # beyond any bound; float() of it would overflow
            _fail(path, f"must be a finite number{_describe(md)}, got an integer of {len(str(abs(value)))} digits.")
    elif not math.isfinite(float(value)):
        dom = f" in {domain_text(md)}" if domain_text(md) else ""
        _fail(path, f"must be a finite number{dom}{_describe(md)}, got {float(value)!r}.")
    if kind is int:
        if float(value) != int(value):
            _fail(path, f"expected a whole number{_describe(md)}, got {value!r}.")
        value = int(value)
    else:
        value = float(value)
    for key, holds, word in _BOUNDS:
        bound = md.get(key)
        if bound is not None and not holds(value, bound):
            unit = f" {md.get('unit')}" if md.get("unit") else ""
            why = f" {md['why']}" if md.get("why") else ""
            _fail(
                path,
                f"must be {word} {bound:g}{unit}{_describe(md)}, got {value:g}; the allowed range is "
                f"{domain_text(md)}.{why} Change it to a value {word} {bound:g}.",
            )
    return value


@functools.cache
def _type_info(tp: Any) -> tuple[Any, tuple[Any, ...], bool]:
    """``(origin, args, is a dataclass)`` of an annotation, computed once per type."""
    return typing.get_origin(tp), typing.get_args(tp), dataclasses.is_dataclass(tp)


def _convert(path: str, value: Any, tp: Any, md: Mapping[str, Any]) -> Any:  # noqa: C901, PLR0912 (one branch per kind of annotation: a flat dispatch)
    if md.get("convert") is not None:
        return md["convert"](value, path)
    origin, args, is_dc = _type_info(tp)
    if origin is typing.Union or origin is types.UnionType:  # Optional[X] or X | None
        if value is None and type(None) in args:
            return None
        non_none = [a for a in args if a is not type(None)]
        errors = []
        for a in non_none:
            try:
                return _convert(path, value, a, md)
            except ScenarioError as exc:
                errors.append(str(exc))
        raise ScenarioError(errors[-1])
    if is_dc:
        if isinstance(value, tp):  # constructed (and so validated) already
            return value
        if not isinstance(value, dict):
            _fail(path, f"expected a mapping of keys for {tp.__name__}, got {type(value).__name__} {quote(value)}.")
        return build(tp, value, path)
    if origin in (tuple, list):
        if isinstance(value, np.ndarray):
            value = value.tolist()
        if isinstance(value, (numbers.Real, str)) and not isinstance(value, (bool, np.bool_)):
            value = [value]
        if not isinstance(value, (list, tuple)):
            _fail(path, f"expected a list{_describe(md)}, got {type(value).__name__} {quote(value)}.")
        inner = args[0] if args else Any
        return tuple(_convert(f"{path}[{j}]", v, inner, md) for j, v in enumerate(value))
    if origin is dict:
        if not isinstance(value, dict):
            _fail(path, f"expected a mapping{_describe(md)}, got {type(value).__name__} {quote(value)}.")
        kt, vt = args
        out = {}
        for k, v in value.items():
            kk = _convert(f"{path}.{short_key(k)}", k, kt, {}) if kt is not Any else k
            out[kk] = _convert(f"{path}.{short_key(k)}", v, vt, md)
        return out
    if tp is float or tp is int:
        value = _check_number(path, value, md, tp)
    elif tp is bool:
        if not isinstance(value, bool):
            _fail(path, f"expected true or false{_describe(md)}, got {quote(value)}.")
    elif tp is str:
        if isinstance(value, np.str_):
            value = str(value)
        if not isinstance(value, str):
            _fail(path, f"expected text{_describe(md)}, got {type(value).__name__} {quote(value)}.")
    choices = md.get("choices")
    if choices is not None and value not in choices:
        _fail(
            path, f"must be one of {', '.join(repr(c) for c in choices)}; got {quote(value)}.{suggest(value, choices)}"
        )
    return value


@functools.cache
def _type_hints(cls: type) -> dict[str, Any]:
    """``typing.get_type_hints`` of a config class, resolved once (it compiles every annotation
    string on each call: ~10 ms per scenario before this cache, the main cost of a sweep case)."""
    return typing.get_type_hints(cls)


#: dotted path of the config section being built by :func:`build` (for messages)
_PATH: contextvars.ContextVar[str | None] = contextvars.ContextVar("snoworm_config_path", default=None)


def internal(default: Any = None) -> Any:
    """A field of a config object that is not a setting: not read from a scenario file, not
    validated, not written by :func:`dump`, not compared (e.g. where a scenario was read from)."""
    return dataclasses.field(default=default, compare=False, repr=False, metadata={"internal": True})


def _settings(cls: type) -> dict[str, dataclasses.Field]:
    """Name -> dataclass field of the settings of ``cls`` (its init fields but internal ones)."""
    return {f.name: f for f in dataclasses.fields(cls) if f.init and not f.metadata.get("internal")}


class _Validated(type):
    """Metaclass of :class:`Config`: converts and validates the values *before* the frozen
    dataclass is made, however it is made (a call, :func:`build`, :func:`dataclasses.replace`),
    so a config object is never changed after its construction."""

    def __call__(cls, *args: Any, **kwargs: Any) -> Any:
        if not dataclasses.is_dataclass(cls):
            return super().__call__(*args, **kwargs)
        fields = _settings(cls)
        names = [f.name for f in dataclasses.fields(cls) if f.init]
        if len(args) > len(names):
            return super().__call__(*args, **kwargs)  # the dataclass's own TypeError
        for name, value in zip(names, args):
            if name in kwargs:
                raise TypeError(f"{cls.__name__}() got multiple values for argument {name!r}")
            kwargs[name] = value
        path = _PATH.get()
        path = cls._section if path is None else path
        prefix = f"{path}." if path else ""
        hints = _type_hints(cls)
        for name, f in fields.items():
            if name in kwargs:
                value = kwargs[name]
            elif f.default is not _MISSING:
                value = f.default
            elif f.default_factory is not _MISSING:
                value = f.default_factory()
            else:
                continue  # missing: the dataclass's own TypeError
            kwargs[name] = _convert(f"{prefix}{name}", value, hints[name], f.metadata)
        return super().__call__(**kwargs)


class Config(metaclass=_Validated):
    """Base of the frozen config dataclasses: every field is validated on construction.

    Subclasses are ``@dataclass(frozen=True)`` with fields declared by :func:`field`; they may
    define ``_check(path)`` for rules across fields, and set ``_section`` (the dotted path used in
    messages when the object is constructed directly rather than by :func:`build`).  The values
    are converted (e.g. an int to a float, a list to a tuple) before the object is made (the
    metaclass), so nothing sets an attribute of a made config object.
    """

    _section = ""

    def __post_init__(self) -> None:
        path = _PATH.get()
        self._check(self._section if path is None else path)

    def _check(self, path: str) -> None:
        """Rules across fields (override); raise :class:`ScenarioError` naming ``path``."""


def build(cls: type[_C], data: dict, path: str = "", internal_values: Mapping[str, Any] | None = None) -> _C:
    """Validate ``data`` against dataclass ``cls`` and construct it.

    ``internal_values`` sets fields declared with :func:`internal` (never read from ``data``).

    Raises
    ------
    ScenarioError
        Unknown key (with suggestions), missing required key, wrong type or value out of bounds.
    """
    if data is None:
        data = {}
    if not isinstance(data, dict):
        _fail(path or "scenario", f"expected a mapping of keys, got {type(data).__name__} {quote(data)}.")
    fields = _settings(cls)
    prefix = f"{path}." if path else ""
    for key in data:
        if key not in fields:
            _fail(
                f"{prefix}{short_key(key)}", f"unknown key.{suggest(key, fields)} Known keys here: {', '.join(fields)}."
            )
    for name, f in fields.items():
        if name not in data and f.default is _MISSING and f.default_factory is _MISSING:
            _fail(f"{prefix}{name}", f"is required but missing{_describe(f.metadata)}. Add it to the scenario.")
    token = _PATH.set(path)
    try:
        if issubclass(cls, Config):
            return cls(**data, **(internal_values or {}))
        hints = _type_hints(typing.cast(type, cls))  # a plain dataclass: convert here
        return cls(**{k: _convert(f"{prefix}{k}", v, hints[k], fields[k].metadata) for k, v in data.items()})
    finally:
        _PATH.reset(token)


def check_field(cls: type, name: str, value: object, path: str | None = None) -> Any:
    """Validate one value against the declaration of field ``name`` of config class ``cls``.

    The single place where a command's own option (``--xt``, ``--rolling-speed``, a calibration
    bound) meets the same domain as the scenario field it stands for.

    Returns
    -------
    object
        The converted value (e.g. a float).

    Raises
    ------
    ScenarioError
        Naming ``path`` (default ``cls._section.name``), the rule and the fix.
    """
    f = {f.name: f for f in dataclasses.fields(cls)}[name]
    if path is None:
        section = getattr(cls, "_section", "")
        path = f"{section}.{name}" if section else name
    return _convert(path, value, _type_hints(cls)[name], f.metadata)


def dump(obj: object) -> Any:
    """Plain (YAML-safe) data for a config dataclass, every field written out."""
    if dataclasses.is_dataclass(obj):
        return {name: dump(getattr(obj, name)) for name in _settings(type(obj))}
    if isinstance(obj, (tuple, list)):
        return [dump(v) for v in obj]
    if isinstance(obj, dict):
        return {k: dump(v) for k, v in obj.items()}
    return obj
