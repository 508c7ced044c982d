"""Progress of long commands: a bar on a terminal, a widget in a notebook, lines in a log file.

:class:`Progress` draws its bar with ``tqdm`` (a dependency); in a Jupyter kernel it uses
``tqdm.auto`` (a widget where ipywidgets is installed); when the stream is not a terminal (a batch
job's log) it prints
one line each time another ~10 % is done, and at least every :data:`LINE_EVERY_S` seconds of
wall time while work advances, so logs show how far a job got.  Counts are rounded to the
precision their total needs (``15/100 s simulated``, not ``14.970594137667268/100``).

The library's functions take a ``progress`` callable ``progress(done, total)`` (e.g.
:func:`snoworm.simulation.driver.simulate` in simulated seconds); :meth:`Progress.set` is one.

Solver fallbacks and retries are logged to ``logging.getLogger("snoworm")`` (:data:`logger`).
"""

from __future__ import annotations

import importlib.util
import logging
import math
import sys
import time

__all__ = ["Progress", "logger", "hms", "LINE_EVERY_S"]

#: In a log (lines mode), a line at least this often [s of wall time] while the work advances.
LINE_EVERY_S = 5.0

#: The package's logger: solver fallbacks and retries (INFO), runs falling back to one by one (INFO).
logger = logging.getLogger("snoworm")


def hms(s: float) -> str:
    """``m:ss`` (or ``h:mm:ss``) of a duration in seconds."""
    s = int(round(s))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60}:{s % 60:02d}"


def _num(v: float):
    """An integral float as int (tqdm then counts 3/3, not 3.0/3.0)."""
    return int(v) if float(v).is_integer() else v


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def _tqdm(notebook=False):
    """tqdm's bar class: ``tqdm.auto``'s in a notebook where ipywidgets is installed (a widget), else
    the terminal bar.  Imported when a bar is drawn (not for lines in a log, nor by ``import snoworm``)."""
    if notebook and importlib.util.find_spec("ipywidgets") is not None:
        from tqdm.auto import tqdm  # lazy: only a bar needs it
    else:
        from tqdm import tqdm  # lazy: only a bar needs it
    return tqdm


def _in_notebook(stream) -> bool:
    """True when ``stream`` is the stderr of a Jupyter kernel (IPython already imported there)."""
    ip = getattr(sys.modules.get("IPython"), "get_ipython", None)
    shell = ip() if callable(ip) else None
    return stream is sys.stderr and type(shell).__name__ == "ZMQInteractiveShell"


def _decimals(total: float) -> int:
    """Decimals of the counts: none for a whole total (cases, runs, a 2000 s run: ``15/2000``),
    else enough for about three significant digits of the total (``0.75/2.5``)."""
    if float(total).is_integer() or total <= 0:
        return 0
    return int(min(3, max(0, 2 - math.floor(math.log10(total)))))


class Progress:
    """A progress report of ``total`` units of work.

    Parameters
    ----------
    total : float
        Work to do (cases, cells, simulated seconds).
    desc : str
        What is being done (start of the line).
    unit : str
        Unit of the work (``"cases"``, ``"s simulated"``).
    stream : file, optional
        Where to draw (default: ``sys.stderr``).
    mode : {"auto", "bar", "lines", "off"}
        ``auto``: a bar (tqdm's) on a terminal or in a notebook, lines otherwise.
    """

    def __init__(self, total, desc, unit="", stream=None, mode="auto"):
        self.total, self.desc, self.unit = float(total), desc, unit
        self.stream = sys.stderr if stream is None else stream
        notebook = _in_notebook(self.stream)
        if mode == "auto":
            mode = "bar" if _isatty(self.stream) or notebook else "lines"
        if mode not in ("bar", "lines", "off"):
            raise ValueError(f"mode must be auto, bar, lines or off, got {mode!r}")
        self.mode = mode
        self.value, self.info = 0.0, ""
        self.t0 = time.perf_counter()
        self._decile, self._closed, self._printed = 0, False, 0.0
        self._line_t = self.t0
        self._bar = self._new_bar(notebook) if mode == "bar" else None

    def _new_bar(self, notebook):
        """tqdm's bar for :attr:`total`, counts rounded as in the lines (``15/100 s simulated``)."""
        unit = self.unit
        d = _decimals(self.total)
        fmt = (
            "{desc}: {percentage:3.0f}%|{bar}| "
            + f"{{n:.{d}f}}/{{total:.{d}f}}"
            + (f" {unit}" if unit else "")
            + " [{elapsed}<{remaining}{postfix}]"
        )
        return _tqdm(notebook)(
            total=_num(self.total),
            desc=self.desc,
            unit=f" {unit}" if unit else "it",
            file=self.stream,
            leave=True,
            dynamic_ncols=True,
            bar_format=fmt,
        )

    # ---------------------------------------------------------------- updates
    def update(self, n=1, info=None):
        """``n`` more units done; ``info``: short text shown after the count."""
        self.set(self.value + n, info=info)

    def set(self, value, total=None, info=None):
        """``value`` units done in all (``total`` may change it; with the same total, progress
        never goes back)."""
        if total is not None and float(total) != self.total:
            self.total = float(total)
            if self._bar is not None:
                self._bar.total = _num(self.total)
        elif float(value) < self.value:
            value = self.value
        self.value = min(float(value), self.total) if self.total > 0 else float(value)
        if info is not None:
            self.info = info
        self._draw()

    __call__ = set

    def close(self, info=None):
        """End the report (the bar's final state, or the last line if not yet printed)."""
        if self._closed:
            return
        self._closed = True
        if info is not None:
            self.info = info
        if self._bar is not None:
            self._bar.set_postfix_str(self.info, refresh=False)
            self._bar.close()
        elif self.mode == "lines" and self.value > self._printed:
            self._line()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    # ---------------------------------------------------------------- drawing
    def _write(self, text):
        self.stream.write(text)
        self.stream.flush()

    def _frac(self):
        return self.value / self.total if self.total > 0 else 1.0

    def _count(self):
        d = _decimals(self.total)
        return f"{self.value:.{d}f}/{self.total:.{d}f}" + (f" {self.unit}" if self.unit else "")

    def _draw(self):
        if self.mode == "off" or self._closed:
            return
        if self._bar is not None:
            if self.info:
                self._bar.set_postfix_str(self.info, refresh=False)
            self._bar.update(_num(self.value) - self._bar.n)
        elif int(10 * self._frac() + 1e-9) > self._decile:
            self._decile = int(10 * self._frac() + 1e-9)
            self._line()
        elif self.value > self._printed and time.perf_counter() - self._line_t >= LINE_EVERY_S:
            self._line()

    def _line(self):
        self._printed, self._line_t = self.value, time.perf_counter()
        info = f", {self.info}" if self.info else ""
        self._write(
            f"{self.desc}: {100 * self._frac():3.0f} % ({self._count()}{info}), "
            f"{hms(time.perf_counter() - self.t0)} elapsed\n"
        )
