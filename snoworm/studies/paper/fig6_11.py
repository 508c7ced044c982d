"""Figures 6 to 11: towing with closed-loop wheel speed (Figs 6, 7) and force control (Figs 8-11).

All from paper section 5.2.
"""

from __future__ import annotations

import math

import numpy as np

from ... import plotting
from .claims import STEADY_WINDOW_S, Context, Section, make_claim, start_time_s, steady_mean

__all__ = [
    "PAPER_TOW_N",
    "FIG6_TOL_N",
    "FC_TOL_N",
    "check_fig6",
    "item_fig6",
    "check_fig7",
    "item_fig7",
    "check_fig8",
    "item_fig8",
    "check_fig9",
    "item_fig9",
    "check_fig11",
    "item_fig11",
]


# ------------------------------------------------------------------------------- Figures 6, 7

PAPER_TOW_N = 200.0
FIG6_TOL_N = 1.0


def check_fig6(res) -> list:
    """Claims of Figure 6 from the tow6_uniform run."""
    T = steady_mean(res, "links", "force_N")
    W = steady_mean(res, "segments", "net_force_N")
    slip = steady_mean(res, "segments", "slip")
    n = W.size
    want = PAPER_TOW_N * np.arange(1, n) / n
    return [
        make_claim(
            "fig6.link_tensions",
            "Fig 6",
            f"'the 200 N load is evenly distributed across the six segment SnoWorm' (section 5.2): link k "
            f"carries (k+1)/6 of the tow, {', '.join(f'{w:.1f}' for w in want)} N",
            {"link_forces_N": T},
            f"|link force - 200 (k+1)/6 N| <= {FIG6_TOL_N:g} N for every link",
            bool(np.all(np.abs(T - want) <= FIG6_TOL_N)),
        ),
        make_claim(
            "fig6.net_forces_uniform",
            "Fig 6",
            "'once the vehicle starts actively driving, the net forces acting on each segment become uniform' "
            "(section 5.2): 200/6 = 33.3 N each",
            {"net_wheel_forces_N": W},
            f"|net wheel force - 33.33 N| <= {FIG6_TOL_N:g} N for every segment",
            bool(np.all(np.abs(W - PAPER_TOW_N / n) <= FIG6_TOL_N)),
        ),
        make_claim(
            "fig6.slip",
            "Fig 6",
            "steady slip 4.80 % on X_t = 0.9 at 1.8 m/s with 33.3 N per segment (docs/model.md section 5, derived)",
            {"slip_pct": 100 * slip},
            "|slip - 4.80 %| <= 0.05 percentage points for every segment",
            bool(np.all(np.abs(slip - 0.048) <= 5e-4)),
            source="model",
        ),
    ]


def item_fig6(ctx: Context) -> Section:
    """Figure 6: six segments towing 200 N, all wheels at 1.8 m/s from 1 s."""
    res = ctx.run("tow6_uniform")
    s = Section(
        "fig6",
        "Figure 6 - six segments towing 200 N, simultaneous start",
        (
            "Section 5.2: a 200 N towing force on the rear segment, X_t = 0.9, closed-loop wheel speed 1.8 m/s, "
            "controllers start just before 1 s. 'Once the vehicle starts actively driving, the net forces acting on "
            "each segment become uniform, and the 200 N load is evenly distributed across the six segment SnoWorm.'"
        ),
        scenarios=["tow6_uniform"],
        claims=check_fig6(res),
    )
    s.notes.append(f"Steady values are means over the last {STEADY_WINDOW_S:g} s of the {res.t[-1]:g} s run.")
    if ctx.out_dir is not None:
        s.figures.append(
            plotting.write_figure(ctx.figure("fig6_forces.png"), plotting.plot_forces, res, size=ctx.figure_size)
        )
    return s


def _settle_time(res, group, key, tol):
    """First time after which the series stays within ``tol`` of its final steady mean."""
    data = getattr(res, group)[key]
    final = steady_mean(res, group, key)
    bad = np.nonzero(np.any(np.abs(data - final) > tol, axis=1))[0]
    return (
        float(res.t[bad[-1] + 1])
        if bad.size and bad[-1] + 1 < res.t.size
        else (float(res.t[0]) if not bad.size else math.nan)
    )


def check_fig7(res7, res6) -> list:
    """Claims of Figure 7 from the tow6_staggered run, against the tow6_uniform run."""
    T7 = steady_mean(res7, "links", "force_N")
    T6 = steady_mean(res6, "links", "force_N")
    last_start = float(np.max(res7.scenario.mode.start_time_s))
    settle = _settle_time(res7, "links", "force_N", FIG6_TOL_N)
    return [
        make_claim(
            "fig7.same_steady_state",
            "Fig 7",
            "with starts staggered by one second the simulation 'reaches the same steady state condition after "
            "the rear-most segment begins driving at Time ~ 6 s' (section 5.2)",
            {
                "link_forces_N": T7,
                "fig6_link_forces_N": T6,
                "last_start_s": last_start,
                "settled_within_1N_at_s": settle,
            },
            f"|link force - Fig 6's| <= {FIG6_TOL_N:g} N for every link (steady means), and the links settle "
            "after the last start and before the end of the run",
            bool(np.all(np.abs(T7 - T6) <= FIG6_TOL_N)) and last_start <= settle < float(res7.t[-1]) - STEADY_WINDOW_S,
        ),
    ]


def item_fig7(ctx: Context) -> Section:
    """Figure 7: Figure 6 with starts staggered by one second."""
    res7 = ctx.run("tow6_staggered")
    res6 = ctx.run("tow6_uniform")
    s = Section(
        "fig7",
        "Figure 7 - six segments towing 200 N, staggered start",
        (
            "Section 5.2: the same simulation 'with an exaggerated one second delay between each segment's start "
            "time ... reaches the same steady state condition after the rear-most segment begins driving at "
            "Time ~ 6s'; 'the simulation consistently reaches the same steady state forces with different "
            "initialization procedures'."
        ),
        scenarios=["tow6_staggered", "tow6_uniform"],
        claims=check_fig7(res7, res6),
    )
    if ctx.out_dir is not None:
        s.figures.append(
            plotting.write_figure(ctx.figure("fig7_forces.png"), plotting.plot_forces, res7, size=ctx.figure_size)
        )
    return s


# ------------------------------------------------------------------------------- Figures 8-11

FC_TOL_N = 2.0


def check_fig8(res) -> list:
    """Claims of Figure 8 from the pi2_zero run."""
    t = res.t
    T = res.links["force_N"][:, 0]
    sp = res.segments["speed_setpoint_mps"]
    start = start_time_s(res)
    Tss = float(steady_mean(res, "links", "force_N")[0])
    W = steady_mean(res, "segments", "net_force_N")
    sp0 = float(steady_mean(res, "segments", "speed_setpoint_mps")[0])
    before = T[t < start]
    after = T[t >= start]
    return [
        make_claim(
            "fig8.link_force_zero",
            "Fig 8",
            "the force between the two segments 'settles to zero as the controller operates' (section 5.2)",
            {"link_force_N": Tss},
            f"|steady link force| <= {FC_TOL_N:g} N",
            abs(Tss) <= FC_TOL_N,
        ),
        make_claim(
            "fig8.rear_carries_tow",
            "Fig 8",
            "with zero link force the rear segment carries the whole 200 N tow (force balance)",
            {"net_wheel_forces_N": W},
            f"|rear net - 200 N| <= {FC_TOL_N:g} N and |leader net| <= {FC_TOL_N:g} N",
            abs(W[-1] - PAPER_TOW_N) <= FC_TOL_N and abs(W[0]) <= FC_TOL_N,
            source="model",
        ),
        make_claim(
            "fig8.leader_setpoint",
            "Fig 8",
            "leader wheel-speed set-point about 1.679 m/s at X_t = 0.9 (docs/model.md section 5, derived)",
            {"leader_setpoint_mps": sp0},
            "|set-point - 1.679 m/s| <= 0.01 m/s",
            abs(sp0 - 1.679) <= 0.01,
            source="model",
        ),
        make_claim(
            "fig8.setpoint_nonnegative",
            "Fig 8",
            "the PI output V_sp 'is constrained to positive values so that the lead segment does not drive "
            "backwards' (section 5.2)",
            {"min_leader_setpoint_mps": float(sp[t >= start, 0].min())},
            "leader set-point >= 0 at every output time after the start",
            bool(np.all(sp[t >= start, 0] >= 0)),
        ),
        make_claim(
            "fig8.transient_shape",
            "Fig 8",
            "the connector force 'starts at a negative value (tension between segments), then goes positive as "
            "the vehicles start moving, and settles to zero' (section 5.2; in snoworm tension is positive, so "
            "the signs read: tension first, then compression, then zero)",
            {
                "link_force_just_before_start_N": float(before[-1]) if before.size else None,
                "min_link_force_after_start_N": float(after.min()),
                "steady_link_force_N": Tss,
            },
            f"tension (> {FC_TOL_N:g} N) just before the start, compression (< -{FC_TOL_N:g} N) at some time "
            f"after it, |steady| <= {FC_TOL_N:g} N",
            bool(before.size) and before[-1] > FC_TOL_N and after.min() < -FC_TOL_N and abs(Tss) <= FC_TOL_N,
        ),
    ]


def item_fig8(ctx: Context) -> Section:
    """Figure 8: two segments, the leader's PI drives the link force to zero."""
    res = ctx.run("pi2_zero")
    s = Section(
        "fig8",
        "Figure 8 - PI control of the link force to zero, two segments",
        (
            "Section 5.2: a PI controller uses a segment's wheel speed as control variable and the force in an "
            "adjacent connector as process value; two segments, 200 N pulling the rear backwards, the force between "
            "segments controlled to zero, the set-point constrained to positive values."
        ),
        scenarios=["pi2_zero"],
        claims=check_fig8(res),
    )
    s.notes.append(
        "The paper's Fig 8 text calls tension negative, while its Fig 6 text calls tension positive; "
        "snoworm uses tension positive throughout and the transient claim is read accordingly."
    )
    if ctx.out_dir is not None:
        s.figures.append(
            plotting.write_figure(ctx.figure("fig8_forces.png"), plotting.plot_forces, res, size=ctx.figure_size)
        )
        s.figures.append(
            plotting.write_figure(ctx.figure("fig8_speeds.png"), plotting.plot_speeds, res, size=ctx.figure_size)
        )
    return s


def check_fig9(res) -> list:
    """Claims of Figures 9-10 from the pi3_equal run."""
    T = steady_mean(res, "links", "force_N")
    W = steady_mean(res, "segments", "net_force_N")
    C = steady_mean(res, "segments", "connector_net_N")
    sp = steady_mean(res, "segments", "speed_setpoint_mps")
    return [
        make_claim(
            "fig9.link_tensions",
            "Figs 9-10",
            "'the lead segment works to maintain a constant 100 N tension between it and the middle segment, the "
            "middle segment works to maintain a constant 100 N tension between it and the rear-most' (section 5.2)",
            {"link_forces_N": T},
            f"|link force - 100 N| <= {FC_TOL_N:g} N for both links",
            bool(np.all(np.abs(T - 100.0) <= FC_TOL_N)),
        ),
        make_claim(
            "fig9.middle_zero_net_connector",
            "Figs 9-10",
            "'zero out the net connector force on the middle segment, while spreading the towed load evenly "
            "across the leader and rear-most segments' (section 5.2; Fig 10 force diagram)",
            {"net_connector_N": C, "net_wheel_forces_N": W},
            f"|middle net connector| <= {FC_TOL_N:g} N; wheel nets within {FC_TOL_N:g} N of 100 / 0 / 100 N",
            abs(C[1]) <= FC_TOL_N and bool(np.all(np.abs(W - [100.0, 0.0, 100.0]) <= FC_TOL_N)),
        ),
        make_claim(
            "fig9.middle_setpoint_lowest",
            "Figs 9-10",
            "the middle segment, pulling nothing, runs the lowest wheel-speed set-point (Fig 9; docs/model.md: "
            "1.800 / 1.747 / 1.800 m/s)",
            {"setpoints_mps": sp},
            "middle set-point < leader's and < rear's (strictly)",
            sp[1] < sp[0] and sp[1] < sp[2],
        ),
    ]


def item_fig9(ctx: Context) -> Section:
    """Figures 9-10: three segments, zero net connector force on the middle segment."""
    res = ctx.run("pi3_equal")
    s = Section(
        "fig9",
        "Figures 9 and 10 - three segments sharing the tow, zero net force on the middle",
        (
            "Section 5.2: 'a three segment vehicle works to zero out the net connector force on the middle segment, "
            "while spreading the towed load evenly across the leader and rear-most segments. The towed load is again "
            "200 N, so the lead segment works to maintain a constant 100 N tension between it and the middle segment, "
            "the middle segment works to maintain a constant 100 N tension between it and the rear-most segment.' "
            "Figure 10 shows the force distribution."
        ),
        scenarios=["pi3_equal"],
        claims=check_fig9(res),
    )
    if ctx.out_dir is not None:
        s.figures.append(
            plotting.write_figure(ctx.figure("fig9_forces.png"), plotting.plot_forces, res, size=ctx.figure_size)
        )
        s.figures.append(
            plotting.write_figure(ctx.figure("fig9_speeds.png"), plotting.plot_speeds, res, size=ctx.figure_size)
        )
        s.figures.append(
            plotting.write_figure(
                ctx.figure("fig10_force_diagram.png"), plotting.plot_force_diagram, res, size=ctx.figure_size
            )
        )
    return s


def check_fig11(res) -> list:
    """Claims of Figure 11 from the pi3_middle_positive run."""
    T = steady_mean(res, "links", "force_N")
    W = steady_mean(res, "segments", "net_force_N")
    C = steady_mean(res, "segments", "connector_net_N")
    sp = steady_mean(res, "segments", "speed_setpoint_mps")
    return [
        make_claim(
            "fig11.middle_positive_connector",
            "Fig 11",
            "the middle segment 'has a net positive connector force ... the segments behind and ahead of it are "
            "pushing and pulling it' (section 5.2)",
            {"net_connector_N": C, "link_forces_N": T},
            f"middle net connector force > {FC_TOL_N:g} N, link ahead in tension (> {FC_TOL_N:g} N), link "
            f"behind in compression (< -{FC_TOL_N:g} N)",
            C[1] > FC_TOL_N and T[0] > FC_TOL_N and T[1] < -FC_TOL_N,
        ),
        make_claim(
            "fig11.outer_segments_carry_more",
            "Fig 11",
            "'the other two segments therefore not only take on the entire 200 N towed load, but also provide "
            "drawbar force to move the middle segment' (section 5.2)",
            {"net_wheel_forces_N": W},
            f"leader + rear net wheel force > 200 N + {FC_TOL_N:g} N and middle net wheel force < -{FC_TOL_N:g} N",
            W[0] + W[2] > PAPER_TOW_N + FC_TOL_N and W[1] < -FC_TOL_N,
        ),
        make_claim(
            "fig11.middle_setpoint_lowest",
            "Fig 11",
            "'the wheel speed of the middle segment is lower relative to the other segments' (section 5.2)",
            {"setpoints_mps": sp},
            "middle set-point < leader's and < rear's (strictly)",
            sp[1] < sp[0] and sp[1] < sp[2],
        ),
    ]


def item_fig11(ctx: Context) -> Section:
    """Figure 11: three segments, positive net connector force on the middle segment."""
    res = ctx.run("pi3_middle_positive")
    s = Section(
        "fig11",
        "Figure 11 - three segments, positive net connector force on the middle",
        (
            "Section 5.2: 'rather than the middle segment providing an equal proportion of the required drawbar force, "
            "or zero net force through the connectors, it instead has a net positive connector force ... the connector "
            "forces are not kept equal, and the wheel speed of the middle segment is lower relative to the other "
            "segments.'"
        ),
        scenarios=["pi3_middle_positive"],
        claims=check_fig11(res),
    )
    s.notes.append(
        "The paper gives no target values for Fig 11; the scenario uses T0 = +50 N, T1 = -50 N "
        "(net connector force +100 N on the middle segment)."
    )
    if ctx.out_dir is not None:
        s.figures.append(
            plotting.write_figure(ctx.figure("fig11_forces.png"), plotting.plot_forces, res, size=ctx.figure_size)
        )
        s.figures.append(
            plotting.write_figure(ctx.figure("fig11_speeds.png"), plotting.plot_speeds, res, size=ctx.figure_size)
        )
    return s
