"""The study commands (click): ground truth and calibration (paper Table 2 and Figure 3), the
mobility map and the paper reproduction.  Thin: each calls the Python API of
:mod:`snoworm.studies`; :mod:`snoworm.cli` adds them to the ``snoworm`` group.
"""

from __future__ import annotations

import sys

import click

from .common import (
    CpuClock,
    command_line,
    echo_claims,
    echo_written,
    figure_size_option,
    handle_errors,
    model_file_option,
    out_option,
    overwrite_option,
    param_set_option,
    plot_format_option,
    progress_bar,
    set_option,
)

__all__ = ["groundtruth", "terrain_curves", "calibrate", "mobility_map", "paper", "STUDY_COMMANDS"]


# ---------------------------------------------------------------- ground truth and calibration
# (snoworm/studies/groundtruth.py, snoworm/studies/calibrate.py; paper Table 2 and Figure 3)
@click.command()
@click.option(
    "--data",
    "data_path",
    type=click.Path(dir_okay=False),
    default=None,
    help="Field-data CSV (default: the shipped FrostyBoy 2020 data, paper Table 2).",
)
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
    --out/table2.csv (with residuals, model minus measured), --out/table2.png and a copy of the
    field data compared, --out/inputs/ (its SHA-256 in the folder's manifest).
    """
    from ..studies.groundtruth import run_groundtruth  # lazy: start-up

    _, text, paths = run_groundtruth(
        out_dir,
        data_path,
        parameter_set_name,
        model_file,
        plot=not no_plot,
        plot_format=plot_format,
        overwrite=overwrite,
        figure_size=figure_size,
        command=command_line(),
    )
    echo_written(text, paths, out_dir)


@click.command("terrain-curves")
@click.option(
    "--xt",
    "xts",
    type=float,
    multiple=True,
    required=True,
    help="Terrain coefficient X_t in (0, 1] (repeatable), e.g. --xt 1 --xt 0.5 for paper Figure 3.",
)
@out_option("Directory for terrain_curves.csv and terrain_curves.png.")
@param_set_option
@model_file_option
@click.option(
    "--points",
    "n_points",
    type=click.IntRange(min=3, max=100_001),  # groundtruth.MAX_CURVE_POINTS (not imported: start-up)
    default=1001,
    show_default=True,
    help="Number of slip values on [0, 1].",
)
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
    from ..studies.groundtruth import run_terrain_curves  # lazy: start-up

    # options: parameter_set_name, model_file, n_points, plot_format, overwrite (run_terrain_curves' names)
    _, text, paths = run_terrain_curves(xts, out_dir, plot=not no_plot, command=command_line(), **options)
    echo_written(text, paths, out_dir)


@click.command()
@click.argument("field_csv", metavar="FIELD.csv", type=click.Path(dir_okay=False))
@click.option(
    "--fit",
    "fit",
    multiple=True,
    required=True,
    metavar="NAME",
    help="Parameter to fit (repeatable): b_tF, b_trF, A, peak_exponent_d, tau0, tau1, or xt (fits every case's X_t).",
)
@out_option("Directory for terrain_model.yaml and calibration.json.")
@param_set_option
@click.option(
    "--model-file",
    type=click.Path(dir_okay=False),
    default=None,
    help="YAML of terrain-model coefficients to start from instead of the parameter set's.",
)
@click.option(
    "--torque-scale",
    "torque_scale_Nm",
    type=float,
    default=1.0,
    show_default=True,
    help="Torque residual unit [N m]: residual = (model - measured) / this.",
)
@click.option(
    "--slip-scale",
    "slip_scale",
    type=float,
    default=0.01,
    show_default=True,
    help="Slip residual unit (fraction; 0.01 = one percentage point).",
)
@overwrite_option
@handle_errors
def calibrate(field_csv, fit, out_dir, **options):
    """Fit terrain-model coefficients to the steady cases of FIELD.csv (least squares).

    FIELD.csv has the columns case, surface, speed_mps, wheel_speed_mps, slip (a fraction),
    torque_Nm (per wheel), drawbar_N, xt; lines starting with # are comments (see
    data/frostyboy_2020.csv).  Each case gives a torque and a slip residual.  Prints fitted
    values with standard errors and the residual table before and after, and writes
    --out/terrain_model.yaml (use it in a scenario with terrain.model_file),
    --out/calibration.json and a copy of FIELD.csv as fitted, --out/inputs/ (its SHA-256 in the
    folder's manifest).  Nothing is written if the input is invalid (exit 2).
    """
    from ..studies.calibrate import run_calibration  # lazy: start-up

    # options: parameter_set_name, model_file, torque_scale_Nm, slip_scale, overwrite (run_calibration's names)
    with progress_bar(1, "calibrate", "model evaluations (budget)") as bar:
        _, text, paths = run_calibration(field_csv, fit, out_dir, progress=bar.set, command=command_line(), **options)
    echo_written(text, paths, out_dir)


# ---------------------------------------------------------------- mobility map (snoworm/studies/mobility.py)


@click.command("mobility-map")
@click.argument("scenario", type=click.Path(dir_okay=False))
@click.option(
    "--xt",
    "xt_spec",
    default="0.2:1.0:9",
    show_default=True,
    help="Terrain coefficients X_t in (0, 1]: START:STOP:COUNT or a comma-separated list.",
)
@click.option(
    "--tow", "tow_spec", default="0", show_default=True, help="Tow forces [N], comma-separated (|force| at most 1e6 N)."
)
@click.option(
    "--grade",
    "grade_spec",
    default="0",
    show_default=True,
    help="Constant grades [deg], positive uphill, |grade| <= 40: START:STOP:COUNT or a comma-separated "
    "list. Several grades add gradeability.png (steepest grade climbed against X_t, per gait).",
)
@click.option(
    "--gait",
    "gaits",
    multiple=True,
    help="Inchworm gait to map, repeatable: a name (six_segment, two_segment) or phases as a list, e.g. "
    "'[[0],[1],[2],[3],[4],[5]]' (default: the scenario's). Several: one gradeability curve each.",
)
@out_option("Directory for mobility_map.csv and mobility_map.png (and gradeability.csv, gradeability.png).")
@set_option
@click.option(
    "--rolling-speed",
    "rolling_speed_mps",
    type=float,
    default=None,
    help="Rolling wheel-speed set-point [m/s] (default: the scenario's supervisor or uniform mode).",
)
@click.option(
    "--slip-cap",
    "slip_cap",
    type=float,
    default=0.3,
    show_default=True,
    help="Slip cap in (0, 1] of the slip-capped rolling limit: with several --grade values each X_t gets the "
    "steepest grade rolled once moving, from rest and with the steady slip at most this (gradeability.csv).",
)
@click.option("--no-inching", is_flag=True, help="Rolling only (steady state, no inching simulations).")
@click.option(
    "--inch-duration",
    "inch_duration_s",
    type=click.FloatRange(min=0, min_open=True),
    default=8.0,
    show_default=True,
    help="Simulated time of each inching run [s].",
)
@click.option(
    "-j",
    "--jobs",
    type=click.IntRange(min=1),
    default=1,
    show_default=True,
    help="Worker processes for the inching runs.",
)
@click.option(
    "--every-cell",
    is_flag=True,
    help="Simulate inching in every cell, also where the chain rolls (to compare the two modes' energy "
    "per metre there); by default only cells that do not roll are simulated (same regions).",
)
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
    also --out/gradeability.csv and --out/gradeability.png, and prints per X_t the rolling limits once
    moving, from rest and below --slip-cap in a sentence).  At most 100000 cells (X_t x grades x tows,
    the bound of one sweep).  Progress of the inching runs goes to stderr.
    """
    from ..studies.mobility import run_mobility_map  # lazy: start-up

    # options: grade_spec, gaits, rolling_speed_mps, slip_cap, inch_duration_s, jobs, every_cell, plot_format,
    # figure_size, overwrite
    # (run_mobility_map's names)
    clock = CpuClock()
    with progress_bar(1, "mobility map", "inching runs") as bar:
        _, text, paths = run_mobility_map(
            scenario,
            xt_spec,
            tow_spec,
            out_dir,
            sets,
            inching=not no_inching,
            plot=not no_plot,
            progress=bar.set,
            command=command_line(),
            **options,
        )
    echo_written(text, paths, out_dir, clock)


# ---------------------------------------------------------------- paper reproduction (snoworm/studies/paper/)


@click.command()
@out_option("Directory for the figures, report.md, report.html (self-contained) and claims.json.")
@click.option(
    "--quick",
    is_flag=True,
    help="Shorter inchworm runs (10 s simulated instead of 30 s) for CI; every figure's claims are still checked.",
)
@click.option(
    "--strict",
    is_flag=True,
    help="Exit with status 1 if any claim fails (default: exit 0 and record failures in the report).",
)
@click.option(
    "-j",
    "--jobs",
    type=click.IntRange(min=1),
    default=None,
    help="Worker processes running the items in parallel (default: the usable cores, at most 8; "
    "1 runs them one after the other). The claims and the report do not depend on it.",
)
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
    from ..studies.paper import default_jobs, run_paper  # lazy: start-up

    clock = CpuClock()
    rep = run_paper(
        out_dir,
        quick=quick,
        progress=lambda line: click.echo(line, err=True),
        overwrite=overwrite,
        jobs=default_jobs() if jobs is None else jobs,
        plot_format=plot_format,
        figure_size=figure_size,
        command=command_line(),
    )
    if echo_claims(rep, out_dir, quick, clock) < len(rep.claims) and strict:
        sys.exit(1)


#: The commands :mod:`snoworm.cli` adds to its group.
STUDY_COMMANDS = (groundtruth, terrain_curves, calibrate, mobility_map, paper)
