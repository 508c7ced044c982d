# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
# ---

# %% [markdown]
# # snoworm from Python: scenario -> run -> DataFrame -> figure -> sweep
#
# A percent-format script: run it as `python docs/tutorial.py`, or open it as a notebook with
# jupytext (`jupytext --to notebook docs/tutorial.py`; each `# %%` line starts a cell).  It needs
# the data extra: `pip install 'snoworm[data]'` (pandas, xarray).
#
# Nothing here changes the matplotlib backend.  A figure drawn without your own `ax`/`fig` comes
# from pyplot's figure manager, so it shows inline in a notebook (and with `plt.show()` in a
# script); one drawn on your axes is yours.  `size="column"` (3.5 in) or `"page"` (7.16 in)
# draws it at print size, every text at least 7 pt.

# %%
import tempfile
from importlib.resources import files
from pathlib import Path

from matplotlib.figure import Figure

import snoworm
from snoworm import plotting

# %% [markdown]
# ## 1. Load a scenario and change a value
# The shipped scenarios come with the package.  `with_` returns a new, validated scenario: a
# bad value raises `ScenarioError` naming the key, exactly like a scenario file would.

# %%
path = files("snoworm") / "scenarios" / "tow6_uniform.yaml"
base = snoworm.load_scenario(path)
sc = base.with_({"tow.force_N": 150.0, "simulation.duration_s": 4.0})
print(sc.name, "-", sc.vehicle.segments, "segments, tow", sc.tow.force_N, "N, X_t", sc.terrain.xt)

# %% [markdown]
# ## 2. Run it and get a table
# `to_pandas()` returns one DataFrame: a row per output time, columns `(kind, quantity, index)`
# (`df["segment", "v_mps"]` is time x segment).  The tidy tables of the CSV files are a call
# away: `segments_frame()` (a row per time and segment) and `links_frame()`.

# %%
res = snoworm.simulate(sc)
print(repr(res))
df_run = res.to_pandas()
print(df_run["segment", "v_mps"].tail(3).round(3))
seg = res.segments_frame()
late = seg[seg["t_s"] >= seg["t_s"].max() - 1.0]
print(late.groupby("segment")[["v_mps", "slip", "net_force_N"]].mean().round(3))
print("units:", {k: seg.attrs["units"][k] for k in ("v_mps", "net_force_N", "slip")})

# %% [markdown]
# The same run as an xarray Dataset (dims time x segment and time x link), with units and the
# resolved scenario in its attributes; `ds.to_netcdf(...)` keeps all of it in one file.

# %%
ds = res.to_xarray()
print(ds["force_N"].attrs["units"], ds["force_N"].sel(link=0).isel(time=-1).item())
print(ds.attrs["scenario_yaml"].splitlines()[0], "| snoworm", ds.attrs["version_snoworm"])

# %% [markdown]
# ## 3. Plot
# `res.plot(kind)` draws one figure (forces, speeds, positions, slip, motor, energy, ...) and
# returns it; a cell ending with it shows it inline.

# %%
res.plot("forces", size="column")

# %% [markdown]
# A figure kept in a name shows as well (pyplot's inline backend shows every new figure at the
# end of its cell), in every cell, and so do your own pyplot figures: snoworm leaves pyplot's
# interactive mode, backend and rcParams as they were.

# %%
fig_speeds = res.plot("speeds", size="column")

# %%
fig_energy = res.plot("energy", size="column")

# %%
import matplotlib.pyplot as plt  # noqa: E402 - a cell of its own, as in a notebook

plt.figure(figsize=(3.5, 2.5), layout="constrained")
plt.plot(late["t_s"], late["v_mps"], ".", ms=3)
plt.xlabel("time [s]")
plt.ylabel("ground speed [m/s]")
plt.title("your own pyplot figure")

# %% [markdown]
# Several runs on one figure: `plotting.compare`.

# %%
stronger = snoworm.simulate(sc.with_({"tow.force_N": 300.0}))
plotting.compare([res, stronger], "speeds", labels=["tow 150 N", "tow 300 N"], size="column")

# %% [markdown]
# Every plotting function (and `Result.plot`) also takes your own `ax=` or `fig=`.

# %%
fig = Figure(figsize=(10, 4), layout="constrained")
ax_pos, ax_v = fig.subplots(1, 2)
res.plot("positions", ax=ax_pos)
for k, g in seg.groupby("segment"):
    ax_v.plot(g["t_s"], g["v_mps"], label=f"segment {k}", **plotting.series_style(k, len(g)))
ax_v.set_xlabel("time [s]")
ax_v.set_ylabel("ground speed [m/s]")
ax_v.legend(fontsize=7)
fig  # shown inline in a notebook

# %% [markdown]
# ## 4. Sweep and draw a heat map
# `run_sweep` takes the same `KEY=SPEC` axes as `snoworm sweep --set` (lists or
# `START:STOP:COUNT`); several axes form a grid.  The table comes back as a DataFrame.

# %%
out = Path(tempfile.mkdtemp(prefix="snoworm-tutorial-")) / "sweep"
table = snoworm.run_sweep(
    sc.with_({"simulation.duration_s": 3.0}),
    ["terrain.xt=0.6:1.0:3", "tow.force_N=0,200"],
    out_dir=out,
    plot=False,
    series="netcdf",
)
df = table.to_pandas()
grid = df.pivot(index="tow.force_N", columns="terrain.xt", values="mean_speed_mps")
print(grid.round(3))

fig2 = Figure(figsize=(6, 3.5), layout="constrained")
plotting.plot_sweep_heatmap(
    [f"{x:g}" for x in grid.columns],
    [f"{f:g}" for f in grid.index],
    grid.to_numpy(),
    "terrain.xt",
    "tow.force_N",
    "mean speed [m/s]",
    ax=fig2.subplots(),
)
fig2

# %% [markdown]
# The table draws its own standard figure too (a heat map for two keys on a grid).

# %%
table.plot(size="column")

# %% [markdown]
# ## 5. Load the sweep back
# `load_sweep` reads a sweep's folder (also one written by `snoworm sweep`); with
# `series="netcdf"` every case's time series is in one file, dims: swept keys x time x segment.

# %%
again = snoworm.load_sweep(out)
assert again.rows == table.rows
series = again.series()
v_end = series["v_mps"].isel(time=-1).mean("segment")
print(v_end.round(3).to_pandas())
assert int(series["ok"].sum()) == len(df)  # every case's series is there

# %% [markdown]
# To keep a figure: `plotting.save(fig2, "heatmap.pdf")` (png at 200 dpi, pdf with TrueType
# fonts, or svg with its text kept as text).
