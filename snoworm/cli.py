"""Command-line interface (click).  Thin: every command calls the Python API.

Exit status: 0 success, 1 solver failure (with the solver's message), 2 bad input (a clear
one-paragraph message naming the field and the fix, never a traceback).
"""
from __future__ import annotations

import functools
import os
import sys

import click

from . import __version__

EXIT_SOLVER = 1
EXIT_INPUT = 2


def _fail(msg, code):
    click.echo(f"Error: {msg}", err=True)
    sys.exit(code)


def handle_errors(fn):
    """Turn ScenarioError into exit 2 and SolverError into exit 1, each with a one-paragraph message."""
    @functools.wraps(fn)
    def wrapper(*a, **kw):
        from .schema import ScenarioError
        from .simulate import SolverError
        try:
            return fn(*a, **kw)
        except ScenarioError as exc:
            _fail(str(exc), EXIT_INPUT)
        except SolverError as exc:
            _fail(f"solver failure: {exc}", EXIT_SOLVER)
        except KeyboardInterrupt:
            _fail("interrupted; files already finished were kept.", 130)
        except Exception as exc:  # a bug: one paragraph, the traceback on request
            if os.environ.get("SNOWORM_DEBUG"):
                raise
            _fail(f"internal error ({type(exc).__name__}: {exc}). This is a bug in snoworm; "
                  "rerun with SNOWORM_DEBUG=1 for the traceback and report it.", EXIT_SOLVER)
    return wrapper


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="snoworm")
def main():
    """snoworm: simulate multi-segment wheeled rovers on snow (SnoWorm / FrostyBoy model).

    Scenarios are YAML files (see scenarios/).  Start with
    `snoworm run scenarios/inchworm6.yaml --out out/`.
    """


set_option = click.option("--set", "sets", multiple=True, metavar="KEY=VALUE",
                          help="Override a scenario value by its dotted key, e.g. --set terrain.xt=0.5 "
                               "(repeatable; VALUE is parsed as YAML).")


@main.command()
@click.argument("scenario", type=click.Path(dir_okay=False))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Directory for segments.csv, links.csv, summary.json, scenario.yaml and the plots.")
@set_option
@click.option("--no-plot", is_flag=True, help="Skip the PNG plots.")
@handle_errors
def run(scenario, out_dir, sets, no_plot):
    """Run SCENARIO and write its results to --out.

    Nothing is written if the scenario is invalid (exit 2) or the solver fails (exit 1);
    each file is written atomically.
    """
    from .scenario import load_scenario
    from .simulate import simulate
    sc = load_scenario(scenario, sets)
    res = simulate(sc)
    paths = res.write(out_dir, plot=not no_plot)
    s = res.summary()
    click.echo(f"{sc.name}: {s['duration_s']:.1f} s simulated in {res.stats['wall_time_s']:.2f} s "
               f"({s['duration_s'] / max(res.stats['wall_time_s'], 1e-9):.0f}x real time), "
               f"distance {s['distance_m']:.2f} m, mean speed {s['mean_speed_mps']:.3f} m/s")
    if s["final_link_forces_N"]:
        click.echo("final link forces [N]: " + ", ".join(f"{f:.1f}" for f in s["final_link_forces_N"]))
    click.echo("final net wheel forces [N]: " + ", ".join(f"{f:.1f}" for f in s["final_net_forces_N"]))
    click.echo(f"wrote {len(paths)} files to {out_dir}")


@main.command()
@click.argument("scenario", type=click.Path(dir_okay=False))
@set_option
@handle_errors
def validate(scenario, sets):
    """Check SCENARIO without running it (exit 0 if valid, 2 with the reason if not)."""
    from .scenario import load_scenario
    sc = load_scenario(scenario, sets)
    click.echo(f"{scenario}: valid ({sc.vehicle.segments} segments, mode {sc.mode.type}, "
               f"{sc.simulation.duration_s:g} s)")


if __name__ == "__main__":  # pragma: no cover
    main()
