"""Command-line interface (click).  Thin: every command calls the Python API.

Exit status: 0 success, 1 solver failure (with the solver's message), 2 bad input (a clear
one-paragraph message naming the field and the fix, never a traceback).  What every command
shares (error handling, exit statuses, common options, progress, logging) is in
:mod:`snoworm.commands.common`; the study commands (ground truth, calibration, mobility map,
paper) are in :mod:`snoworm.commands.studies`.
"""

from __future__ import annotations

import os
import sys

import click

from ._version import __version__
from .commands.common import (
    EXIT_SOLVER,
    CommandGroup,
    allow_code_option,
    code_check,
    command_line,
    configure_logging,
    echo_run,
    echo_scenarios,
    echo_sweep,
    fail,
    figure_size_option,
    handle_errors,
    out_option,
    overwrite_option,
    plot_format_option,
    progress_bar,
    set_option,
    sweep_interrupted,
)
from .commands.studies import STUDY_COMMANDS


@click.group(cls=CommandGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="snoworm")
@click.option("-v", "--verbose", is_flag=True, help="Also log solver fallbacks and retries to stderr.")
def main(verbose=False):
    """snoworm: simulate multi-segment wheeled rovers on snow (SnoWorm / FrostyBoy model).

    Scenarios are YAML files or the names of the shipped ones (`snoworm scenarios` lists them).
    Start with `snoworm run inchworm6 --out out/`.
    """
    configure_logging(verbose)


@main.command()
@click.argument("scenario", type=click.Path(dir_okay=False))
@out_option("Directory for segments.csv, links.csv, summary.json, scenario.yaml and the plots.")
@set_option
@click.option("--no-plot", is_flag=True, help="Skip the plots.")
@plot_format_option
@figure_size_option
@overwrite_option
@allow_code_option
@handle_errors
def run(scenario, out_dir, sets, no_plot, plot_format, figure_size, overwrite, allow_code):
    """Run SCENARIO (a YAML file or a shipped scenario's name) and write its results to --out.

    All or nothing: the files go to a temporary folder beside --out that replaces it at the
    end, with a manifest (.snoworm-manifest.json); nothing is written if the scenario is
    invalid (exit 2), the solver fails (exit 1) or the run is interrupted.  Progress in
    simulated time goes to stderr, and so does which controller code runs (if any).

    The last line is the run's verdict (also in summary.json: status, immobilised_at_m,
    status_reason): "reached the end of the route ... at t = ..." (the leader passed
    simulation.goal_m or the route's last point), "immobilised at x = ..., t = ... (X_t, grade,
    slip there)" (stalled for good with the wheels driven: simulation.immobilised) or "moving at
    the end (...)".
    """
    from .config.scenario import load_scenario  # lazy: start-up
    from .infra.folders import check_output_folder  # lazy: start-up
    from .simulation.driver import simulate  # lazy: start-up

    out_dir = os.path.abspath(out_dir)  # once: a controller's os.chdir does not move it
    sc = load_scenario(scenario, sets)
    code_check(sc, allow_code, "running")
    check_output_folder(out_dir, overwrite)
    with progress_bar(sc.simulation.duration_s, sc.name, "s simulated") as bar:
        res = simulate(sc, progress=bar.set, allow_code=allow_code)
    paths = res.write(
        out_dir,
        plot=not no_plot,
        plot_format=plot_format,
        overwrite=overwrite,
        figure_size=figure_size,
        command=command_line(),
    )
    echo_run(sc.name, res, paths, out_dir)


@main.command()
@click.argument("scenario", type=click.Path(dir_okay=False))
@set_option
@allow_code_option
@handle_errors
def validate(scenario, sets, allow_code):
    """Check SCENARIO without running it (exit 0 if valid, 2 with the reason if not).

    Besides the scenario's values, this makes the checks a run makes when it assembles the chain
    model (e.g. a force-control target the chain cannot carry), which loading a scenario in
    Python does not. Nothing of the scenario runs: a controller is checked statically (the file or
    module exists, parses and defines the class) and against --allow-code as `snoworm run` would."""
    from .config.scenario import load_scenario  # lazy: start-up
    from .simulation.driver import check_assembly  # lazy: start-up

    sc = load_scenario(scenario, sets)
    code_check(sc, allow_code)
    check_assembly(sc)
    click.echo(
        f"{scenario}: valid ({sc.vehicle.segments} segments, mode {sc.mode.type}, {sc.simulation.duration_s:g} s)"
    )


@main.command()
@click.argument("scenario", type=click.Path(dir_okay=False))
@click.option(
    "--set",
    "sets",
    multiple=True,
    metavar="KEY=SPEC",
    required=True,
    help="A swept scenario key and its values: a list (tow.force_N=0,100,200) or an inclusive "
    "range START:STOP:COUNT (terrain.xt=0.3:1.0:15 gives 15 values). Repeat for a grid "
    "(first key slowest); a single value just overrides the key.",
)
@out_option(
    "Directory for sweep.json, summary.csv and sweep.png / heatmap.png. Re-running the same "
    "command resumes an interrupted sweep there."
)
@click.option("-j", "--jobs", default=1, show_default=True, type=click.IntRange(min=1), help="Local worker processes.")
@click.option(
    "--scheduler",
    metavar="ADDRESS",
    default=None,
    help="Run the cases on a Dask distributed scheduler, e.g. tcp://10.0.0.5:8786 "
    "(needs pip install 'snoworm[dask]'); overrides -j.",
)
@click.option(
    "--zip",
    "zip_",
    is_flag=True,
    help="Pair the --set values element by element (equal lengths) instead of a full grid.",
)
@click.option("--save-cases", is_flag=True, help="Also write each case's time series to DIR/cases/<case_id>/.")
@click.option(
    "--series",
    type=click.Choice(["folders", "netcdf"]),
    default="folders",
    show_default=True,
    help="With --save-cases: each case's time series in its own folder DIR/cases/<case_id>/, or every "
    "case in one netCDF file DIR/series.nc (dims: swept keys x time x segment/link; needs "
    "pip install 'snoworm[data]').",
)
@click.option("--no-plot", is_flag=True, help="Skip sweep.png / heatmap.png.")
@plot_format_option
@figure_size_option
@click.option(
    "--batch",
    default=0,
    show_default=True,
    type=click.IntRange(min=0),
    metavar="B",
    help="Integrate up to B cases of the same structure (uniform or force-control mode) as one stacked system "
    "(several times the cases/s; 100-500 is a good B); other cases run one by one.",
)
@click.option(
    "--overwrite",
    is_flag=True,
    help="Replace another sweep in --out (its files are removed), or write into a non-empty folder "
    "snoworm did not write; never a folder another snoworm process is writing (exit 2).",
)
@click.option(
    "--restart",
    is_flag=True,
    help="Run afresh a sweep in --out whose input files or snoworm version "
    "changed since (its rows are removed); without it such a resume exits 2 naming the file.",
)
@allow_code_option
@handle_errors
def sweep(scenario, sets, out_dir, no_plot, **options):
    """Run SCENARIO (a YAML file or a shipped scenario's name) over a grid of values and tabulate
    the results in --out.

    \b
    summary.csv has one row per case, appended as each case finishes (completion order):
      case_id, case_key, the swept values, status (ok, solver_failure, invalid, error, controller_failure), error,
      n_segments, distance_m, mean_speed_mps, late_speed_mps (mean forward speed over the
      last 25 % of the run), mean_slip and max_slip (signed slip over the segments and the
      second half of the run), max_link_force_N (largest |force| over the run),
      final_link_force_<j>_N, energy_per_m_J, immobilised, verdict, immobilised_at_m, wall_time_s.
    verdict: the run's verdict, as `snoworm run` prints it: moving, reached_end (the leader passed
    simulation.goal_m or the route's last point) or immobilised (for simulation.immobilised.window_s,
    5 s, the wheels driven but the chain's centre slower than max(0.05 m/s, 5 *
    terrain.model.sign_eps_mps) and covering less than a tenth of the wheels' travel; for a
    free-rolling FrostyBoy: X_t below about 0.586); immobilised_at_m: the leader's position then.

    A failing case is recorded and the sweep goes on. Re-running the same command skips the
    cases already in summary.csv; a different sweep in the same --out is refused (exit 2)
    unless --overwrite. The folder is locked while the sweep runs: a second sweep into it exits
    2 naming the process holding it. The scheduler is checked before anything is written.
    Progress goes to stderr (a bar on a terminal, a line per ~10 % otherwise).
    Exit status: 0 when the sweep completes (even with failed cases), 2 on bad input, 1 if a
    worker process or the Dask cluster fails, 130 when interrupted (143 on SIGTERM; re-run to
    resume).
    """
    from .studies.sweep import SweepExecutionError, run_sweep  # lazy: start-up

    # options: jobs, scheduler, zip_, save_cases, series, plot_format, figure_size, batch, overwrite, allow_code,
    # restart
    try:
        table = run_sweep(scenario, sets, out_dir=out_dir, plot=not no_plot, command=command_line(), **options)
    except SweepExecutionError as exc:
        fail(str(exc), EXIT_SOLVER)
    except KeyboardInterrupt as exc:
        sweep_interrupted(exc, out_dir)
    echo_sweep(table, out_dir)


# ------------------------------------------------------------------------------ snoworm odds (issue 33)
@main.command()
@click.argument("scenario", type=click.Path(dir_okay=False))
@out_option("Directory for odds.json, samples.csv and the figures. Re-running the same command resumes there.")
@click.option(
    "--vary",
    multiple=True,
    metavar="PATH=DIST:PARAMS",
    help="An uncertain numeric scenario field and its distribution: normal:MEAN:SD, lognormal:MEAN:SD (of the "
    "value), uniform:LOW:HIGH, triangular:LOW:MODE:HIGH, truncnormal:MEAN:SD:LOW:HIGH; e.g. "
    "--vary terrain.xt=normal:0.8:0.05 (repeatable; adds to the scenario's uncertainty: section).",
)
@click.option(
    "--xt-field",
    metavar="sd=SD,corr=METRES",
    default=None,
    help="A spatially random X_t field around the route's X_t (standard deviation, correlation length), "
    "clipped to [0.05, 1]; each draw has the same field for every strategy.",
)
@click.option(
    "--calibration",
    type=click.Path(file_okay=False),
    default=None,
    help="A `snoworm calibrate` output folder: its fitted coefficients drawn jointly with their covariance.",
)
@click.option(
    "--set",
    "sets",
    multiple=True,
    metavar="KEY=VALUE",
    help="Fix a scenario value for every draw (a fixed key is not uncertain).",
)
@click.option(
    "--samples",
    default=1000,
    show_default=True,
    type=int,
    help="Number of draws (with --sensitivity: the base size n; n (k + 2) draws for k inputs).",
)
@click.option(
    "--method",
    type=click.Choice(["random", "sobol", "lhs"]),
    default="random",
    show_default=True,
    help="Monte Carlo, scrambled Sobol' points or Latin hypercube.",
)
@click.option(
    "--seed", default=0, show_default=True, type=click.IntRange(min=0), help="Seed of the draws and of the X_t fields."
)
@click.option(
    "--strategy",
    "strategy",
    default="scenario",
    show_default=True,
    metavar="LIST",
    help="Comma-separated strategies run on the same draws: scenario (the mode as written), rolling, inching, supervisor.",
)
@click.option(
    "--sensitivity", is_flag=True, help="Also first-order and total Sobol indices (with bootstrap intervals)."
)
@click.option(
    "--fidelity",
    type=click.Choice(["transient", "steady"]),
    default="transient",
    show_default=True,
    help="transient: simulate every draw; steady: screen each route element at its steady state (fast, docs/odds.md).",
)
@click.option(
    "--goal-m",
    type=float,
    default=None,
    help="The leader's distance that counts as the end of the route [m] (default: the route's last point).",
)
@click.option(
    "--rolling-speed",
    type=float,
    default=None,
    help="Wheel speed of the rolling strategy when the scenario's mode does not roll [m/s].",
)
@click.option("-j", "--jobs", default=1, show_default=True, type=click.IntRange(min=1), help="Local worker processes.")
@click.option(
    "--scheduler",
    metavar="ADDRESS",
    default=None,
    help="Run the draws on a Dask scheduler (tcp://host:port); overrides -j.",
)
@click.option("--no-plot", is_flag=True, help="Skip the figures.")
@plot_format_option
@click.option(
    "--overwrite", is_flag=True, help="Replace another odds study (or a folder snoworm did not write) in --out."
)
@allow_code_option
@handle_errors
def odds(scenario, out_dir, vary, xt_field, calibration, sets, strategy, no_plot, **options):
    """The odds that SCENARIO gets through with uncertain snow: P(go) per strategy with its 95 % interval.

    \b
    Writes to --out: odds.json (per strategy p_go, p_go_ci (Wilson), n, percentiles 5/50/95 of time, speed
    made good and energy per metre, where draws stop; the inputs, seed and method; with --sensitivity the
    Sobol indices), samples.csv (one row per draw and strategy, appended as each finishes), and the figures
    odds.png, stops.png, convergence.png (and sobol.png).  Model error is not sampled (docs/odds.md).
    Exit status: 0 done (even with failed draws), 2 bad input, 1 if a worker or the cluster fails, 130
    when interrupted (re-run to resume).
    """
    from .studies.odds import odds as run_odds  # lazy: start-up

    strategies = [s.strip() for s in strategy.split(",") if s.strip()]
    try:
        res = run_odds(
            scenario,
            vary=vary,
            xt_field=xt_field,
            calibration=calibration,
            sets=sets,
            strategies=strategies,
            out_dir=out_dir,
            plot=not no_plot,
            command=command_line(),
            **options,
        )
    except KeyboardInterrupt as exc:
        _odds_interrupted(exc, out_dir)
    except Exception as exc:
        from .studies.sweep import SweepExecutionError  # lazy: start-up

        if isinstance(exc, SweepExecutionError):
            fail(str(exc), EXIT_SOLVER)
        raise
    click.echo(res.text)
    click.echo(f"wrote {out_dir}: odds.json, samples.csv" + ("" if no_plot else ", figures"))


def _odds_interrupted(exc, out_dir):
    """An interrupted odds study: where its finished draws are, exit 130 (143 on SIGTERM)."""
    from .commands.common import Terminated  # lazy: start-up

    how = "terminated (SIGTERM)" if isinstance(exc, Terminated) else "interrupted"
    click.echo(f"{how}: finished draws are in {out_dir}/samples.csv; run the same command again to resume.", err=True)
    sys.exit(143 if isinstance(exc, Terminated) else 130)


for _command in STUDY_COMMANDS:
    main.add_command(_command)


@main.command()
@handle_errors
def scenarios():
    """List the shipped scenarios, one line each (name and description).

    Run one by name from anywhere: `snoworm run inchworm6 --out out/` (a path that exists wins
    over a name).
    """
    echo_scenarios()


if __name__ == "__main__":  # pragma: no cover
    main()
