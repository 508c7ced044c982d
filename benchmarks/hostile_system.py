"""The hostile-input battery's cases on files, code and processes: netCDF, Gymnasium, code trust (benchmarks/hostile.py)."""

from __future__ import annotations

import os
import py_compile
import random
import shutil
import subprocess
import tempfile
import textwrap
import threading
from pathlib import Path

from hostile_core import PY, ROOT, Case, check_sweep, spawn
from hostile_processes import PROCESS_SURFACES

RR = ("refused",)
OK = ("ok",)
EITHER = ("ok", "refused")

# ------------------------------------------------------------------------------------------ netCDF

SWEEP_NC = [
    "sweep",
    "tow6_uniform",
    "--set",
    "tow.force_N=0,100",
    "--set",
    "simulation.duration_s=0.5",
    "--no-plot",
    "--save-cases",
    "--series",
    "netcdf",
    "--out",
    "{out}",
]
_fixture_lock = threading.Lock()
_fixture: list = []


def _nc_fixture() -> Path:
    """A finished two-case sweep with series.nc, made once per battery run."""
    with _fixture_lock:
        if not _fixture:
            d = Path(tempfile.mkdtemp(prefix="snoworm-hostile-fixture-"))
            argv = [PY, "-m", "snoworm", *[a.format(out=d / "sweep") for a in SWEEP_NC]]
            subprocess.run(argv, cwd=d, env={**os.environ, "PYTHONPATH": str(ROOT)}, check=True, capture_output=True)
            _fixture.append(d / "sweep")
        return _fixture[0]


def _nc_setup(tamper):
    def setup(ctx):
        src = _nc_fixture()
        shutil.copytree(src, ctx.out)
        shutil.copytree(src, ctx.base / "pristine")
        tamper(ctx, ctx.out / "series.nc")

    return setup


def _truncate(n):
    def t(ctx, p):
        size = p.stat().st_size
        keep = n if n >= 0 else size + n
        if isinstance(n, float):
            keep = int(size * n)
        with open(p, "r+b") as f:
            f.truncate(keep)

    return t


def _flip(seed):
    def t(ctx, p):
        data = bytearray(p.read_bytes())
        rng = random.Random(seed)
        for _ in range(8):
            k = rng.randrange(len(data))
            data[k] ^= 0xFF
        p.write_bytes(bytes(data))

    return t


def _replace(kind):
    def t(ctx, p):
        p.unlink()
        if kind == "fifo":
            os.mkfifo(p)
        elif kind == "dir":
            p.mkdir()
        elif kind == "devzero":
            os.symlink("/dev/zero", p)
        elif kind == "victim":
            os.symlink(ctx.victim, p)
        elif kind == "empty":
            p.write_bytes(b"")
        elif kind == "text":
            p.write_text("not a netCDF file\n")
        elif kind == "loop":
            os.symlink(p, p)
        elif kind == "huge_dims":
            import h5py
            import numpy as np

            with h5py.File(p, "w") as f:
                f.create_dataset("time", shape=(10**12,), dtype="f8", chunks=(1024,))
                f.create_dataset("x_m", shape=(2, 10**12, 6), dtype="f8", chunks=(1, 1024, 6))
                f.attrs["snoworm"] = np.bytes_(b"x")
        elif kind == "other_sweep":
            subprocess.run(
                [
                    PY,
                    "-m",
                    "snoworm",
                    "sweep",
                    "tow6_uniform",
                    "--set",
                    "tow.force_N=0,50,100",
                    "--set",
                    "simulation.duration_s=0.3",
                    "--no-plot",
                    "--save-cases",
                    "--series",
                    "netcdf",
                    "--out",
                    str(ctx.base / "other"),
                ],
                cwd=ctx.base,
                env={**os.environ, "PYTHONPATH": str(ROOT)},
                check=True,
                capture_output=True,
            )
            shutil.copy(ctx.base / "other" / "series.nc", p)

    return t


READ_BODY = textwrap.dedent("""\
    import numpy as np, snoworm
    ds = snoworm.load_sweep('{out}').series()
    ref = snoworm.load_sweep('{base}/pristine').series()
    for name in ref.data_vars:
        a, b = np.asarray(ds[name]), np.asarray(ref[name])
        if a.shape != b.shape or not np.array_equal(a, b, equal_nan=True):
            nonsense(f'series() read a tampered file without complaint: {name} differs')
    """)


def netcdf():
    tampers = {f"truncate_{n}": _truncate(n) for n in (0, 8, 64, 512, 4096, 0.5, -1)}
    tampers.update({f"flip_{s}": _flip(s) for s in range(12)})
    tampers.update(
        {
            k: _replace(k)
            for k in ("fifo", "dir", "devzero", "victim", "empty", "text", "loop", "huge_dims", "other_sweep")
        }
    )
    cases = []
    for name, t in tampers.items():
        setup = _nc_setup(t)
        # flipped bytes may land where nothing is read: then the values must equal the pristine file's
        e = EITHER if name.startswith("flip") else RR
        cases.append(Case("netcdf", f"series/{name}", code=READ_BODY, setup=setup, expect=e, timeout=60))
        cases.append(Case("netcdf", f"resume/{name}", SWEEP_NC, setup=setup, expect=EITHER, check=check_sweep))
    cases.append(Case("netcdf", "series/untouched", code=READ_BODY, setup=_nc_setup(lambda c, p: None), expect=OK))
    return cases


# -------------------------------------------------------------------------------------- Gymnasium

ENV_HEAD = "import numpy as np, gymnasium, pickle, copy\nfrom snoworm.env import SnowormEnv, SnowormVectorEnv\n"


def _gym(name, body, expect):
    return Case("gym", name, code=ENV_HEAD + textwrap.dedent(body), expect=expect, timeout=60)


def gym():
    cases = []
    actions = {
        "ok": ("np.full(6, 0.5, np.float32)", OK),
        "nan": ("np.full(6, np.nan)", RR),
        "inf": ("np.full(6, np.inf)", EITHER),
        "-inf": ("np.full(6, -np.inf)", EITHER),
        "complex": ("np.full(6, 0.5+0.5j)", RR),
        "short": ("np.zeros(5)", RR),
        "long": ("np.zeros(7)", RR),
        "2d": ("np.zeros((2, 6))", RR),
        "scalar": ("0.5", RR),
        "string": ("'fast'", RR),
        "strings": ("['a'] * 6", RR),
        "none": ("None", RR),
        "object": ("np.array([object()] * 6)", RR),
        "huge": ("np.full(6, 1e300)", EITHER),
        "bool": ("np.ones(6, bool)", EITHER),
        "int": ("np.ones(6, int)", EITHER),
        "list": ("[0.5] * 6", EITHER),
        "dict": ("{'a': 1}", RR),
        "float16_nan": ("np.full(6, np.nan, np.float16)", RR),
        "empty": ("np.zeros(0)", RR),
    }
    for name, (a, e) in actions.items():
        body = f"""\
            env = SnowormEnv(scenario='tow6_uniform', dt_s=0.1)
            env.reset(seed=0)
            obs, r, term, trunc, info = env.step({a})
            if not np.all(np.isfinite(obs)) or not np.isfinite(r): nonsense('non-finite observation or reward')
            """
        cases.append(_gym(f"action/{name}", body, e))
        vbody = f"""\
            env = SnowormVectorEnv(num_envs=3, scenario='tow6_uniform', dt_s=0.1)
            env.reset(seed=0)
            a = {a}
            a = np.stack([np.asarray(a)] * 3) if np.ndim(a) == 1 else a
            obs, r, term, trunc, info = env.step(a)
            if not np.all(np.isfinite(obs)) or not np.all(np.isfinite(r)): nonsense('non-finite observation or reward')
            """
        if name not in ("scalar", "string", "none", "dict", "strings", "object"):
            cases.append(_gym(f"vector_action/{name}", vbody, e))
    dts = {
        "0.1": OK,
        "0": RR,
        "-1": RR,
        "float('nan')": RR,
        "float('inf')": RR,
        "1e-9": RR,
        "1e6": EITHER,
        "'0.1'": RR,
        "True": RR,
        "1e-4": EITHER,
        "0.1+0j": RR,
        "None": RR,
        "np.float32(0.1)": EITHER,
    }
    for v, e in dts.items():
        body = f"""\
            env = SnowormEnv(scenario='tow6_uniform', dt_s={v})
            env.reset(seed=0)
            for _ in range(3):
                obs, r, term, trunc, info = env.step(np.full(6, 0.5, np.float32))
                if not np.all(np.isfinite(obs)): nonsense('non-finite observation')
                if term or trunc: break
            """
        cases.append(_gym(f"dt_s={v}", body, e))
    nums = {
        "2": OK,
        "0": RR,
        "-1": RR,
        "1.5": RR,
        "True": RR,
        "10**9": RR,
        "'2'": RR,
        "None": RR,
        "2**70": RR,
        "np.int64(2)": EITHER,
        "5000": RR,
    }
    for v, e in nums.items():
        body = f"""\
            env = SnowormVectorEnv(num_envs={v}, scenario='tow6_uniform', dt_s=0.1)
            env.reset(seed=0)
            obs, r, *_ = env.step(np.full((env.num_envs, 6), 0.5, np.float32))
            """
        cases.append(_gym(f"num_envs={v}", body, e))
    misc = {
        "pickle_mid_episode": (
            """\
            env = SnowormEnv(scenario='tow6_uniform', dt_s=0.1); env.reset(seed=0)
            a = np.full(6, 0.7, np.float32)
            env.step(a)
            twin = pickle.loads(pickle.dumps(env))
            o1 = env.step(a)[0]; o2 = twin.step(a)[0]
            if not np.array_equal(o1, o2): nonsense('a pickled copy steps to another observation')
            """,
            OK,
        ),
        "deepcopy_mid_episode": (
            """\
            env = SnowormEnv(scenario='tow6_uniform', dt_s=0.1); env.reset(seed=0)
            a = np.full(6, 0.7, np.float32)
            env.step(a)
            twin = copy.deepcopy(env)
            o1 = env.step(a)[0]; o2 = twin.step(a)[0]
            if not np.array_equal(o1, o2): nonsense('a deep copy steps to another observation')
            """,
            OK,
        ),
        "vector_pickle": (
            """\
            env = SnowormVectorEnv(num_envs=2, scenario='tow6_uniform', dt_s=0.1); env.reset(seed=0)
            a = np.full((2, 6), 0.7, np.float32)
            env.step(a)
            twin = pickle.loads(pickle.dumps(env))
            if not np.array_equal(env.step(a)[0], twin.step(a)[0]): nonsense('vector copy differs')
            """,
            OK,
        ),
        "gymnasium_make": (
            """\
            import snoworm.env
            env = gymnasium.make('snoworm/Snoworm-v0', scenario='tow6_uniform', dt_s=0.1)
            env.reset(seed=0); env.step(env.action_space.sample())
            """,
            OK,
        ),
        "make_vec": (
            """\
            import snoworm.env
            env = gymnasium.make_vec('snoworm/Snoworm-v0', num_envs=2, vectorization_mode='vector_entry_point')
            env.reset(seed=0); env.step(env.action_space.sample())
            """,
            OK,
        ),
        "step_before_reset": (
            """\
            env = SnowormEnv(scenario='tow6_uniform', dt_s=0.1)
            env.step(np.zeros(6))
            """,
            RR,
        ),
        "step_after_truncation": (
            """\
            env = SnowormEnv(scenario='tow6_uniform', dt_s=0.5)
            env.reset(seed=0)
            for _ in range(100):
                env.step(np.full(6, 0.5, np.float32))
            """,
            RR,
        ),
        "bad_scenario_name": ("SnowormEnv(scenario='no_such_scenario')", RR),
        "scenario_number": ("SnowormEnv(scenario=5)", RR),
        "scenario_path_dir": ("SnowormEnv(scenario='.')", RR),
        "action_keys_empty": ("SnowormEnv(action_keys=())", RR),
        "action_keys_unknown": ("SnowormEnv(action_keys=('warp',))", RR),
        "action_keys_string": ("SnowormEnv(action_keys='wheel_speed_mps')", EITHER),
        "action_keys_dup": ("SnowormEnv(action_keys=('wheel_speed_mps', 'wheel_speed_mps'))", RR),
        "joint_on_fixed": ("SnowormEnv(action_keys=('joint_force_N',))", RR),
        "energy_weight_nan": ("SnowormEnv(energy_weight=float('nan'))", RR),
        "stall_time_neg": ("SnowormEnv(stall_time_s=-1)", RR),
        "method_bad": ("SnowormEnv(method='Euler')", RR),
        "seed_string": ("env = SnowormEnv(); env.reset(seed='a')", RR),
        "seed_negative": ("env = SnowormEnv(); env.reset(seed=-1)", RR),
        "seed_huge": ("env = SnowormEnv(); env.reset(seed=2**70)", EITHER),
        "reset_options": ("env = SnowormEnv(); env.reset(options={'x': 1})", EITHER),
        "reward_not_callable": ("SnowormEnv(reward=5)", RR),
        "reward_returns_nan": (
            """\
            env = SnowormEnv(reward=lambda p, o, i: float('nan')); env.reset(seed=0)
            o, r, *_ = env.step(np.full(6, 0.5, np.float32))
            if not np.isnan(r): nonsense("the reward function's value was changed")
            """,
            OK,  # the user's reward function is theirs: its value (NaN too) and its exceptions reach the user
        ),
        "reward_raises": (
            """\
            env = SnowormEnv(reward=lambda p, o, i: 1 / 0); env.reset(seed=0)
            try:
                env.step(np.full(6, 0.5, np.float32))
                nonsense('the reward function raised and step() went on')
            except ZeroDivisionError:
                pass
            """,
            OK,
        ),
        "render_mode": ("SnowormEnv(render_mode='human')", RR),
    }
    for name, (body, e) in misc.items():
        cases.append(_gym(name, body, e))
    return cases


# -------------------------------------------------------------------------------------- code trust

CTL_SCENARIO = """\
name: ctl
vehicle: {{parameter_set: frostyboy, segments: 3, links: {{type: fixed}}}}
terrain: {{xt: 0.9}}
tow: {{force_N: 0}}
mode: {{type: controller, controller: "{ref}", period_s: 0.1, params: {{}}}}
simulation: {{duration_s: 0.5, output_dt_s: 0.05}}
"""
EVIL = "open({marker!r}, 'a').write('imported {where}\\n')\n"
CTL_CLASS = "class Ctl:\n    def __init__(self, params, scenario):\n        pass\n    def __call__(self, obs):\n        return {}\n"


def _evil(ctx, path: Path, where: str):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(EVIL.format(marker=str(ctx.marker), where=where) + CTL_CLASS)


def _trust_setup(ref, sc_dir="", ctl="ctl.py", evil=True, extra=None):
    def setup(ctx):
        d = ctx.cwd / sc_dir
        d.mkdir(parents=True, exist_ok=True)
        (d / "sc.yaml").write_text(CTL_SCENARIO.format(ref=ctx.fmt(ref)))
        if ctl:
            if evil:
                _evil(ctx, ctx.cwd / ctl, ctl)
            else:
                (ctx.cwd / ctl).write_text(CTL_CLASS)
        if extra:
            extra(ctx)

    return setup


def _pyc(ctx):
    """ctl.py benign; __pycache__/ctl.cpython-XY.pyc from an evil source of the same size and mtime."""
    benign = CTL_CLASS + "# " + "x" * 200 + "\n"
    evil = EVIL.format(marker=str(ctx.marker), where="pyc") + CTL_CLASS
    evil = evil + "#" + "y" * (len(benign) - len(evil) - 2) + "\n"
    assert len(evil) == len(benign)
    src = ctx.cwd / "ctl.py"
    src.write_text(evil)
    os.utime(src, ns=(1_600_000_000_000_000_000, 1_600_000_000_000_000_000))
    import importlib.util

    py_compile.compile(str(src), cfile=importlib.util.cache_from_source(str(src)), doraise=True)
    src.write_text(benign)
    os.utime(src, ns=(1_600_000_000_000_000_000, 1_600_000_000_000_000_000))


def _result_folder(ctx):
    """res/: a run of a benign ctl.py (in the working folder); then ctl.py turns evil."""
    (ctx.cwd / "ctl.py").write_text(CTL_CLASS)
    (ctx.cwd / "sc.yaml").write_text(CTL_SCENARIO.format(ref="ctl.py:Ctl"))
    r = spawn(ctx, [PY, "-m", "snoworm", "run", "sc.yaml", "--no-plot", "--out", str(ctx.cwd / "res")])
    assert r["rc"] == 0, r["stderr"]
    _evil(ctx, ctx.cwd / "ctl.py", "after")
    for p in (ctx.cwd / "res").rglob("*.py"):
        _evil(ctx, p, "copy")


def trust():
    run = ["run", "sc.yaml", "--no-plot", "--out", "{out}"]
    runsub = ["run", "sub/sc.yaml", "--no-plot", "--out", "{out}"]
    c = []

    def add(name, args=None, setup=None, expect=RR, may=False, env=None, code=None):
        c.append(
            Case(
                "trust", name, args, code=code, setup=setup, expect=expect, code_may_run=may, env=env or {}, check=None
            )
        )

    add("file_in_folder/run", run, _trust_setup("ctl.py:Ctl"), OK, may=True)
    add("file_in_folder/validate", ["validate", "sc.yaml"], _trust_setup("ctl.py:Ctl"), OK)
    add(
        "file_in_folder/load_scenario",
        None,
        _trust_setup("ctl.py:Ctl"),
        OK,
        code="import snoworm; snoworm.load_scenario('sc.yaml')",
    )
    add(
        "file_in_folder/sweep_plan_bad",
        ["sweep", "sc.yaml", "--set", "mode.period_s=0,-1", "--out", "{out}"],
        _trust_setup("ctl.py:Ctl"),
        EITHER,
    )
    add("module_in_folder/run", run, _trust_setup("ctl:Ctl"), EITHER, may=True)
    for tag, env in (("python_m", {}), ("pythonpath_dot", {"PYTHONPATH": f".{os.pathsep}{ROOT}"})):
        add(f"module_outside_tree/{tag}/run", runsub, _trust_setup("ctl:Ctl", "sub"), env=env)
        add(
            f"module_outside_tree/{tag}/validate",
            ["validate", "sub/sc.yaml"],
            _trust_setup("ctl:Ctl", "sub"),
            EITHER,
            env=env,
        )
        add(
            f"module_outside_tree/{tag}/sweep",
            ["sweep", "sub/sc.yaml", "--set", "tow.force_N=0,10", "--out", "{out}"],
            _trust_setup("ctl:Ctl", "sub"),
            env=env,
        )
    add(
        "module_outside_tree/python_c",
        None,
        _trust_setup("ctl:Ctl", "sub"),
        code="import sys; sys.path.insert(0, '.'); import snoworm\nsnoworm.simulate(snoworm.load_scenario('sub/sc.yaml'))",
    )
    add(
        "module_outside_tree/allowed",
        [*runsub, "--allow-code", "ctl.py"],
        _trust_setup("ctl:Ctl", "sub"),
        EITHER,
        may=True,
    )
    add(
        "package_init_outside_tree",
        runsub,
        _trust_setup(
            "pkg.mod:Ctl", "sub", ctl="pkg/mod.py", extra=lambda ctx: _evil(ctx, ctx.cwd / "pkg/__init__.py", "init")
        ),
    )
    add("file_outside_tree/run", runsub, _trust_setup("../ctl.py:Ctl", "sub"))
    add("file_outside_tree/validate", ["validate", "sub/sc.yaml"], _trust_setup("../ctl.py:Ctl", "sub"))
    add(
        "file_absolute_outside",
        run,
        _trust_setup("{base}/evil.py:Ctl", extra=lambda ctx: _evil(ctx, ctx.base / "evil.py", "abs")),
    )
    add(
        "file_symlink_outside",
        run,
        _trust_setup(
            "ln.py:Ctl",
            ctl=None,
            extra=lambda ctx: (
                _evil(ctx, ctx.base / "evil.py", "symlink"),
                os.symlink(ctx.base / "evil.py", ctx.cwd / "ln.py"),
            ),
        ),
    )
    add(
        "set_controller_outside",
        [*run, "--set", "mode.controller={base}/evil.py:Ctl"],
        _trust_setup("ctl.py:Ctl", evil=False, extra=lambda ctx: _evil(ctx, ctx.base / "evil.py", "set")),
    )
    add(
        "sweep_set_controller_outside",
        [
            "sweep",
            "sc.yaml",
            "--set",
            "mode.controller={base}/evil.py:Ctl",
            "--set",
            "tow.force_N=0,1",
            "--out",
            "{out}",
        ],
        _trust_setup("ctl.py:Ctl", evil=False, extra=lambda ctx: _evil(ctx, ctx.base / "evil.py", "set")),
    )
    add("allow_code_empty", [*runsub, "--allow-code", ""], _trust_setup("../ctl.py:Ctl", "sub"))
    add("allow_code_missing", [*runsub, "--allow-code", "nowhere"], _trust_setup("../ctl.py:Ctl", "sub"))
    add("allow_code_nul", [*runsub, "--allow-code", "a\udcff"], _trust_setup("../ctl.py:Ctl", "sub"))
    for ref in (
        "subprocess:Popen",
        "os:PathLike",
        "antigravity:Ctl",
        "this:Ctl",
        "snoworm.cli:main",
        "ctl:Popen",
        "ctl:",
        ":Ctl",
        "ctl.py:",
        "ctl.py:Ctl:Ctl",
        "ctl.py:1x",
        "ctl.txt:Ctl",
        "/dev/zero:Ctl",
        "ctl.py:__class__",
    ):

        def extra(ctx):
            (ctx.cwd / "ctl.txt").write_text(EVIL.format(marker=str(ctx.marker), where="txt") + CTL_CLASS)
            with open(ctx.cwd / "ctl.py", "a") as f:
                f.write("from subprocess import Popen\n")

        add(f"ref={ref}", ["validate", "sc.yaml"], _trust_setup(ref, extra=extra))
        add(f"ref={ref}/run", run, _trust_setup(ref, extra=extra), EITHER if ref == "snoworm.cli:main" else RR)
    add("pyc_file/run", run, _trust_setup("ctl.py:Ctl", ctl=None, extra=_pyc), OK)
    add("pyc_module/run", run, _trust_setup("ctl:Ctl", ctl=None, extra=_pyc), EITHER)
    add("read_back/load_result", None, _result_folder, OK, code="import snoworm; snoworm.load_result('res')")
    add(
        "read_back/simulate",
        None,
        _result_folder,
        RR,
        code="import snoworm; snoworm.simulate(snoworm.load_result('res').scenario)",
    )
    add(
        "read_back/run_yaml_elsewhere",
        ["run", "res/scenario.yaml", "--no-plot", "--out", "{out}"],
        _result_folder,
        EITHER,
        may=False,
    )
    return c


SYSTEM_SURFACES = {"netcdf": netcdf, "gym": gym, "trust": trust, **PROCESS_SURFACES}
