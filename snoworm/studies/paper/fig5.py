"""Figure 5: inchworm movement of a six-segment SnoWorm (paper section 5.1)."""

from __future__ import annotations

import numpy as np

from ... import plotting
from .claims import QUICK_INCHWORM_DURATION_S, Context, Section, make_claim, start_time_s, steady_mean

__all__ = [
    "FIG5_PAIRS",
    "FIG5_PAIR_RMS_MAX",
    "FIG5_NONPAIR_RMS_MIN",
    "FIG5_MOVE_MIN_M",
    "FIG5_PEAK_EARLY_FRACTION",
    "FIG5_LATE_FRACTION_MAX",
    "FIG5_LATE_EVERY_MAX",
    "SLIDING_FRACTION",
    "FIG5_XT_HIGH",
    "pair_overlap",
    "backward_sliding_timing",
    "check_fig5",
    "fig5_runs",
    "item_fig5",
]


#: Segments that move together in the six-segment gait (paper section 5.1).
FIG5_PAIRS = ((0, 3), (1, 4), (2, 5))
#: Largest RMS speed difference of a pair, relative to the peak speed, that counts as overlapping.
FIG5_PAIR_RMS_MAX = 0.3
#: Smallest RMS speed difference of two segments of different pairs, relative to the peak speed.
FIG5_NONPAIR_RMS_MIN = 0.5
#: Displacement that counts as moving forward [m].
FIG5_MOVE_MIN_M = 0.1


def _duration(ctx):
    return [f"simulation.duration_s={QUICK_INCHWORM_DURATION_S:g}"] if ctx.quick else []


def pair_overlap(res, pairs=FIG5_PAIRS):
    """RMS difference of the speed traces of two segments over the run (from the gait start),
    relative to the peak ground speed, for every pair of segments.

    Returns
    -------
    dict
        ``pairs``: {"a&b": rms ratio} for the given pairs; ``others``: the same for every other
        pair of segments; ``peak_speed_mps``.
    """
    start = start_time_s(res)
    v = res.segments["v_mps"][res.t >= start]
    peak = float(np.abs(v).max())
    n = v.shape[1]

    def rms(a, b):
        return float(np.sqrt(np.mean((v[:, a] - v[:, b]) ** 2)) / peak)

    want = {tuple(sorted(p)) for p in pairs}
    out = {"pairs": {}, "others": {}, "peak_speed_mps": peak}
    for a in range(n):
        for b in range(a + 1, n):
            out["pairs" if (a, b) in want else "others"][f"{a}&{b}"] = rms(a, b)
    return out


#: Fig 5 timing: the held segments' peak backward speed falls within this fraction of a phase ...
FIG5_PEAK_EARLY_FRACTION = 0.25
#: ... and in the median phase's second half their backward speed stays below this fraction of that peak ...
FIG5_LATE_FRACTION_MAX = 0.6
#: ... and in every such phase it must at least drop off below this fraction of the peak.
FIG5_LATE_EVERY_MAX = 0.95


#: A phase counts as one "with backward sliding" when its held segments' peak backward speed is
#: at least this fraction of the run's largest.
SLIDING_FRACTION = 0.25


def backward_sliding_timing(res):
    """When the held segments slide backwards in each gait phase of an inchworm run.

    For every completed phase (from the mode summary; the phase cut off by the end of the run is
    left out) in which the held segments slide backwards noticeably -- their peak backward speed
    is at least ``SLIDING_FRACTION`` of the largest over the run; below that it is the slow
    creep of the smooth Coulomb law, with no peak to speak of -- the time
    of the held segments' most negative speed as a fraction of the phase duration, and the
    largest backward speed in the second half of the phase relative to that peak.

    Returns
    -------
    (peak_fraction, late_ratio) : list of float, list of float
    """
    t, v = res.t, res.segments["v_mps"]
    n = v.shape[1]
    phases = []
    for ph in res.mode_summary.get("phases", []):
        t0, t1 = ph["t_start_s"], ph["t_end_s"]
        sel = (t >= t0) & (t <= t1)
        held = [k for k in range(n) if k not in ph["moving"]]
        if sel.sum() < 3 or not held or t1 >= t[-1] - 1e-9:  # too short, or cut off by the end of the run
            continue
        phases.append((t0, t1, v[sel][:, held].min(1), t[sel]))
    run_peak = max((-p[2].min() for p in phases), default=0.0)
    peak_fraction, late_ratio = [], []
    for t0, t1, vh, tt in phases:
        if run_peak <= 0 or -vh.min() < SLIDING_FRACTION * run_peak:
            continue
        i = int(np.argmin(vh))
        peak_fraction.append(float((tt[i] - t0) / (t1 - t0)))
        late_ratio.append(float(max(-vh[tt >= t0 + 0.5 * (t1 - t0)].min(), 0.0) / -vh[i]))
    return peak_fraction, late_ratio


def _advance(res):
    x = res.segments["x_m"]
    return x[-1] - x[0]


def _mean_speed(res):
    start = start_time_s(res)
    return float(np.mean(_advance(res)) / (res.t[-1] - start))


def check_fig5(inch, roll, inch_hi) -> list:
    """Claims of Figure 5 from inchworm6, rolling6_xt025 and inchworm6 at a higher X_t."""
    return _movement_claims(inch, roll) + _higher_xt_claims(inch, inch_hi)


def _movement_claims(inch, roll) -> list:
    """Fig 5 at one X_t: inching advances where rolling is stuck; pairs overlap; backward sliding peaks early."""
    adv = _advance(inch)
    adv_roll = _advance(roll)
    ov = pair_overlap(inch)
    xt_lo = float(inch.scenario.terrain.xt)
    m_lo = inch.mode_summary
    timing = backward_sliding_timing(inch)
    return [
        make_claim(
            "fig5.inchworm_advances",
            "Fig 5",
            f"inchworm movement gives forward motion on X_t = {xt_lo:g}, 'through terrain that would "
            "immobilize a single-segment vehicle' (abstract, section 5.1)",
            {"advance_per_segment_m": adv, "gait_cycles": m_lo.get("gait_cycles"), "simulated_s": float(inch.t[-1])},
            f"every segment advances more than {FIG5_MOVE_MIN_M:g} m",
            bool(np.all(adv > FIG5_MOVE_MIN_M)),
        ),
        make_claim(
            "fig5.rolling_immobilised",
            "Fig 5",
            f"the same vehicle rolling (all wheels driven, rigid joints) on X_t = {float(roll.scenario.terrain.xt):g} "
            "is immobilised (section 3: no slip overcomes the resistance below X_t ~ 0.59)",
            {"advance_per_segment_m": adv_roll, "final_slip": steady_mean(roll, "segments", "slip")},
            f"no segment advances more than {FIG5_MOVE_MIN_M:g} m",
            bool(np.all(adv_roll <= FIG5_MOVE_MIN_M)),
        ),
        make_claim(
            "fig5.pairs_overlap",
            "Fig 5",
            "'Segments 0 & 3, 1 & 4, and 2 & 5 each have the same location within this movement pattern, "
            "their speeds therefore overlap' (section 5.1)",
            {
                "rms_difference_over_peak_pairs": ov["pairs"],
                "rms_difference_over_peak_other_max": max(ov["others"].values()),
                "rms_difference_over_peak_other_min": min(ov["others"].values()),
                "peak_speed_mps": ov["peak_speed_mps"],
            },
            f"RMS difference of each pair's speed traces (no time shift, from the gait start) <= "
            f"{FIG5_PAIR_RMS_MAX:g} x peak speed, and >= {FIG5_NONPAIR_RMS_MIN:g} x peak speed for every "
            "two segments of different pairs",
            max(ov["pairs"].values()) <= FIG5_PAIR_RMS_MAX and min(ov["others"].values()) >= FIG5_NONPAIR_RMS_MIN,
        ),
        make_claim(
            "fig5.backward_peak_early",
            "Fig 5",
            "'negative speeds peak shortly after motion starts, then drop off as the prismatic force is "
            "decreased' (section 5.1)",
            {"peak_time_fraction_of_phase": timing[0], "late_over_peak_backward_speed": timing[1]},
            f"in every gait phase with backward sliding, the held segments' most negative speed falls within "
            f"the first {FIG5_PEAK_EARLY_FRACTION:g} of the phase and in its second half their backward speed "
            f"stays below {FIG5_LATE_EVERY_MAX:g} x that peak, and below {FIG5_LATE_FRACTION_MAX:g} x in "
            "the median phase (the joint force itself is not checked)",
            bool(timing[0])
            and max(timing[0]) <= FIG5_PEAK_EARLY_FRACTION
            and max(timing[1]) < FIG5_LATE_EVERY_MAX
            and float(np.median(timing[1])) < FIG5_LATE_FRACTION_MAX,
        ),
    ]


def _higher_xt_claims(inch, inch_hi) -> list:
    """Fig 5 at a higher X_t: faster, less backward sliding, lower joint forces."""
    xt_lo, xt_hi = float(inch.scenario.terrain.xt), float(inch_hi.scenario.terrain.xt)
    m_lo, m_hi = inch.mode_summary, inch_hi.mode_summary
    v_lo, v_hi = _mean_speed(inch), _mean_speed(inch_hi)
    return [
        make_claim(
            "fig5.higher_xt_faster",
            "Fig 5",
            "'Simulations with higher terrain coefficients had similar results, but with ... higher forward "
            "speeds' (section 5.1)",
            {f"mean_speed_xt{xt_lo:g}_mps": v_lo, f"mean_speed_xt{xt_hi:g}_mps": v_hi},
            f"mean forward speed (mean advance / time since the gait start) at X_t = {xt_hi:g} > at {xt_lo:g}",
            v_hi > v_lo,
        ),
        make_claim(
            "fig5.higher_xt_less_sliding",
            "Fig 5",
            "higher terrain coefficients give 'less backwards sliding of stationary segments' (section 5.1)",
            {
                f"peak_backward_speed_held_xt{xt_lo:g}_mps": m_lo["peak_backward_speed_held_mps"],
                f"peak_backward_speed_held_xt{xt_hi:g}_mps": m_hi["peak_backward_speed_held_mps"],
            },
            f"peak backward speed of held segments at X_t = {xt_hi:g} < at {xt_lo:g}",
            m_hi["peak_backward_speed_held_mps"] < m_lo["peak_backward_speed_held_mps"],
        ),
        make_claim(
            "fig5.higher_xt_lower_joint_force",
            "Fig 5",
            "higher terrain coefficients need 'lower forces required for the prismatic joints' (section 5.1)",
            {
                f"peak_joint_force_xt{xt_lo:g}_N": m_lo["peak_joint_force_N"],
                f"peak_joint_force_xt{xt_hi:g}_N": m_hi["peak_joint_force_N"],
            },
            f"peak |joint force| at X_t = {xt_hi:g} < at {xt_lo:g}",
            m_hi["peak_joint_force_N"] < m_lo["peak_joint_force_N"],
        ),
    ]


#: Higher terrain coefficient for the Fig 5 comparison (paper: 'higher terrain coefficients').
FIG5_XT_HIGH = 0.5


def fig5_runs(ctx: Context) -> list:
    """The runs Figure 5 needs, as ``(scenario name, extra overrides)`` for :meth:`Context.run`:
    the inchworm on X_t = 0.25, rolling there, the inchworm on X_t = 0.5 (longest first).

    :func:`snoworm.studies.paper.report.evaluate` runs them in parallel before the item when ``jobs > 1``.
    """
    dur = _duration(ctx)
    return [("inchworm6", dur), ("inchworm6", dur + [f"terrain.xt={FIG5_XT_HIGH:g}"]), ("rolling6_xt025", dur)]


def item_fig5(ctx: Context) -> Section:
    """Figure 5: six-segment inchworm on X_t = 0.25, against rolling and against X_t = 0.5."""
    inch, hi, roll = (ctx.run(name, extra) for name, extra in fig5_runs(ctx))
    s = Section(
        "fig5",
        "Figure 5 - inchworm movement of a six-segment SnoWorm",
        (
            "Section 5.1: a six-segment SnoWorm inches on X_t = 0.25 with two segments held for each one that "
            "moves; 'a simple force controller is used on the prismatic joint to limit backwards sliding of the "
            "stationary segments'. 'Simulations with higher terrain coefficients had similar results, but with "
            "less backwards sliding of stationary segments, higher forward speeds, and lower forces required for "
            "the prismatic joints.' 'Segments 0 & 3, 1 & 4, and 2 & 5 ... their speeds therefore overlap.'"
        ),
        scenarios=["inchworm6", "rolling6_xt025", f"inchworm6 --set terrain.xt={FIG5_XT_HIGH:g}"]
        + ([f"(quick: all three with --set simulation.duration_s={QUICK_INCHWORM_DURATION_S:g})"] if ctx.quick else []),
        claims=check_fig5(inch, roll, hi),
    )
    ov = pair_overlap(inch)
    rows = ["| segments | RMS speed difference / peak speed | kind |", "|---|---|---|"]
    rows += [f"| {k} | {v:.3f} | moves together (paper) |" for k, v in ov["pairs"].items()]
    rows += [f"| {k} | {v:.3f} | different groups |" for k, v in ov["others"].items()]
    s.tables.append("\n".join(rows))
    s.notes.append(
        "Overlap measure: RMS of v_a(t) - v_b(t) from the gait start, without any time shift, divided "
        "by the peak ground speed of the run. The thresholds (pairs <= 0.3, others >= 0.5) were chosen "
        "by this report, not given by the paper. Within a pair the two segments start and stop "
        "together, but they are moved by different joints (e.g. segment 0 pushed by joint 0 extending, "
        "segment 3 pulled by joint 2 contracting), so their speed ramps differ and the pairs 0 & 3 "
        "and 2 & 5 overlap less closely than 1 & 4. The timing thresholds of fig5.backward_peak_early "
        "(first quarter of the phase; in its second half below 0.95 of the peak in every phase and 0.6 in the median phase, counting phases whose sliding reaches a quarter of the run's peak) are also this report's."
    )
    if ctx.out_dir is not None:
        s.figures.append(
            plotting.write_figure(
                ctx.figure("fig5_speeds.png"), plotting.plot_groups, inch, FIG5_PAIRS, size=ctx.figure_size
            )
        )
        s.figures.append(
            plotting.write_figure(ctx.figure("fig5_positions.png"), plotting.plot_positions, inch, size=ctx.figure_size)
        )
    return s
