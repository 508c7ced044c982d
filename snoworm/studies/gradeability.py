"""Gradeability from a mobility map with a grade axis: the steepest grade each gait climbs (beyond the paper).

Reads the cells of :func:`snoworm.studies.mobility.mobility_map` (docs/model.md section 7): per X_t and tow,
the steady limits of a rolling chain (continuous: once moving, :func:`snoworm.steady.max_grade_deg`; from
rest, :func:`snoworm.steady.max_grade_from_rest_deg`; below a slip cap,
:func:`snoworm.steady.max_grade_below_slip_deg`) and the sentence that says them in field terms
(:func:`rolling_sentence`), the steepest grid grade where the chain rolls, and for each inchworm gait the
steepest grid grade where it moved the chain, each with the electrical energy per metre climbed at that
grade (the cell's energy per metre along the track divided by ``sin(grade)``).  Pure bookkeeping on the
map's rows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..config.schema import Config, field
from ..slope import MAX_GRADE_DEG

__all__ = [
    "gradeability",
    "grade_text",
    "rolling_sentence",
    "gradeability_rows",
    "GRADEABILITY_COLUMNS",
    "SLIP_CAP",
    "SlipCap",
]

#: Default slip cap of the slip-capped limit (``--slip-cap``) [assumed]: 30 % is the highest steady slip at
#: which FrostyBoy was measured still moving (paper Table 2, case 5, deep loose snow); its field runs that
#: went further ended in slip-sinkage, which the laws of Eqs. 2-3 alone do not show (docs/model.md section 7).
SLIP_CAP = 0.3


@dataclass(frozen=True)
class SlipCap(Config):
    """The domain of the slip cap (``--slip-cap``), checked like a scenario field."""

    _section = ""
    slip_cap: float = field(
        gt=0,
        le=1,
        doc="slip cap of the slip-capped rolling limit",
        why="Slip (Eq. 1) of a wheel driving forward lies in (0, 1]; 1 is full spin.",
    )


def _top(cells, moved, energy):
    """(steepest grade, energy per metre climbed there) of the cells where ``moved(cell)``."""
    ok = [r for r in cells if moved(r)]
    if not ok:
        return None, None
    top = ok[-1]
    per_m = energy(top)
    climb = math.sin(math.radians(top["grade_deg"]))
    return top["grade_deg"], (per_m / climb if per_m is not None and climb > 0 else None)


def gradeability(result: dict, tow_N: float) -> dict:
    """Steepest grade climbed against X_t, per gait, with the energy per metre climbed, for one tow.

    Returns
    -------
    dict
        ``xt``; ``rolling_max_grade_deg`` (steady limit of a rolling chain, None below -40 deg), beside it
        ``rolling_from_rest_grade_deg`` (a chain starting from rest) and ``rolling_slip_capped_grade_deg``
        (steady slip at most ``slip_cap``), with ``rolling_sentence`` saying the three in field terms
        (None where the map has no such limits); ``rolling_grid_deg`` and ``rolling_J_per_m_climbed``;
        ``inching``: ``{gait label: {"grid_deg": [...], "J_per_m_climbed": [...]}}`` (None: no grid grade
        moved the chain, or the cell was not simulated; energy None on a level or downhill grade).
    """
    gaits = result.get("gait_labels") or ["inching"]
    cap = result.get("slip_cap")
    out = {
        "xt": [],
        "rolling_max_grade_deg": [],
        "rolling_from_rest_grade_deg": [],
        "rolling_slip_capped_grade_deg": [],
        "slip_cap": cap,
        "rolling_sentence": [],
        "rolling_grid_deg": [],
        "rolling_J_per_m_climbed": [],
        "inching": {g: {"grid_deg": [], "J_per_m_climbed": []} for g in gaits},
    }
    for x in result["xts"]:
        cells = sorted(
            (r for r in result["rows"] if r["xt"] == x and r["tow_N"] == tow_N), key=lambda r: r["grade_deg"]
        )
        out["xt"].append(x)
        on = result["rolling_max_grade_deg"][tow_N][x]
        out["rolling_max_grade_deg"].append(on)
        if "rolling_from_rest_grade_deg" in result:
            rest = result["rolling_from_rest_grade_deg"][tow_N][x]
            capped = result["rolling_slip_capped_grade_deg"][tow_N][x]
            sentence = rolling_sentence(x, on, rest, capped, cap)
        else:
            rest = capped = sentence = None
        out["rolling_from_rest_grade_deg"].append(rest)
        out["rolling_slip_capped_grade_deg"].append(capped)
        out["rolling_sentence"].append(sentence)
        g, e = _top(cells, lambda r: r["rolling"], lambda r: r["rolling_energy_per_metre_J_per_m"])
        out["rolling_grid_deg"].append(g)
        out["rolling_J_per_m_climbed"].append(e)
        for lab in gaits:

            def per(r, lab=lab):
                return r.get("inching_by_gait", {}).get(lab, r)

            g, e = _top(
                cells,
                lambda r, per=per: per(r).get("inching"),
                lambda r, per=per: per(r).get("inching_energy_per_metre_J_per_m"),
            )
            out["inching"][lab]["grid_deg"].append(g)
            out["inching"][lab]["J_per_m_climbed"].append(e)
    return out


def _deg(g) -> str:
    """A grade limit in words: ``14.2 deg``, or at the model's bound ``40 deg (the steepest grade modelled)``."""
    return f"{g:.0f} deg (the steepest grade modelled)" if g >= MAX_GRADE_DEG else f"{g:.1f} deg"


def rolling_sentence(xt, on, rest, capped, cap) -> str:
    """The rolling limits at one X_t in a sentence a field engineer reads at once (docs/model.md section 7).

    ``on``, ``rest``, ``capped``: the steepest grade [deg] once moving, from rest and with the steady slip at
    most ``cap`` (None: not even ``MAX_GRADE_DEG`` downhill; negative: a downhill grade is needed), e.g.
    ``rolling: climbs up to 14.5 deg once moving, 12.7 deg from rest, 13.7 deg below 30 % slip`` or
    ``rolling: cannot start on level snow at X_t 0.4 (it would need 12.7 deg downhill)``.
    """
    pct = f"{100 * cap:g} %"
    steepest = f"{MAX_GRADE_DEG:g} deg"
    if on is None:
        return f"rolling: cannot move at X_t {xt:g}, not even {steepest} downhill"
    if rest is None or rest < 0:
        need = f"more than {steepest}" if rest is None else f"{-rest:.1f} deg"
        text = f"rolling: cannot start on level snow at X_t {xt:g} (it would need {need} downhill)"
        if rest is None or abs(on - rest) >= 0.05:  # once moving, another limit (else: nothing to add)
            once = f"climbs up to {_deg(on)}" if on >= 0 else f"still needs {-on:.1f} deg downhill"
            text += f"; once moving it {once}"
    else:
        text = f"rolling: climbs up to {_deg(on)} once moving, {_deg(rest)} from rest"
    if capped is None:
        return text + f"; its slip stays above {pct} even {steepest} downhill"
    if capped >= 0:
        return text + f", {_deg(capped)} below {pct} slip"
    return text + f"; below {pct} slip only from {-capped:.1f} deg downhill"


def grade_text(name: str, res: dict, inching: bool, every_cell: bool) -> str:
    """The mobility-map command's summary of a map with a grade axis: per tow, the steepest grade
    each gait climbs."""
    n_sim = sum(
        1
        for r in res["rows"]
        for c in (r.get("inching_by_gait") or {"": r}).values()
        if c.get("inching_speed_mps") is not None
    )
    lines = [
        f"{name}: mobility map, {len(res['xts'])} X_t x {len(res['grades'])} grades x {len(res['tows'])} tow "
        f"values, {res['wall_time_s']:.1f} s ({n_sim} inching runs)"
    ]
    top = max(res["grades"])
    for f in res["tows"]:
        g = res["gradeability"][f]
        lines.append(f"tow {f:g} N: steepest grade climbed [deg] (rolling: steady limit; inching: grid)")
        for j, x in enumerate(g["xt"]):
            rm = g["rolling_max_grade_deg"][j]
            rolls_all = all(r["rolling"] for r in res["rows"] if r["xt"] == x and r["tow_N"] == f)
            parts = [f"rolling {'none' if rm is None else f'{rm:.1f}'}"]
            for lab, curve in g["inching"].items() if inching else ():
                ig = curve["grid_deg"][j]
                inch = (
                    "not simulated (rolls on every grid grade)"
                    if ig is None and rolls_all and not every_cell
                    else "none on the grid"
                    if ig is None
                    else f">= {ig:g} (the grid's top)"
                    if ig == top
                    else f"{ig:g}"
                )
                parts.append(f"{'inching' if lab == 'inching' else lab} {inch}")
            lines.append(f"  X_t = {x:g}: " + ", ".join(parts))
            if g.get("rolling_sentence") and g["rolling_sentence"][j]:
                lines.append(f"    {g['rolling_sentence'][j]}")
        failed = [r for r in res["rows"] if r["tow_N"] == f and r.get("inching_note", "").startswith("solver")]
        if failed:
            lines.append(f"  inching run failed (solver) at {len(failed)} cells; see inching_note")
    if inching and not every_cell:
        lines.append(
            "inching simulated only where the chain does not roll, bisected over the grades (--every-cell: all)"
        )
    return "\n".join(lines)


#: Columns of ``gradeability.csv``: one row per tow and X_t, the rolling limits and the sentence, then for
#: each gait the steepest grid grade it climbed (``inching_grid_deg`` and ``inching_gait``).
GRADEABILITY_COLUMNS = (
    "tow_N",
    "xt",
    "rolling_max_grade_deg",
    "rolling_from_rest_grade_deg",
    "rolling_slip_capped_grade_deg",
    "slip_cap",
    "rolling_grid_deg",
    "inching_gait",
    "inching_grid_deg",
    "rolling_sentence",
)


def gradeability_rows(res: dict) -> list:
    """Rows of ``gradeability.csv`` from a map's ``gradeability``: per tow and X_t, and per gait."""
    rows = []
    for f in res["tows"]:
        g = res["gradeability"][f]
        for j, x in enumerate(g["xt"]):
            for lab, curve in g["inching"].items():
                rows.append(
                    {
                        "tow_N": f,
                        "xt": x,
                        **{k: g[k][j] for k in GRADEABILITY_COLUMNS[2:5]},
                        "slip_cap": g["slip_cap"],
                        "rolling_grid_deg": g["rolling_grid_deg"][j],
                        "inching_gait": lab if res.get("inching") else None,
                        "inching_grid_deg": curve["grid_deg"][j] if res.get("inching") else None,
                        "rolling_sentence": g["rolling_sentence"][j],
                    }
                )
    return rows
