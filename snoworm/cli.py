"""Command-line interface (click).  Thin: every command calls the Python API.

Exit status: 0 success, 1 solver failure (with the solver's message), 2 bad input (a clear
one-paragraph message naming the field and the fix, never a traceback).  What every command
shares (error handling, exit statuses, common options, progress, logging) is in
:mod:`snoworm.cli_common`.
"""
from __future__ import annotations

import os
import sys

import click

from ._version import __version__
from .cli_common import (
    EXIT_SOLVER,
    CommandGroup,
    allow_code_option,
    code_check,
    command_line,
    configure_logging,
    echo_claims,
    echo_run,
    echo_scenarios,
    echo_sweep,
    echo_written,
    fail,
    figure_size_option,
    handle_errors,
    model_file_option,
    out_option,
    overwrite_option,
    param_set_option,
    plot_format_option,
    progress_bar,
    set_option,
    sweep_interrupted,
)


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
    """
    from .config.scenario import load_scenario  # lazy: start-up
    from .infra.folders import check_output_folder  # lazy: start-up
    from .simulation.driver import simulate  # lazy: start-up
    out_dir = os.path.abspath(out_dir)          # once: a controller's os.chdir does not move it
    sc = load_scenario(scenario, sets)
    code_check(sc, allow_code, "running")
    check_output_folder(out_dir, overwrite)
    from .modes.codeload import allow_code as allowed  # lazy: start-up
    with progress_bar(sc.simulation.duration_s, sc.name, "s simulated") as bar, allowed(allow_code):
        res = simulate(sc, progress=bar.set)
    paths = res.write(out_dir, plot=not no_plot, plot_format=plot_format, overwrite=overwrite, figure_size=figure_size,
                      command=command_line())
    echo_run(sc.name, res, paths, out_dir)


@main.command()
@click.argument("scenario", type=click.Path(dir_okay=False))
@set_option
@allow_code_option
@handle_errors
def validate(scenario, sets, allow_code):
    """Check SCENARIO without running it (exit 0 if valid, 2 with the reason if not).

    Nothing of the scenario runs: a controller is checked statically (the file or module exists,
    parses and defines the class) and against --allow-code as `snoworm run` would."""
    from .config.scenario import load_scenario  # lazy: start-up
    sc = load_scenario(scenario, sets)
    code_check(sc, allow_code)
    click.echo(f"{scenario}: valid ({sc.vehicle.segments} segments, mode {sc.mode.type}, "
               f"{sc.simulation.duration_s:g} s)")


# ---------------------------------------------------------------- ground truth and calibration
# (snoworm/studies/groundtruth.py, snoworm/studies/calibrate.py; paper Table 2 and Figure 3)
@main.command()
@click.option("--data", "data_path", type=click.Path(dir_okay=False), default=None,
              help="Field-data CSV (default: the shipped FrostyBoy 2020 data, paper Table 2).")
@out_option("Directory for table2.csv and table2.png.")
@param_set_option
@model_file_option
@click.option("--no-plot", is_flag=True, help="Skip table2.png.")
@plot_format_option
@figure_size_option
@overwrite_option
@handle_errors
def groundtruth(data_path, out_dir, parameter_set_name, model_file, no_plot, plot_format, figure_size, overwrite):
    """Compare the steady-state model with field data (paper Table 2).

    Runs the steady-state model on every case at its measured wheel speed R_w*omega, drawbar
    and X_t, prints measured against modelled speed, slip and torque, and writes
    --out/table2.csv (with residuals, model minus measured) and --out/table2.png.
    """
    from .studies.groundtruth import run_groundtruth  # lazy: start-up
    _, text, paths = run_groundtruth(out_dir, data_path, parameter_set_name, model_file, plot=not no_plot,
                                     plot_format=plot_format, overwrite=overwrite, figure_size=figure_size,
                                     command=command_line())
    echo_written(text, paths, out_dir)


@main.command("terrain-curves")
@click.option("--xt", "xts", type=float, multiple=True, required=True,
              help="Terrain coefficient X_t in (0, 1] (repeatable), e.g. --xt 1 --xt 0.5 for paper Figure 3.")
@out_option("Directory for terrain_curves.csv and terrain_curves.png.")
@param_set_option
@model_file_option
@click.option("--points", "n_points", type=click.IntRange(min=3), default=1001, show_default=True,
              help="Number of slip values on [0, 1].")
@click.option("--no-plot", is_flag=True, help="Skip terrain_curves.png.")
@plot_format_option
@figure_size_option
@overwrite_option
@handle_errors
def terrain_curves(xts, out_dir, no_plot, **options):
    """Tractive, resistive and net force per wheel against slip (paper Figure 3).

    Normal load per wheel is the static one (a quarter of the segment weight); the resistance is
    that of forward motion (Eq. 3 with sgn = +1).  Prints the slip at which the net force
    crosses zero for each X_t, or says that it stays negative.
    """
    from .studies.groundtruth import run_terrain_curves  # lazy: start-up
    # options: parameter_set_name, model_file, n_points, plot_format, overwrite (run_terrain_curves' names)
    _, text, paths = run_terrain_curves(xts, out_dir, plot=not no_plot, command=command_line(), **options)
    echo_written(text, paths, out_dir)


@main.command()
@click.argument("field_csv", metavar="FIELD.csv", type=click.Path(dir_okay=False))
@click.option("--fit", "fit", multiple=True, required=True, metavar="NAME",
              help="Parameter to fit (repeatable): b_tF, b_trF, A, peak_exponent_d, tau0, tau1, "
                   "or xt (fits every case's X_t).")
@out_option("Directory for terrain_model.yaml and calibration.json.")
@param_set_option
@click.option("--model-file", type=click.Path(dir_okay=False), default=None,
              help="YAML of terrain-model coefficients to start from instead of the parameter set's.")
@click.option("--torque-scale", "torque_scale_Nm", type=float, default=1.0, show_default=True,
              help="Torque residual unit [N m]: residual = (model - measured) / this.")
@click.option("--slip-scale", "slip_scale", type=float, default=0.01, show_default=True,
              help="Slip residual unit (fraction; 0.01 = one percentage point).")
@overwrite_option
@handle_errors
def calibrate(field_csv, fit, out_dir, **options):
    """Fit terrain-model coefficients to the steady cases of FIELD.csv (least squares).

    FIELD.csv has the columns case, surface, speed_mps, wheel_speed_mps, slip (a fraction),
    torque_Nm (per wheel), drawbar_N, xt; lines starting with # are comments (see
    data/frostyboy_2020.csv).  Each case gives a torque and a slip residual.  Prints fitted
    values with standard errors and the residual table before and after, and writes
    --out/terrain_model.yaml (use it in a scenario with terrain.model_file) and
    --out/calibration.json.  Nothing is written if the input is invalid (exit 2).
    """
    from .studies.calibrate import run_calibration  # lazy: start-up
    # options: parameter_set_name, model_file, torque_scale_Nm, slip_scale, overwrite (run_calibration's names)
    with progress_bar(1, "calibrate", "model evaluations (budget)") as bar:
        _, text, paths = run_calibration(field_csv, fit, out_dir, progress=bar.set, command=command_line(), **options)
    echo_written(text, paths, out_dir)

@main.command()
@click.argument("scenario", type=click.Path(dir_okay=False))
@click.option("--set", "sets", multiple=True, metavar="KEY=SPEC", required=True,
              help="A swept scenario key and its values: a list (tow.force_N=0,100,200) or an inclusive "
                   "range START:STOP:COUNT (terrain.xt=0.3:1.0:15 gives 15 values). Repeat for a grid "
                   "(first key slowest); a single value just overrides the key.")
@out_option("Directory for sweep.json, summary.csv and sweep.png / heatmap.png. Re-running the same "
            "command resumes an interrupted sweep there.")
@click.option("-j", "--jobs", default=1, show_default=True, type=click.IntRange(min=1),
              help="Local worker processes.")
@click.option("--scheduler", metavar="ADDRESS", default=None,
              help="Run the cases on a Dask distributed scheduler, e.g. tcp://10.0.0.5:8786 "
                   "(needs pip install 'snoworm[dask]'); overrides -j.")
@click.option("--zip", "zip_", is_flag=True,
              help="Pair the --set values element by element (equal lengths) instead of a full grid.")
@click.option("--save-cases", is_flag=True, help="Also write each case's time series to DIR/cases/<case_id>/.")
@click.option("--series", type=click.Choice(["folders", "netcdf"]), default="folders", show_default=True,
              help="With --save-cases: each case's time series in its own folder DIR/cases/<case_id>/, or every "
                   "case in one netCDF file DIR/series.nc (dims: swept keys x time x segment/link; needs "
                   "pip install 'snoworm[data]').")
@click.option("--no-plot", is_flag=True, help="Skip sweep.png / heatmap.png.")
@plot_format_option
@figure_size_option
@click.option("--batch", default=0, show_default=True, type=click.IntRange(min=0), metavar="B",
              help="Integrate up to B cases of the same structure (uniform or force-control mode) as one stacked system "
                   "(several times the cases/s; 100-500 is a good B); other cases run one by one.")
@click.option("--overwrite", is_flag=True,
              help="Replace another sweep in --out (its files are removed), or write into a non-empty folder "
                   "snoworm did not write.")
@click.option("--restart", is_flag=True, help="Run afresh a sweep in --out whose input files or snoworm version "
              "changed since (its rows are removed); without it such a resume exits 2 naming the file.")
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
      final_link_force_<j>_N, energy_per_m_J, immobilised, wall_time_s.
    immobilised: late_speed_mps < max(0.05 m/s, 5 * terrain.model.sign_eps_mps), i.e. only the
    creep allowed by the smooth sign of the terrain resistance is left (for a free-rolling
    FrostyBoy: X_t below about 0.586).

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


# ---------------------------------------------------------------- mobility map (snoworm/studies/mobility.py)

@main.command("mobility-map")
@click.argument("scenario", type=click.Path(dir_okay=False))
@click.option("--xt", "xt_spec", default="0.2:1.0:9", show_default=True,
              help="Terrain coefficients X_t in (0, 1]: START:STOP:COUNT or a comma-separated list.")
@click.option("--tow", "tow_spec", default="0", show_default=True, help="Tow forces [N], comma-separated (|force| at most 1e6 N).")
@click.option("--grade", "grade_spec", default="0", show_default=True,
              help="Constant grades [deg], positive uphill, |grade| <= 40: START:STOP:COUNT or a comma-separated "
                   "list. Several grades add gradeability.png (steepest grade climbed against X_t, per gait).")
@click.option("--gait", "gaits", multiple=True,
              help="Inchworm gait to map, repeatable: a name (six_segment, two_segment) or phases as a list, e.g. "
                   "'[[0],[1],[2],[3],[4],[5]]' (default: the scenario's). Several: one gradeability curve each.")
@out_option("Directory for mobility_map.csv and mobility_map.png (and gradeability.png).")
@set_option
@click.option("--rolling-speed", "rolling_speed_mps", type=float, default=None,
              help="Rolling wheel-speed set-point [m/s] (default: the scenario's supervisor or uniform mode).")
@click.option("--no-inching", is_flag=True, help="Rolling only (steady state, no inching simulations).")
@click.option("--inch-duration", "inch_duration_s", type=click.FloatRange(min=0, min_open=True), default=8.0,
              show_default=True, help="Simulated time of each inching run [s].")
@click.option("-j", "--jobs", type=click.IntRange(min=1), default=1, show_default=True,
              help="Worker processes for the inching runs.")
@click.option("--every-cell", is_flag=True,
              help="Simulate inching in every cell, also where the chain rolls (to compare the two modes' energy "
                   "per metre there); by default only cells that do not roll are simulated (same regions).")
@click.option("--no-plot", is_flag=True, help="Skip mobility_map.png.")
@plot_format_option
@figure_size_option
@overwrite_option
@handle_errors
def mobility_map(scenario, xt_spec, tow_spec, out_dir, sets, no_inching, no_plot, **options):
    """Which modes move SCENARIO's vehicle (a YAML file or a shipped name) over X_t, grade and tow.

    Regions: rolling, inching only, immobile.

    Rolling by the steady-state solver (each segment's share of the tow below its maximum
    drawbar); inching by short simulations of the inchworm gait of the scenario's supervisor or
    inchworm mode, in the cells that do not roll (every cell with --every-cell), bisected over the
    grades.  Writes --out/mobility_map.csv and --out/mobility_map.png (with several --grade values
    also --out/gradeability.png).  Progress of the inching runs goes to stderr.
    """
    from .studies.mobility import run_mobility_map  # lazy: start-up
    # options: grade_spec, gaits, rolling_speed_mps, inch_duration_s, jobs, every_cell, plot_format, figure_size,
    # overwrite
    # (run_mobility_map's names)
    with progress_bar(1, "mobility map", "inching runs") as bar:
        _, text, paths = run_mobility_map(scenario, xt_spec, tow_spec, out_dir, sets, inching=not no_inching,
                                          plot=not no_plot, progress=bar.set, command=command_line(), **options)
    echo_written(text, paths, out_dir)

# ---------------------------------------------------------------- paper reproduction (snoworm/studies/paper/)

@main.command()
@out_option("Directory for the figures, report.md, report.html (self-contained) and claims.json.")
@click.option("--quick", is_flag=True,
              help="Shorter inchworm runs (10 s simulated instead of 30 s) for CI; every figure's claims are "
                   "still checked.")
@click.option("--strict", is_flag=True,
              help="Exit with status 1 if any claim fails (default: exit 0 and record failures in the report).")
@click.option("-j", "--jobs", type=click.IntRange(min=1), default=None,
              help="Worker processes running the items in parallel (default: the usable cores, at most 8; "
                   "1 runs them one after the other). The claims and the report do not depend on it.")
@plot_format_option
@figure_size_option
@overwrite_option
@handle_errors
def paper(out_dir, quick, strict, jobs, plot_format, figure_size, overwrite):
    """Reproduce the paper: Figure 3, Table 2, Figures 5 to 11, in one command.

    Runs every scenario behind the paper's quantitative content, checks each of the paper's
    statements against the computed numbers with a stated tolerance, re-checks Figure 3 and
    Table 2 under the alternative readings of the paper (d = 1 in Eq. 2, an X_t-independent
    resistance torque, the traction torque-balance convention), and writes the figures,
    --out/report.md, --out/report.html and --out/claims.json (--plot-format pdf figures are linked
    from report.html, png and svg shown in it).  One progress line per item goes
    to stderr as it finishes.  A failing claim is reported, not fatal: the exit status is 0 unless
    --strict.
    """
    from .studies.paper import default_jobs, run_paper  # lazy: start-up
    rep = run_paper(out_dir, quick=quick, progress=lambda line: click.echo(line, err=True), overwrite=overwrite,
                    jobs=default_jobs() if jobs is None else jobs, plot_format=plot_format,
                    figure_size=figure_size, command=command_line())
    if echo_claims(rep, out_dir, quick) < len(rep.claims) and strict:
        sys.exit(1)


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
