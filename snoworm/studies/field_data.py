"""Field data: steady-state cases measured on snow (paper Table 2), read from a CSV and validated.

:func:`read_field_data` reads a field-data file (``#`` comment lines allowed) such as the shipped
``frostyboy_2020.csv`` (:func:`default_data_path`) into a :class:`FieldData`; every bad value is a
:class:`~snoworm.config.schema.ScenarioError` naming the file, the line, the column and the fix.
The ground truth (:mod:`snoworm.studies.groundtruth`) and the calibration
(:mod:`snoworm.studies.calibrate`) compare the model with it.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from ..config.schema import ScenarioError, suggest
from ..infra.files import FileProblem, read_regular_file

__all__ = ["FIELD_COLUMNS", "FieldData", "default_data_path", "read_field_data"]

#: Columns of a field-data file: name -> meaning.  Extra columns are allowed and ignored.
FIELD_COLUMNS = {
    "case": "case label (unique)",
    "surface": "free-text description of the surface",
    "speed_mps": "measured longitudinal ground speed V [m/s]",
    "wheel_speed_mps": "measured wheel speed R_w*omega [m/s], > 0",
    "slip": "measured steady slip as a fraction (0.06 for 6 %), in [-1, 1]",
    "torque_Nm": "measured motor output torque per wheel [N m]",
    "drawbar_N": "measured drawbar (tow) force [N]; 0 when nothing is towed",
    "xt": "terrain coefficient X_t assigned to the case, in (0, 1]",
}
_NUMERIC = ("speed_mps", "wheel_speed_mps", "slip", "torque_Nm", "drawbar_N", "xt")

_DATA_FILE = "frostyboy_2020.csv"
#: Largest field-data file read (bytes; the shipped one is ~2 kB).
MAX_FIELD_DATA_BYTES = 16 * 2**20


def default_data_path() -> Path:
    """Path of the shipped FrostyBoy 2020 field data (paper Table 2), package data of snoworm."""
    return Path(str(resources.files("snoworm") / "data" / _DATA_FILE))


@dataclass(frozen=True)
class FieldData:
    """Steady-state field cases (one row each), SI units.

    Attributes
    ----------
    source : str
        File the data came from.
    case, surface : tuple of str
        Case labels and surface descriptions.
    speed_mps, wheel_speed_mps, slip, torque_Nm, drawbar_N, xt : ndarray
        Columns of :data:`FIELD_COLUMNS` (slip as a fraction).
    data : bytes
        The file's bytes as read (a results folder keeps a copy of them, :mod:`snoworm.results.copies`).
    """

    source: str
    case: tuple
    surface: tuple
    speed_mps: np.ndarray
    wheel_speed_mps: np.ndarray
    slip: np.ndarray
    torque_Nm: np.ndarray
    drawbar_N: np.ndarray
    xt: np.ndarray
    data: bytes = field(default=b"", repr=False, compare=False)

    def __len__(self) -> int:
        return len(self.case)


def _bad(path, msg):
    raise ScenarioError(f"{path}: {msg}")


def read_field_data(path=None) -> FieldData:
    """Read and validate a field-data CSV (format of the shipped ``frostyboy_2020.csv``).

    Lines whose first non-blank character is ``#`` and blank lines are skipped; the first
    remaining line is the header.  Required columns are those of :data:`FIELD_COLUMNS`
    (any order; extra columns are ignored).

    Parameters
    ----------
    path : str or Path, optional
        The file; ``None`` reads the shipped FrostyBoy 2020 data (paper Table 2).

    Raises
    ------
    ScenarioError
        Missing file or columns, non-numeric or non-finite values, slip outside [-1, 1],
        wheel speed or X_t not positive, duplicate case labels, no data rows.
    """
    path = Path(path) if path is not None else default_data_path()
    linenos, rows, raw = _read_rows(path)
    header = [h.strip() for h in rows[0]]
    missing = [c for c in FIELD_COLUMNS if c not in header]
    if missing:
        hints = "".join(f" For '{m}':{suggest(m, header)}" for m in missing if suggest(m, header))
        _bad(
            path,
            f"missing column(s) {', '.join(repr(m) for m in missing)}. The header must name "
            f"{', '.join(FIELD_COLUMNS)} (found {', '.join(repr(h) for h in header)}).{hints} "
            "Slip is a fraction, torque per wheel in N m, drawbar in N (0 when nothing is towed).",
        )
    if len(rows) < 2:
        _bad(path, "has a header but no data rows. Add one row per steady-state case.")
    col = {c: header.index(c) for c in FIELD_COLUMNS}
    values = {c: [] for c in FIELD_COLUMNS}
    for lineno, row in zip(linenos[1:], rows[1:]):
        case = _row_values(path, lineno, row, header, col)
        _check_case(path, lineno, case)
        for c in FIELD_COLUMNS:
            values[c].append(case[c])
    dup = sorted({c for c in values["case"] if values["case"].count(c) > 1})
    if dup:
        _bad(
            path,
            f"case label(s) {', '.join(repr(d) for d in dup)} appear more than once. Give each case a unique label.",
        )
    return FieldData(
        source=str(path),
        case=tuple(values["case"]),
        surface=tuple(values["surface"]),
        **{c: np.array(values[c], float) for c in _NUMERIC},
        data=raw,
    )


def _read_rows(path):
    """(line numbers, CSV rows, the file's bytes) of a field-data file, the header first; ``#`` and
    blank lines skipped."""
    try:
        raw = read_regular_file(path, MAX_FIELD_DATA_BYTES)
        text = raw.decode("utf-8")
    except FileNotFoundError:
        _bad(path, "no such file. Give the path of a field-data CSV (see data/frostyboy_2020.csv for the format).")
    except FileProblem as exc:
        _bad(path, f"the file is {exc}; give a field-data CSV.")
    except (OSError, UnicodeDecodeError) as exc:
        _bad(path, f"cannot be read as UTF-8 text ({exc}).")
    lines = [(n, ln) for n, ln in enumerate(text.splitlines(), 1) if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        _bad(
            path,
            "no header and no data rows. Expected a header line "
            f"'{','.join(FIELD_COLUMNS)}' followed by one row per case.",
        )
    return [n for n, _ in lines], list(csv.reader(io.StringIO("\n".join(ln for _, ln in lines)))), raw


def _row_values(path, lineno, row, header, col) -> dict:
    """One data row as ``{column: value}``: text columns as given, numbers parsed and finite."""
    if len(row) != len(header):
        _bad(
            path,
            f"line {lineno} has {len(row)} fields but the header has {len(header)}. "
            'Quote text that contains commas, e.g. "lake snow, sled".',
        )
    out = {}
    for c in FIELD_COLUMNS:
        raw = row[col[c]].strip()
        if c in _NUMERIC:
            try:
                v = float(raw)
            except ValueError:
                extra = " Write 0 for no drawbar." if c == "drawbar_N" else ""
                _bad(path, f"line {lineno}, column '{c}': expected a number ({FIELD_COLUMNS[c]}), got {raw!r}.{extra}")
            if not math.isfinite(v):
                _bad(path, f"line {lineno}, column '{c}': must be a finite number, got {raw!r}.")
            out[c] = v
        else:
            out[c] = raw
    return out


def _check_case(path, lineno, case: dict):
    """The domain rules of one case: slip a fraction in [-1, 1], wheel speed > 0, X_t in (0, 1]."""
    lab = case["case"]
    s, w, x = case["slip"], case["wheel_speed_mps"], case["xt"]
    if not -1.0 <= s <= 1.0:
        hint = f" Did you give it in percent? As a fraction it would be {s / 100:g}." if abs(s) <= 100 else ""
        _bad(path, f"line {lineno} (case {lab}): slip {s:g} is outside [-1, 1]; slip is a fraction.{hint}")
    if not w > 0:
        _bad(
            path,
            f"line {lineno} (case {lab}): wheel_speed_mps must be greater than 0 m/s "
            f"(steady forward driving), got {w:g}.",
        )
    if not 0 < x <= 1:
        _bad(
            path, f"line {lineno} (case {lab}): xt must be in (0, 1], got {x:g}. X_t = 1 is neve, lower is looser snow."
        )
