"""Gradeability from a mobility map with a grade axis: the steepest grade each gait climbs (beyond the paper).

Reads the cells of :func:`snoworm.studies.mobility.mobility_map` (docs/model.md section 7): per X_t and tow,
the steady maximum grade of a rolling chain (:func:`snoworm.steady.max_grade_deg`, continuous), the
steepest grid grade where the chain rolls, and for each inchworm gait the steepest grid grade where
it moved the chain, each with the electrical energy per metre climbed at that grade (the cell's
energy per metre along the track divided by ``sin(grade)``).  Pure bookkeeping on the map's rows.
"""

from __future__ import annotations

import math

__all__ = ["gradeability", "grade_text"]


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
        ``xt``; ``rolling_max_grade_deg`` (steady limit of a rolling chain, None below -40 deg);
        ``rolling_grid_deg`` and ``rolling_J_per_m_climbed``; ``inching``: ``{gait label:
        {"grid_deg": [...], "J_per_m_climbed": [...]}}`` (None: no grid grade moved the chain, or the
        cell was not simulated; energy None on a level or downhill grade).
    """
    gaits = result.get("gait_labels") or ["inching"]
    out = {
        "xt": [],
        "rolling_max_grade_deg": [],
        "rolling_grid_deg": [],
        "rolling_J_per_m_climbed": [],
        "inching": {g: {"grid_deg": [], "J_per_m_climbed": []} for g in gaits},
    }
    for x in result["xts"]:
        cells = sorted(
            (r for r in result["rows"] if r["xt"] == x and r["tow_N"] == tow_N), key=lambda r: r["grade_deg"]
        )
        out["xt"].append(x)
        out["rolling_max_grade_deg"].append(result["rolling_max_grade_deg"][tow_N][x])
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
        failed = [r for r in res["rows"] if r["tow_N"] == f and r.get("inching_note", "").startswith("solver")]
        if failed:
            lines.append(f"  inching run failed (solver) at {len(failed)} cells; see inching_note")
    if inching and not every_cell:
        lines.append(
            "inching simulated only where the chain does not roll, bisected over the grades (--every-cell: all)"
        )
    return "\n".join(lines)
