"""Command-line interface (click).  Thin: every command calls the Python API.

Exit status: 0 success, 1 solver failure (with the solver's message), 2 bad input (a clear
one-paragraph message naming the field and the fix, never a traceback).  What every command
shares (error handling, exit statuses, common options, progress, logging) is in
:mod:`snoworm.commands.common`; the study commands (ground truth, calibration, mobility map,
paper) are in :mod:`snoworm.commands.studies`.
"""

from __future__ import annotations

import math
import os
import sys

import click

from ._version import __version__
from .commands.common import (
    EXIT_INPUT,
    EXIT_SOLVER,
    CommandGroup,
    CpuClock,
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
    simulated time goes to stderr, and so does which controller code runs (if any), and one line
    when the chain drives past the end of its route file (beyond it the terrain is held).

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
        clock = CpuClock()
        res = simulate(sc, progress=bar.set, allow_code=allow_code)
        cpu_s = clock.seconds()[1]
    paths = res.write(
        out_dir,
        plot=not no_plot,
        plot_format=plot_format,
        overwrite=overwrite,
        figure_size=figure_size,
        command=command_line(),
    )
    echo_run(sc.name, res, paths, out_dir, cpu_s)
    if sc.terrain.route is not None:  # one line on stderr when the run left the route file's end
        from .config.routes import route_end_warning  # lazy: start-up

        front = res.segments["x_m"][:, 0] + sc.vehicle.segment_params()[0].wheelbase_m / 2.0
        note = route_end_warning(sc.terrain.route_data(), res.t, front.tolist())
        if note:
            click.echo(note, err=True)


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
    clock = CpuClock()
    try:
        table = run_sweep(scenario, sets, out_dir=out_dir, plot=not no_plot, command=command_line(), **options)
    except SweepExecutionError as exc:
        fail(str(exc), EXIT_SOLVER)
    except KeyboardInterrupt as exc:
        sweep_interrupted(exc, out_dir)
    echo_sweep(table, out_dir, clock)


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


# ------------------------------------------------------------------ animate (issue 34)
@main.command()
@click.argument("result_dir", type=click.Path(file_okay=False))
@click.option(
    "--fps", default=20, show_default=True, type=click.IntRange(1, 60), help="Frames per second of the video."
)
@click.option(
    "--speed-up",
    type=float,
    default=None,
    metavar="X",
    help="Simulated seconds per second of video [default: the run in at most 20 s of video, never faster "
    "than real time (1)].",
)
@click.option(
    "--format",
    "fmt",
    type=click.Choice(["gif", "mp4"]),
    default=None,
    help="Video format [default: the --out file's suffix, else mp4 when the ffmpeg program is installed, "
    "else gif]; mp4 needs ffmpeg.",
)
@click.option(
    "--out",
    "out_file",
    type=click.Path(dir_okay=False),
    default=None,
    help="The video file [default: RESULT_DIR/animation.gif or .mp4, listed in the folder's manifest].",
)
@click.option("--overwrite", is_flag=True, help="Replace an existing --out file snoworm did not write.")
@handle_errors
def animate(result_dir, fps, speed_up, fmt, out_file, overwrite):
    """Animate the run in RESULT_DIR (a folder written by `snoworm run`): the chain moving along its
    route, segments, wheels and links to scale, the links coloured by their force (tension red,
    compression blue), the terrain's elevation with X_t as a colour band under it, the time and the
    gait phase in a corner, the view following the chain.

    Written atomically; into RESULT_DIR under its lock (never while another snoworm process writes
    it). Progress goes to stderr. Exit status 2 for a bad option, a folder that is not a run or mp4
    without ffmpeg.
    """
    from .plotting.animation import AnimationOptionError, check_options, ffmpeg_available  # lazy: matplotlib
    from .results.result import load_result  # lazy: start-up

    suffix = os.path.splitext(out_file)[1].lower().lstrip(".") if out_file is not None else ""
    fmt = fmt or (suffix if suffix in ("gif", "mp4") else "mp4" if ffmpeg_available() else "gif")
    try:
        check_options(0.0, fps, speed_up, fmt)  # the options alone, before reading anything
    except AnimationOptionError as exc:
        fail(f"{exc}.", EXIT_INPUT)
    path = os.path.abspath(out_file if out_file is not None else os.path.join(result_dir, f"animation.{fmt}"))
    if os.path.lexists(path) and not overwrite and not _written_by_snoworm(path):
        fail(f"{path} exists and snoworm did not write it; give another --out or pass --overwrite.", EXIT_INPUT)
    res = load_result(result_dir)
    duration = float(res.t[-1] - res.t[0])
    try:
        speed_up = check_options(duration, fps, speed_up, fmt)
        with progress_bar(1 + math.floor(duration * fps / speed_up + 1e-9), "animate", "frames") as bar:
            out = res.animate(path, fps=fps, speed_up=speed_up, fmt=fmt, progress=lambda done, total: bar.set(done))
    except AnimationOptionError as exc:
        fail(f"{exc}.", EXIT_INPUT)
    click.echo(f"{res.scenario.name}: {duration:g} s at {speed_up:g}x, {fps} fps -> {out}")


def _written_by_snoworm(path: str) -> bool:
    """``path`` is listed in the manifest of the snoworm output folder holding it."""
    from .infra.folders import folder_state, read_manifest  # lazy: start-up

    folder = os.path.dirname(path)
    if folder_state(folder) != "snoworm":
        return False
    man = read_manifest(folder) or {}
    return os.path.basename(path) in man.get("files", [])


# ------------------------------------------------------------------ route files (issue 34)
@main.group(cls=CommandGroup)
def route():
    """Route files (docs/model.md section 7): import a GPS track as a route."""


@route.command("import")
@click.argument("track", type=click.Path(dir_okay=False))
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False), help="The route file (CSV).")
@click.option(
    "--smooth-m",
    default=20.0,
    show_default=True,
    type=float,
    metavar="M",
    help="Full width of the triangular window that smooths the GPS elevations along the track [m]; 0 keeps them raw.",
)
@click.option("--xt", type=float, default=None, help="A constant X_t for the whole route, in (0, 1].")
@click.option(
    "--xt-tag",
    default=None,
    metavar="TAG",
    help="X_t per point, from the element TAG in each point's <extensions> (any namespace), e.g. --xt-tag xt.",
)
@click.option("--overwrite", is_flag=True, help="Replace an existing --out file.")
@handle_errors
def route_import(track, out_file, smooth_m, xt, xt_tag, overwrite):
    """Turn the GPS track TRACK (a GPX file) into a route file that `terrain.route` reads.

    \b
    distance_m: the geodesic on the WGS84 ellipsoid (Vincenty) summed over the track's points;
    elevation_m: the points' <ele>, smoothed along the track over --smooth-m;
    xt: --xt for every point, or each point's <extensions><TAG> (--xt-tag TAG).
    The raw latitude, longitude and elevation are kept as extra columns. The file is read back as
    a route before it replaces --out (written atomically). Exit status 2 for a bad GPX file (the
    line and the fix) or an existing --out without --overwrite.
    """
    from .config.gpx import read_gpx, route_csv, route_from_track  # lazy: start-up
    from .config.routes import read_route  # lazy: start-up
    from .infra.folders import add_file  # lazy: start-up

    if (xt is None) == (xt_tag is None):
        fail(
            "give the route's X_t: either a constant (--xt 0.8) or the points' extension tag (--xt-tag xt).", EXIT_INPUT
        )
    out = os.path.abspath(out_file)
    if os.path.lexists(out) and not overwrite:
        fail(f"{out} exists; give another --out or pass --overwrite to replace it.", EXIT_INPUT)
    rt = route_from_track(read_gpx(track, xt_tag), smooth_m, xt)
    with add_file(out) as tmp:
        tmp.write_text(route_csv(rt, os.path.basename(track)), encoding="utf-8")
        read_route(tmp)  # reads back as a route, or nothing replaces --out
    z = rt.elevation_m
    click.echo(
        f"{out}: {rt.distance_m.size} points, {rt.distance_m[-1]:.1f} m along the track, elevation "
        f"{z.min():.1f} to {z.max():.1f} m (smoothed over {smooth_m:g} m), X_t {rt.xt.min():g} to {rt.xt.max():g}"
        + (f"; {rt.dropped} points within a centimetre of the previous one dropped" if rt.dropped else "")
    )


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
