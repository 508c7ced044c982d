"""What every command of the command line (:mod:`snoworm.cli`) shares.

Exit statuses and :func:`handle_errors` (bad input exit 2, solver or controller failure exit 1,
Ctrl-C 130, SIGTERM 143, never a traceback unless ``SNOWORM_DEBUG``), the options several
commands take (``--out``, ``--set``, ``--overwrite``, ``--plot-format``, ``--parameter-set``,
``--model-file``), the progress bar, the log handler, and the reports the longer commands print
when they finish (:func:`echo_run`, :func:`echo_sweep`, :func:`echo_claims`).  Like :mod:`snoworm.cli`, it imports the
library only inside the functions that need it, so ``snoworm --help`` starts fast.
"""

from __future__ import annotations

import functools
import logging
import os
import re
import shlex
import signal
import sys
import time

import click

__all__ = [
    "EXIT_SOLVER",
    "EXIT_INPUT",
    "bounded",
    "fail",
    "Terminated",
    "handle_errors",
    "CommandGroup",
    "command_line",
    "out_option",
    "allow_code_option",
    "code_check",
    "overwrite_option",
    "set_option",
    "plot_format_option",
    "figure_size_option",
    "param_set_option",
    "model_file_option",
    "progress_bar",
    "StderrHandler",
    "configure_logging",
    "echo_scenarios",
    "echo_written",
    "echo_run",
    "CpuClock",
    "echo_sweep",
    "sweep_interrupted",
    "echo_claims",
]

EXIT_SOLVER = 1
EXIT_INPUT = 2


#: A run of non-blank characters longer than this in a message (a path, a value) is cut in its middle.
MAX_WORD_CHARS = 240


def bounded(msg) -> str:
    """``msg`` with every run of over :data:`MAX_WORD_CHARS` non-blank characters (a 4 kB path
    echoed once or three times) cut in its middle (``...[N characters]...``), its ends kept."""
    from ..config.schema import short_path  # lazy: start-up

    return re.sub(rf"\S{{{MAX_WORD_CHARS + 1},}}", lambda m: short_path(m.group(0), MAX_WORD_CHARS), str(msg))


def fail(msg, code):
    """Print ``Error: msg`` to stderr (long words cut, :func:`bounded`) and exit with status ``code``."""
    click.echo(f"Error: {bounded(msg)}", err=True)
    sys.exit(code)


class Terminated(KeyboardInterrupt):
    """SIGTERM, handled like Ctrl-C (finished files kept, partial ones removed)."""


def _on_sigterm(signum, frame):
    raise Terminated()


def _catch_sigterm():
    """Install the SIGTERM handler (main thread only); returns the previous handler or None."""
    try:
        return signal.signal(signal.SIGTERM, _on_sigterm)
    except (ValueError, AttributeError):  # not the main thread / no SIGTERM on this platform
        return None


def handle_errors(fn):
    """Turn ScenarioError and OutputError into exit 2, SolverError and ControllerError into exit 1,
    each with a clear message; SIGTERM is handled like Ctrl-C."""

    @functools.wraps(fn)
    def wrapper(*a, **kw):
        from ..config.schema import ScenarioError  # lazy: start-up
        from ..infra.folders import OutputError  # lazy: start-up
        from ..modes.controller import ControllerError  # lazy: start-up
        from ..results.result import ResultFileError  # lazy: start-up
        from ..simulation.guard import SolverError  # lazy: start-up

        old = _catch_sigterm()
        try:
            return fn(*a, **kw)
        except (ScenarioError, OutputError, ResultFileError) as exc:  # bad input, a folder not as written
            fail(str(exc), EXIT_INPUT)
        except SolverError as exc:
            fail(f"solver failure: {exc}", EXIT_SOLVER)
        except ControllerError as exc:  # the user's controller raised or returned a bad command
            fail(str(exc), EXIT_SOLVER)
        except RecursionError:  # a structure nested beyond Python's stack: bad input, not a bug
            fail("the input is nested too deeply to read (a scenario needs only a few levels); flatten it.", EXIT_INPUT)
        except BrokenPipeError:  # output piped into e.g. `head`: not an error of ours
            sys.stderr.close()
            sys.exit(0)
        except KeyboardInterrupt as exc:
            fail(
                "interrupted; nothing half-written was left (finished files of a sweep were kept).",
                143 if isinstance(exc, Terminated) else 130,
            )
        except Exception as exc:  # a bug: one paragraph, the traceback on request
            from ..infra.pool import interrupt_within  # lazy: start-up (the error path only)

            interrupt = interrupt_within(exc)
            if interrupt is not None:  # Ctrl-C/SIGTERM inside NumPy/SciPy C code came back as another error
                fail(
                    "interrupted; nothing half-written was left (finished files of a sweep were kept).",
                    143 if isinstance(interrupt, Terminated) else 130,
                )
            if os.environ.get("SNOWORM_DEBUG"):
                raise
            fail(
                f"internal error ({type(exc).__name__}: {exc}). This is a bug in snoworm; "
                "rerun with SNOWORM_DEBUG=1 for the traceback and report it.",
                EXIT_SOLVER,
            )
        finally:
            if old is not None:
                signal.signal(signal.SIGTERM, old)

    return wrapper


def command_line() -> str | None:
    """The running command's line, ``snoworm <its arguments>`` (recorded in the manifests of the
    output folders it writes), or None outside a command."""
    ctx = click.get_current_context(silent=True)
    argv = ctx.find_root().meta.get("snoworm.argv") if ctx is not None else None
    return shlex.join(["snoworm", *argv]) if argv is not None else None


class CommandGroup(click.Group):
    """The command group; keeps its command line (for the output folders' manifests)."""

    def parse_args(self, ctx, args):
        ctx.meta["snoworm.argv"] = list(args)
        return super().parse_args(ctx, args)


def _check_out(ctx, param, value):
    """``--out`` must name a directory (an empty path would write into the current folder); one line
    on stderr when it holds earlier results."""
    if value is not None and not str(value).strip():
        raise click.BadParameter(
            "must name a directory, got an empty path (it would write into the current "
            "folder). Give e.g. --out results/."
        )
    from ..infra.folders import earlier_output_note  # lazy: start-up

    try:
        note = earlier_output_note(value, resumes=ctx.command.name == "sweep") if value is not None else None
    except (OSError, ValueError) as exc:  # a name too long, a NUL byte
        raise click.BadParameter(
            bounded(
                f"{value} cannot be used as a folder ({getattr(exc, 'strerror', None) or exc}). Give e.g. --out results/."
            )
        ) from None
    if note:  # re-running into the same --out: say so, in one line
        click.echo(bounded(note), err=True)
    return value


def out_option(help_text):
    """The ``--out DIR`` option of a command that writes results (checked by :func:`_check_out`)."""
    return click.option(
        "--out", "out_dir", required=True, type=click.Path(file_okay=False), callback=_check_out, help=help_text
    )


class StderrHandler(logging.StreamHandler):
    """Log records to the current ``sys.stderr`` (looked up at each record, not at start-up)."""

    def emit(self, record):
        self.stream = sys.stderr
        super().emit(record)


overwrite_option = click.option(
    "--overwrite",
    is_flag=True,
    help="Write into a non-empty --out folder that snoworm did not write (same-named "
    "files are replaced, other files kept). An earlier snoworm output folder is "
    "always replaced as a whole; a folder another snoworm process is writing never (exit 2).",
)


def progress_bar(total, desc, unit):
    """A :class:`~snoworm.infra.progress.Progress` bar on stderr (imported on first use)."""
    from ..infra.progress import Progress  # lazy: start-up

    return Progress(total, desc, unit)


set_option = click.option(
    "--set",
    "sets",
    multiple=True,
    metavar="KEY=VALUE",
    help="Override a scenario value by its dotted key, e.g. --set terrain.xt=0.5 "
    "(repeatable; VALUE is parsed as YAML).",
)
plot_format_option = click.option(
    "--plot-format",
    type=click.Choice(["png", "pdf", "svg"]),
    default="png",
    show_default=True,
    help="File format of the plots (PNG at 200 dpi; PDF with TrueType fonts; SVG with text kept as text).",
)


def _check_size(ctx, param, value):
    """``--figure-size`` must be column, page or WxH (checked by :func:`snoworm.plotting.style.parse_size`)."""
    if value is not None:
        from ..plotting.style import parse_size  # lazy: matplotlib, only when a size is given

        try:
            parse_size(value)
        except ValueError as exc:
            raise click.BadParameter(f"{exc}.") from None
    return value


figure_size_option = click.option(
    "--figure-size",
    metavar="column|page|WxH",
    default=None,
    callback=_check_size,
    help="Print size of the figures: column (3.5 in wide), page (7.16 in, the "
    "default) or WxH inches, e.g. 3.5x2.5; text is at least 7 pt at that size.",
)


def _check_allowed(ctx, param, value):
    """Refuse an empty ``--allow-code ''`` (it would allow the whole working folder's code)."""
    for p in value:
        if not p.strip():
            raise click.BadParameter(
                "an empty path would allow the code of the whole working folder. Name the file or folder "
                "whose controller code may run (e.g. --allow-code ./controllers).",
                ctx=ctx,
                param=param,
            )
    return value


allow_code_option = click.option(
    "--allow-code",
    "allow_code",
    multiple=True,
    type=click.Path(),
    callback=_check_allowed,
    metavar="PATH",
    help="Let controller code under PATH (a file or folder) run although it lies outside the scenario's folder "
    "(repeatable). A scenario with a controller is a program: see docs/controllers.md.",
)


def code_check(sc, allow_code, verb=None):
    """Refuse (exit 2) a controller that may not run; with ``verb``, say on stderr which code runs."""
    if getattr(sc.mode, "type", None) == "controller":
        from ..modes.controller import code_notice  # lazy: start-up (only controller scenarios)

        notice = code_notice(sc, allow_code)
        if verb:
            click.echo(bounded(f"snoworm: {verb} {notice}"), err=True)


def configure_logging(verbose: bool):
    """Solver fallbacks and retries to stderr: INFO with ``--verbose``, else only warnings."""
    log = logging.getLogger("snoworm")
    if not any(isinstance(h, StderrHandler) for h in log.handlers):
        h = StderrHandler()
        h.setFormatter(logging.Formatter("snoworm: %(message)s"))
        log.addHandler(h)
    log.setLevel(logging.INFO if verbose else logging.WARNING)


param_set_option = click.option(
    "--parameter-set",
    "parameter_set_name",
    default="frostyboy",
    show_default=True,
    help="Named set of physical values (segment and terrain model) to use.",
)
model_file_option = click.option(
    "--model-file",
    type=click.Path(dir_okay=False),
    default=None,
    help="YAML of terrain-model coefficients (e.g. terrain_model.yaml written by "
    "`snoworm calibrate`) replacing the parameter set's.",
)


# ---------------------------------------------------------------- what the commands print at the end


def echo_scenarios():
    """The shipped scenarios, one line each: name and description."""
    from ..config.scenario import shipped_scenarios  # lazy: start-up

    items = shipped_scenarios()
    width = max(map(len, items), default=0)
    for name, (_, desc) in items.items():
        click.echo(f"{name:<{width}}  {desc}")


def echo_written(text, paths, out_dir, clock=None):
    """A study command's report, then how many files it wrote and where (and, with a
    :class:`CpuClock`, the wall and CPU time the command took)."""
    click.echo(text)
    click.echo(f"wrote {len(paths)} files to {out_dir}" + ("" if clock is None else f" ({clock.text()})"))


class CpuClock:
    """Wall and CPU time since it was made: the speed line of the commands, so that a loaded machine
    (little CPU per wall second) does not look like a slow simulator.

    CPU time is this process's (:func:`time.process_time`: every thread, user and system) plus that
    of its child processes that have exited and been waited for (``resource.getrusage`` with
    ``RUSAGE_CHILDREN``, on POSIX systems): the worker processes of ``--jobs`` once their pool has
    shut down.  Dask workers run elsewhere and are not counted.
    """

    def __init__(self):
        self.wall0, self.cpu0 = time.perf_counter(), self._cpu()

    @staticmethod
    def _cpu() -> float:
        cpu = time.process_time()
        try:
            import resource  # lazy: POSIX only
        except ImportError:  # pragma: no cover - Windows: no child-process accounting
            return cpu
        ru = resource.getrusage(resource.RUSAGE_CHILDREN)
        return cpu + ru.ru_utime + ru.ru_stime

    def seconds(self) -> tuple[float, float]:
        """(wall, CPU) seconds since the clock was made."""
        return time.perf_counter() - self.wall0, self._cpu() - self.cpu0

    def text(self) -> str:
        """``"12.34 s wall, 20.10 s CPU"``."""
        wall, cpu = self.seconds()
        return f"{wall:.2f} s wall, {cpu:.2f} s CPU"


def echo_run(name, res, paths, out_dir, cpu_s=None):
    """``snoworm run``'s report: simulated, wall and CPU time (``cpu_s``: the CPU seconds of the
    simulation, measured by the caller with :class:`CpuClock`), distance, speed, final forces,
    files written, and last the verdict's line (:func:`snoworm.results.verdict.verdict`): reached
    the end of the route, immobilised (where, when, why) or moving at the end."""
    s = res.summary()
    wall = res.stats["wall_time_s"]
    cpu = "" if cpu_s is None else f", {cpu_s:.2f} s CPU"
    click.echo(
        f"{name}: {s['duration_s']:.1f} s simulated in {wall:.2f} s wall{cpu} "
        f"({s['duration_s'] / max(wall, 1e-9):.0f}x real time), "
        f"distance {s['distance_m']:.2f} m, mean speed {s['mean_speed_mps']:.3f} m/s"
    )
    if s["final_link_forces_N"]:
        click.echo("final link forces [N]: " + ", ".join(f"{f:.1f}" for f in s["final_link_forces_N"]))
    click.echo("final net wheel forces [N]: " + ", ".join(f"{f:.1f}" for f in s["final_net_forces_N"]))
    click.echo(f"wrote {len(paths)} files to {out_dir}")
    click.echo(s["status_reason"])  # the verdict, last (snoworm.results.verdict)


def sweep_interrupted(exc, out_dir):
    """An interrupted sweep: say where the finished cases are and exit 130 (143 on SIGTERM)."""
    how = "terminated (SIGTERM)" if isinstance(exc, Terminated) else "interrupted"
    click.echo(f"{how}: finished cases are in {out_dir}/summary.csv; run the same command again to resume.", err=True)
    sys.exit(143 if isinstance(exc, Terminated) else 130)


def echo_sweep(table, out_dir, clock=None):
    """``snoworm sweep``'s report: cases ok, failed and immobilised, the first five failures (and,
    with a :class:`CpuClock`, the wall and CPU time of this process and its local workers)."""
    bad = table.failures()
    imm = sum(bool(r["immobilised"]) for r in table.rows if r["status"] == "ok")
    click.echo(
        f"{len(table)} cases: {len(table) - len(bad)} ok, {len(bad)} failed, {imm} immobilised; "
        f"summary in {out_dir}/summary.csv" + ("" if clock is None else f" ({clock.text()})")
    )
    for r in bad[:5]:
        click.echo(f"  case {r['case_id']} {r['status']}: {r['error']}")
    if len(bad) > 5:
        click.echo(f"  ... and {len(bad) - 5} more (see the error column)")


def echo_claims(rep, out_dir, quick, clock=None) -> int:
    """``snoworm paper``'s report: how many claims hold (returned), and each failing one on stderr;
    with a :class:`CpuClock`, the wall and CPU time of this process and its workers."""
    n_ok = sum(c.holds for c in rep.claims)
    took = f"{rep.wall_time_s:.1f} s" if clock is None else clock.text()
    click.echo(
        f"{n_ok} of {len(rep.claims)} claims hold ({'quick' if quick else 'full'} mode, "
        f"{took}); report: {os.path.join(out_dir, 'report.html')}"
    )
    for c in rep.claims:
        if not c.holds:
            click.echo(f"FAILS: {c.id}: {c.statement}", err=True)
    return n_ok
