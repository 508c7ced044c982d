"""Sweep specifications: the values of one swept key from ``KEY=SPEC``, and the cases they make.

A SPEC is a list (``0,100,200``; each item a number or a YAML value, brackets allowed for list
values) or an inclusive range ``START:STOP:COUNT`` (``0.3:1.0:15``).  The same grammar serves
``snoworm sweep --set`` and ``snoworm mobility-map --xt/--tow`` (:func:`parse_spec` names the
option in its messages).

The cases: :func:`build_cases` makes the grid (or zip) of an axis list, each case a
:class:`SweepCase` with a stable id and key.
"""

from __future__ import annotations

import hashlib
import itertools
import math
import re
from dataclasses import dataclass

import numpy as np
import yaml

from ...config.schema import ScenarioError, quote
from ...config.yamlio import load_yaml_text
from ...infra.csvwriter import canonical_json

__all__ = [
    "Axis",
    "MAX_CASES",
    "RANGE",
    "as_axes",
    "parse_scalar",
    "parse_spec",
    "parse_sweep_option",
    "SweepCase",
    "build_cases",
]


#: Most values of one range and most cases of a sweep (grid or zip): each case is a simulation and a
#: row of summary.csv; larger studies are split into several sweeps.
MAX_CASES = 100_000


@dataclass(frozen=True)
class Axis:
    """One swept key and its values (in the order given)."""

    key: str
    values: tuple
    spec: str = ""


def parse_scalar(text: str, source: str = "--set value"):
    """A number if ``text`` is one (``1e-3`` included), else the YAML value (read by the hardened
    reader, :func:`snoworm.yamlio.load_yaml_text`: an alias bomb is refused, ScenarioError)."""
    t = text.strip()
    for conv in (int, float):
        try:
            v = conv(t)
        except ValueError:
            continue
        return v
    return load_yaml_text(t, source)


def _split_top_level(text: str):
    """Split at commas outside brackets (so ``[1.8, 1.5],[1.0, 1.0]`` gives two values)."""
    parts, depth, cur = [], 0, []
    for ch in text:
        if ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    parts.append("".join(cur))
    return parts


#: A range SPEC: two colons, no commas or brackets.
RANGE = re.compile(r"^[^,\[\]{}]*:[^,\[\]{}]*:[^,\[\]{}]*$")


def _clean_float(v: float):
    """Round away linspace noise (0.7000000000000001 -> 0.7): 12 significant digits."""
    return float(f"{v:.12g}")


def parse_spec(key: str, spec, option: str | None = None) -> tuple:
    """Values of one sweep axis from its SPEC.

    Parameters
    ----------
    key : str
        Dotted scenario key (only used in messages).
    spec : str or sequence
        ``"a,b,c"`` (a list; each item a number or a YAML value, brackets allowed for list
        values), ``"start:stop:count"`` (``count`` values from ``start`` to ``stop`` inclusive,
        evenly spaced; whole numbers stay whole when the spacing is whole), a single value, or
        an already-parsed sequence of values.
    option : str, optional
        How messages name the option (default ``--set KEY=SPEC``; ``snoworm mobility-map``
        passes ``--xt '0.2:1.0'``).

    Raises
    ------
    ScenarioError
        Empty item, malformed range, non-positive count, duplicate value.
    """
    text = str(spec)
    opt = f"--set {key}={text if len(text) <= 60 else text[:60] + '...'}" if option is None else option
    if isinstance(spec, (list, tuple)):
        values = tuple(spec)
    else:
        text = str(spec).strip()
        if not text:
            raise ScenarioError(f"{opt}: no values. Give a list (0,100,200) or a range START:STOP:COUNT (0.3:1.0:15).")
        if RANGE.match(text):
            values = _parse_range(opt, text)
        else:
            items = _split_top_level(text)
            for it in items:
                if ":" in it and "[" not in it and "{" not in it and _looks_numeric(it.split(":")):
                    raise ScenarioError(
                        f"{opt}: {quote(it.strip(), 60)} is not a range: a range is START:STOP:COUNT "
                        "(two colons, no commas; a range cannot be mixed with a list), e.g. 0.3:1.0:15 for 15 values "
                        "from 0.3 to 1.0."
                    )
            if any(not it.strip() for it in items):
                raise ScenarioError(
                    f"{opt}: empty item in the list. Separate values by single commas, "
                    "e.g. 0,100,200, with no trailing comma."
                )
            try:
                values = tuple(parse_scalar(it, opt) for it in items)
            except yaml.YAMLError as exc:
                raise ScenarioError(f"{opt}: a value is not valid YAML ({getattr(exc, 'problem', exc)}).") from None
    if not values:
        raise ScenarioError(f"{opt}: no values.")
    seen = set()
    for v in values:
        k = canonical_json(v)
        if k in seen:
            raise ScenarioError(f"{opt}: the value {quote(v, 60)} appears twice. Give each value once.")
        seen.add(k)
    return values


def _parse_range(opt, text):
    hint = "A range is START:STOP:COUNT, inclusive, e.g. 0.3:1.0:15 for 15 values from 0.3 to 1.0."
    parts = [p.strip() for p in text.split(":")]
    if len(parts) != 3:
        raise ScenarioError(f"{opt}: {quote(text, 60)} has {len(parts) - 1} colons, not 2. {hint}")
    a, b, c = parts
    try:
        start, stop = _number(a), _number(b)
    except ValueError:
        raise ScenarioError(
            f"{opt}: START and STOP must be numbers (finite), got {quote(a, 40)} and {quote(b, 40)}. {hint}"
        ) from None
    try:
        count = int(c)
    except ValueError:
        raise ScenarioError(f"{opt}: COUNT must be a whole number of values, got {quote(c, 40)}. {hint}") from None
    if count < 1:
        raise ScenarioError(f"{opt}: COUNT must be at least 1, got {count}. {hint}")
    if count > MAX_CASES:
        raise ScenarioError(
            f"{opt}: COUNT {count} is over the {MAX_CASES} values allowed in one range; "
            "use fewer values or split the study."
        )
    if count == 1:
        if start != stop:
            raise ScenarioError(f"{opt}: COUNT 1 needs START = STOP; give {start} alone or COUNT >= 2. {hint}")
        return (start,)
    if start == stop:
        raise ScenarioError(f"{opt}: START = STOP with COUNT {count} repeats one value. {hint}")
    if isinstance(start, int) and isinstance(stop, int) and (stop - start) % (count - 1) == 0:
        step = (stop - start) // (count - 1)
        return tuple(start + j * step for j in range(count))
    return tuple(_clean_float(v) for v in np.linspace(float(start), float(stop), count))


def _looks_numeric(parts):
    for p in parts:
        if p.strip():
            try:
                float(p)
            except ValueError:
                return False
    return True


def _number(text):
    try:
        return int(text)
    except ValueError:
        v = float(text)
        if not math.isfinite(v):
            raise ValueError(text) from None
        return v


def parse_sweep_option(item: str) -> Axis:
    """Split one ``KEY=SPEC`` option into an :class:`Axis`."""
    if not isinstance(item, str) or "=" not in item:
        raise ScenarioError(
            f"--set {quote(item)}: expected KEY=SPEC with a dotted scenario key, e.g. "
            "terrain.xt=0.6:1.0:9 or tow.force_N=0,100,200."
        )
    key, _, spec = item.partition("=")
    key = key.strip()
    if not key or any(not p.strip() for p in key.split(".")):
        raise ScenarioError(f"--set {quote(item)}: the key must be a dotted scenario path such as tow.force_N.")
    return Axis(key, parse_spec(key, spec), spec.strip())


def as_axes(sets) -> list:
    """The axes of a sweep from ``KEY=SPEC`` strings, ``(key, spec)`` pairs or :class:`Axis` objects."""
    if isinstance(sets, (str, Axis)):
        sets = [sets]
    axes = []
    for s in sets:
        if isinstance(s, Axis):
            axes.append(s)
        elif isinstance(s, str):
            axes.append(parse_sweep_option(s))
        else:
            key, spec = s
            axes.append(Axis(str(key), parse_spec(str(key), spec), spec if isinstance(spec, str) else ""))
    if not axes:
        raise ScenarioError(
            "no --set KEY=SPEC given: a sweep needs at least one key to vary, e.g. --set terrain.xt=0.6:1.0:9."
        )
    keys = [a.key for a in axes]
    for k in keys:
        if keys.count(k) > 1:
            raise ScenarioError(f"--set {k}: the key is given more than once. Put all its values in one SPEC.")
    return axes


# --------------------------------------------------------- cases: the grid (or zip) of the axes
@dataclass(frozen=True)
class SweepCase:
    """One case: its index in the grid order and one value per axis."""

    index: int
    values: tuple
    case_id: str
    key: str

    def overrides(self, axes):
        return [(a.key, v) for a, v in zip(axes, self.values)]


def build_cases(axes, zip_: bool = False) -> list:
    """All cases of a sweep, in a deterministic order.

    A grid (``itertools.product``, the first axis varying slowest) or, with ``zip_``, the
    element-wise pairing of axes of equal length.  ``case_id`` is the zero-padded index in that
    order; ``key`` is a digest of the keys and values, the identity used for resumption.
    """
    n_cases = len(axes[0].values) if zip_ and axes else math.prod(len(a.values) for a in axes)
    if n_cases > MAX_CASES:
        raise ScenarioError(
            f"--set: the sweep has {n_cases} cases, over the {MAX_CASES} allowed in one sweep; "
            "use fewer values or split the study into several sweeps."
        )
    if zip_:
        lens = {a.key: len(a.values) for a in axes}
        if len(set(lens.values())) > 1:
            detail = ", ".join(f"{k} has {n}" for k, n in lens.items())
            raise ScenarioError(
                f"--zip pairs the values of every --set element by element, so each needs the "
                f"same number of values; {detail}. Make the lengths equal or drop --zip for a grid."
            )
        combos = list(zip(*(a.values for a in axes)))
    else:
        combos = list(itertools.product(*(a.values for a in axes)))
    width = max(4, len(str(len(combos) - 1)))
    cases = []
    for j, vals in enumerate(combos):
        digest = hashlib.sha1(canonical_json([[a.key, v] for a, v in zip(axes, vals)]).encode()).hexdigest()[:12]
        cases.append(SweepCase(j, tuple(vals), f"{j:0{width}d}", digest))
    return cases
