"""CSV tables: one writer for every result table (header + rows, written atomically).

Every CSV file a study writes whole (``summary.csv`` of a sweep, ``mobility_map.csv``,
``table2.csv``, ``terrain_curves.csv``) goes through :func:`write_csv`; the sweep's
``summary.csv``, appended one line per finished case, formats its lines with :func:`csv_line`.

Cells are formatted by :func:`format_cell` with a :class:`CellFormat`:

``FULL``
    Floats at full precision (``repr``, so they read back bit for bit), booleans
    ``true``/``false``: the sweep's ``summary.csv``.
``SHORT``
    Floats to 6 significant digits (``%.6g``), booleans ``1``/``0``: the other tables.

In both, ``None`` is an empty cell, integers are written whole, text as it is (quoted by the
CSV rules when it holds a comma, a quote or a line break, unless ``CellFormat.comma`` replaces
its commas) and any other value (a list, a mapping) as canonical JSON.
"""

from __future__ import annotations

import csv
import io
import json
from dataclasses import dataclass

import numpy as np

from .folders import atomic_write_text

__all__ = ["CellFormat", "FULL", "SHORT", "canonical_json", "format_cell", "csv_line", "csv_text", "write_csv"]


@dataclass(frozen=True)
class CellFormat:
    """How values become CSV cells.

    Attributes
    ----------
    float_spec : str
        Format spec of floats (``".6g"``); empty: ``repr`` (shortest text that reads back exactly).
    true, false : str
        Text of the booleans.
    comma : str or None
        Replacement of commas in text cells (None: keep them; the cell is then quoted).
    """

    float_spec: str = ".6g"
    true: str = "1"
    false: str = "0"
    comma: str | None = None


#: Full precision, ``true``/``false`` (a sweep's ``summary.csv``).
FULL = CellFormat(float_spec="", true="true", false="false")
#: Six significant digits, ``1``/``0``.
SHORT = CellFormat()


def canonical_json(value) -> str:
    """Canonical JSON text of a value (sorted keys, no spaces; unknown types by ``str``)."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), default=str)


def format_cell(value, fmt: CellFormat = SHORT) -> str:
    """The CSV cell text of one value (see the module docstring)."""
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return fmt.true if value else fmt.false
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return format(float(value), fmt.float_spec) if fmt.float_spec else repr(float(value))
    if isinstance(value, str):
        return value if fmt.comma is None else value.replace(",", fmt.comma)
    return canonical_json(value)


def csv_line(values, fmt: CellFormat = SHORT) -> str:
    """One CSV line (ending in ``\\n``) of the formatted ``values``."""
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow([format_cell(v, fmt) for v in values])
    return buf.getvalue()


def _cells(row, columns):
    if isinstance(row, dict):
        return [row.get(c) for c in columns]
    return row


def csv_text(columns, rows, fmt: CellFormat = SHORT) -> str:
    """CSV text: a header line of ``columns`` then one line per row.

    A row is a mapping (its values for ``columns``, None where missing) or a sequence of values
    in column order.
    """
    cols = list(columns)
    return csv_line(cols, fmt) + "".join(csv_line(_cells(r, cols), fmt) for r in rows)


def write_csv(path, columns, rows, fmt: CellFormat = SHORT):
    """Write :func:`csv_text` to ``path`` atomically (a failure leaves any old file as it was, and no
    new file); returns the path."""
    return atomic_write_text(path, csv_text(columns, rows, fmt))
