"""snoworm.config.yamlio: hostile or broken YAML gives a short ScenarioError; ordinary YAML reads as safe_load."""

import codecs
import os
import time
from pathlib import Path

import pytest
import yaml
from hypothesis import given, settings, strategies as st

from snoworm.config import yamlio
from snoworm.config.schema import ScenarioError
from snoworm.config.yamlio import MAX_BYTES, MAX_DEPTH, load_yaml_text, quote, read_yaml
from tests.conftest import SCENARIOS

# Time bounds below are hang guards (pure-Python PyYAML on a slow CI machine), not benchmarks.
HANG_GUARD_S = 5.0


def load_error(text: str) -> str:
    """The ScenarioError message for ``text`` (fails if it loads)."""
    with pytest.raises(ScenarioError) as info:
        load_yaml_text(text, "in.yaml")
    return str(info.value)


def timed_error(text: str):
    """(message, seconds) of a text that must be rejected."""
    t0 = time.perf_counter()
    msg = load_error(text)
    return msg, time.perf_counter() - t0


def billion_laughs(levels=9, fan=9) -> str:
    """The classic alias bomb: level k holds ``fan`` aliases of level k-1 (fan**levels leaves)."""
    lines = ["a0: &a0 [" + ", ".join(['"lol"'] * fan) + "]"]
    lines += [f"a{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * fan) + "]" for k in range(1, levels + 1)]
    return "\n".join(lines) + "\n"


# --- quote -----------------------------------------------------------------------------------


def test_quote_short_values_are_plain_repr():
    assert quote("abc") == "'abc'"
    assert quote(3.5) == "3.5"
    assert quote([1, 2]) == "[1, 2]"


def test_quote_cuts_long_string_and_gives_total_length():
    q = quote("x" * 2_000_000)
    assert q.startswith("'xxx") and q.endswith("... (2000000 characters)")
    assert len(q) < 130
    assert quote("y" * 500, limit=20) == "'" + "y" * 19 + "... (500 characters)"
    assert quote(b"\0" * 300).endswith("... (300 bytes)")


def test_quote_bounds_containers_and_huge_ints():
    assert len(quote(list(range(10**6)))) < 130
    assert len(quote({"k": "v" * 10**6})) < 130
    assert len(quote(16**10**5)) < 130  # beyond Python's int-to-str digit limit: no ValueError


# --- ordinary input behaves as yaml.safe_load ------------------------------------------------

ORDINARY = [
    "a: 1\nb: 2.5\nc: text\nd: [1, 2, 3]\ne: {x: true, y: null}\n",
    "rtol: 1e-5\natol: 1.0e-5\nhex: 0x1F\nsexagesimal: 1:30\nday: 2001-12-14\nflag: yes\n",
    "base: &b {x: 1, y: 2}\nderived:\n  <<: *b\n  x: 3\n",  # merge key, overriding is no duplicate
    "p: &p [0.0, 0.9]\nprofile: [*p, *p, [10.0, 0.3]]\n",  # aliases within the budget
    "=: 1\n'<<': literal key\n",
    "- !!binary aGVsbG8=\n- !!set {a, b}\n- !!str 12\n- !!float 3\n",
    "text: |\n  two\n  lines\nfolded: >\n  one\n  line\n",
    "\ufeffa: 1\n",  # a BOM at the start of the text
    "",
    "# only a comment\n",
    "~\n",
]


@pytest.mark.parametrize("text", ORDINARY)
def test_ordinary_input_matches_safe_load(text):
    assert load_yaml_text(text, "in.yaml") == yaml.safe_load(text)


def test_1e_5_stays_text_as_in_yaml_1_1():
    # YAML 1.1 floats need a dot: PyYAML reads 1e-5 as a string; the schema layer converts numeric text.
    assert load_yaml_text("a: 1e-5\nb: 1.0e-5\n", "in.yaml") == {"a": "1e-5", "b": 1e-5}


def test_shipped_scenarios_read_as_safe_load(scenario_path):
    path = scenario_path("traverse_patch")
    assert read_yaml(path) == yaml.safe_load(path.read_text(encoding="utf-8"))


scalars = st.integers(-(2**63), 2**63) | st.floats(allow_nan=False) | st.text(max_size=20) | st.booleans() | st.none()
documents = st.recursive(
    scalars,
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4),
    max_leaves=25,
)


@settings(max_examples=150, deadline=None)
@given(documents)
def test_safe_dump_round_trip_matches_safe_load(data):
    for dump in (yaml.safe_dump(data), yaml.safe_dump(data, default_flow_style=True)):
        got, want = load_yaml_text(dump, "dump.yaml"), yaml.safe_load(dump)
        assert got == want
        assert repr(got) == repr(want)  # same types too (True vs 1, 1.0 vs 1)


@settings(max_examples=300, deadline=None)
@given(st.text(alphabet="ab1.: -?[]{},&*!|>'\"%#\n\t\\", max_size=40))
def test_arbitrary_text_loads_or_gives_scenario_error(text):
    try:
        load_yaml_text(text, "fuzz.yaml")
    except ScenarioError as exc:
        assert str(exc).startswith("fuzz.yaml")


# --- tags, duplicate keys ----------------------------------------------------------------------


@pytest.mark.parametrize(
    "text, tag",
    [
        ("a: !!python/object/apply:os.system ['echo pwned']\n", "python/object/apply:os.system"),
        ("!!python/object:collections.OrderedDict {}\n", "python/object:collections.OrderedDict"),
        ("a: !!python/name:os.system\n", "python/name:os.system"),
        ("a: !custom 3\n", "!custom"),
        ("%TAG !p! tag:yaml.org,2002:python/\n---\na: !p!object:os.system {}\n", "python/object:os.system"),
    ],
)
def test_unknown_tags_are_refused_and_named(text, tag):
    msg = load_error(text)
    assert "unknown tag" in msg and tag in msg and "line " in msg


@pytest.mark.parametrize(
    "text, key, line",
    [
        ("a: 1\nb: 2\na: 3\n", "'a'", 3),
        ("tow:\n  force_N: 0\nmode:\n  type: uniform\n  speed: 1\n  type: supervisor\n", "'type'", 6),
        ("outer: [{x: 1, x: 2}]\n", "'x'", 1),
        ("1: one\ntrue: also one\n", "True", 2),  # 1 == True: PyYAML would keep one entry
        ("d:\n  <<: {x: 1, x: 2}\n", "'x'", 2),
    ],
)
def test_duplicate_keys_are_refused_with_key_and_line(text, key, line):
    msg = load_error(text)
    assert f"duplicate key {key}" in msg and f"line {line}," in msg
    assert yaml.safe_load(text) is not None  # safe_load would silently keep the last value


# --- alias bombs, recursion, depth -------------------------------------------------------------


def test_billion_laughs_is_refused_fast():
    text = billion_laughs()  # 9**9 = 387 420 489 leaves once expanded; about 300 bytes of text
    msg, seconds = timed_error(text)
    assert "alias bomb" in msg and "line " in msg
    assert seconds < HANG_GUARD_S  # hang guard, not a benchmark (measured ~0.01 s)


def test_merge_key_bomb_is_refused_fast():
    lines = ["m0: &m0 {" + ", ".join(f"k{j}: {j}" for j in range(9)) + "}"]
    lines += [f"m{k}: &m{k} {{<<: [" + ", ".join([f"*m{k - 1}"] * 9) + "]}" for k in range(1, 10)]
    msg, seconds = timed_error("\n".join(lines))
    assert "alias bomb" in msg
    assert seconds < HANG_GUARD_S  # hang guard, not a benchmark


def test_aliases_within_the_budget_are_fine():
    text = billion_laughs(levels=4, fan=9)  # 9**4 = 6561 leaves, under MAX_NODES
    assert load_yaml_text(text, "in.yaml") == yaml.safe_load(text)


def test_node_budget_counts_plain_nodes_too(monkeypatch):
    monkeypatch.setattr(yamlio, "MAX_NODES", 1000)  # the real 100 000 takes ~3 s of pure-Python parsing
    assert load_yaml_text("[" + ",".join(["1"] * 998) + "]", "in.yaml") == [1] * 998
    plain = load_error("[" + ",".join(["1"] * 1000) + "]")
    assert "too long for a list written inline" in plain and "alias" not in plain  # no alias in it
    assert "too many aliases / nodes" in load_error(billion_laughs(levels=3, fan=10))  # 1111 expanded nodes


def test_a_100000_point_elevation_table_points_to_route_files_not_to_an_alias_bomb(tmp_path):
    """Issue 30: a long inline elevation table was called 'a YAML alias bomb?'."""
    from click.testing import CliRunner

    from snoworm.cli import main

    raw = yaml.safe_load((SCENARIOS / "tow6_uniform.yaml").read_text())
    raw["terrain"]["elevation"] = [[float(i), 0.0] for i in range(100_000)]
    (tmp_path / "long.yaml").write_text(yaml.safe_dump(raw, default_flow_style=True))
    r = CliRunner().invoke(main, ["validate", str(tmp_path / "long.yaml")])
    assert r.exit_code == 2 and "alias" not in r.output, r.output
    assert "too long for a list written inline" in r.output and "terrain.route" in r.output


@pytest.mark.parametrize("text", ["&a [*a]\n", "x: &a {y: [1, *a]}\n"])
def test_recursive_alias_is_refused(text):
    assert "recursive alias" in load_error(text)


@pytest.mark.parametrize("n", [5000, 100_000])
def test_deeply_nested_brackets_give_depth_error_not_recursion_error(n):
    msg, seconds = timed_error("[" * n + "]" * n)
    assert f"more than {MAX_DEPTH} levels" in msg and "line 1, column" in msg
    assert seconds < HANG_GUARD_S  # hang guard, not a benchmark (measured ~0.005 s)


def test_depth_limit_is_exact_for_flow_and_block():
    deepest = "[" * MAX_DEPTH + "]" * MAX_DEPTH
    assert load_yaml_text(deepest, "in.yaml") == yaml.safe_load(deepest)
    assert "levels deep" in load_error("[" * (MAX_DEPTH + 1) + "]" * (MAX_DEPTH + 1))
    block = "\n".join(" " * (2 * i) + f"k{i}:" for i in range(MAX_DEPTH + 1)) + " 1\n"
    assert "levels deep" in load_error(block)


def test_depth_through_aliases_counts():
    inner = "[" * 30 + "1" + "]" * 30
    text = f"a: &a {inner}\nb: " + "[" * 30 + "*a" + "]" * 30 + "\n"  # 60 levels once expanded
    assert "levels deep" in load_error(text)


def test_recursion_error_becomes_depth_message(monkeypatch):
    # with the composer's own guard lifted, PyYAML's recursive composer hits Python's recursion limit
    monkeypatch.setattr(yamlio, "MAX_DEPTH", 10**9)
    assert "levels deep" in load_error("[" * 5000 + "]" * 5000)


# --- syntax and value errors -------------------------------------------------------------------


@pytest.mark.parametrize(
    "text, line, column",
    [
        ("a: 1\n b: 2\n", 2, 3),
        ("a: [1, 2\nb: 3\n", 2, 2),
        ("a:\n\tb: 1\n", 2, 1),
        ("a: 'unterminated\n", 2, 1),
        ("a: 1\n---\nb: 2\n", 2, 1),
    ],
)
def test_syntax_errors_give_line_column_and_hint(text, line, column):
    msg = load_error(text)
    assert msg.startswith(f"in.yaml, line {line}, column {column}: not valid YAML")
    assert "Fix the syntax (indentation, colons, quotes)" in msg


def test_control_character_is_refused_with_line():
    assert load_error("a: 1\nb: \x01\n").startswith("in.yaml, line 2: character #x0001")


@pytest.mark.parametrize(
    "text",
    [
        "a: !!timestamp 2020-13-45\n",
        "a: !!timestamp soon\n",
        "a: !!int abc\n",
        "a: !!float abc\n",
        "a: !!int ''\n",
        "a: !!bool maybe\n",
        "a: !!binary é\n",
        "a: !!omap [a]\n",
        "? [a, b]\n: 1\n",
        "<<: 5\n",
    ],
)
def test_values_a_tag_cannot_read_give_scenario_error(text):
    # PyYAML itself raises ValueError, KeyError, IndexError or AttributeError for several of these
    msg = load_error(text)
    assert msg.startswith("in.yaml, line 1") and "NoneType" not in msg and "Traceback" not in msg


STANDARD_TAGS = [
    "!!bool",
    "!!null",
    "!!int",
    "!!float",
    "!!binary",
    "!!timestamp",
    "!!omap",
    "!!pairs",
    "!!set",
    "!!str",
    "!!seq",
    "!!map",
    "!!merge",
    "!!value",
]


@settings(max_examples=300, deadline=None)
@given(st.sampled_from(STANDARD_TAGS), st.text(alphabet="ab01.:-+_eEoxT ~[]{},'\"", max_size=20))
def test_standard_tags_with_any_value_load_or_give_scenario_error(tag, value):
    try:
        load_yaml_text(f"k: {tag} {value}\n", "tags.yaml")
    except ScenarioError as exc:
        assert str(exc).startswith("tags.yaml")


def test_absurdly_long_integers_are_refused_fast():
    # a 400 kB sexagesimal int (1:1:1:...) takes safe_load over 15 s of quadratic big-int arithmetic
    msg, seconds = timed_error("a: 1" + ":1" * 200_000)
    assert "too long" in msg and len(msg) < 300
    assert seconds < HANG_GUARD_S  # hang guard, not a benchmark
    assert "too long" in load_error("a: " + "9" * 5000)


BIG = "v" * 2_000_000


@pytest.mark.parametrize(
    "text",
    [
        f"? {BIG}\n: 1\n? {BIG}\n: 2\n",  # duplicate key
        f"a: *{BIG}\n",  # undefined alias: PyYAML's own message echoes the name
        f"a: !{BIG}!x 1\n",  # undefined tag handle
        f"a: !!python/object:{BIG} {{}}\n",  # unknown tag
        f"a: !!int {BIG}\n",  # value the tag cannot read
        f"a: !!timestamp {BIG}\n",
    ],
)
def test_messages_quote_at_most_about_100_characters(text):
    msg = load_error(text)
    assert len(msg) < 400, msg[:500]
    assert "v" * 130 not in msg


def test_oversized_text_is_refused_before_parsing():
    assert "allowed" in load_error("x" * (MAX_BYTES + 1))


# --- files -------------------------------------------------------------------------------------


def test_read_yaml_reads_utf8_with_and_without_bom(tmp_path):
    text = "name: Frosty Böy\nterrain: {xt: 0.9}\n"
    plain, bom = tmp_path / "plain.yaml", tmp_path / "bom.yaml"
    plain.write_bytes(text.encode("utf-8"))
    bom.write_bytes(codecs.BOM_UTF8 + text.encode("utf-8"))
    assert read_yaml(plain) == read_yaml(str(bom)) == {"name": "Frosty Böy", "terrain": {"xt": 0.9}}


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le", "utf-16-be", "utf-32"])
def test_read_yaml_refuses_utf16_and_utf32(tmp_path, encoding):
    path = tmp_path / "wide.yaml"
    path.write_bytes("a: 1\n".encode(encoding))  # "utf-16" and "utf-32" write a byte-order mark
    with pytest.raises(ScenarioError, match="save it as UTF-8") as info:
        read_yaml(path)
    assert str(info.value).startswith(str(path))


def test_read_yaml_refuses_latin1_with_line(tmp_path):
    path = tmp_path / "latin1.yaml"
    path.write_bytes("name: x\nsnow: neigé\n".encode("latin-1"))
    with pytest.raises(ScenarioError, match="save it as UTF-8") as info:
        read_yaml(path)
    assert str(info.value).startswith(f"{path}, line 2: byte 0xe9 is not valid UTF-8")


def test_read_yaml_missing_file_and_directory(tmp_path):
    with pytest.raises(ScenarioError, match=r"no such file\. Check the path"):
        read_yaml(tmp_path / "missing.yaml")
    with pytest.raises(ScenarioError, match=r"not a regular file \(a FIFO, a device or a folder\)"):
        read_yaml(tmp_path)


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root can read any file")
def test_read_yaml_unreadable_file(tmp_path):
    path = tmp_path / "secret.yaml"
    path.write_text("a: 1\n", encoding="utf-8")
    path.chmod(0)
    with pytest.raises(ScenarioError, match=r"cannot read the file \(Permission denied\)"):
        read_yaml(path)


@pytest.mark.parametrize("content", [b"", b"\n  \n", codecs.BOM_UTF8, b"# just a comment\n"])
def test_read_yaml_empty_file(tmp_path, content):
    path = tmp_path / "empty.yaml"
    path.write_bytes(content)
    with pytest.raises(ScenarioError, match="the file is empty"):
        read_yaml(path)


def test_read_yaml_refuses_oversized_file(tmp_path):
    path = tmp_path / "huge.yaml"
    path.write_bytes(b"#" * (MAX_BYTES + 1))
    with pytest.raises(ScenarioError, match="larger than"):
        read_yaml(path)


def test_read_yaml_errors_name_the_file(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("a: 1\na: 2\n", encoding="utf-8")
    with pytest.raises(ScenarioError) as info:
        read_yaml(path)
    assert str(info.value).startswith(f"{path}, line 2, column 1: duplicate key 'a'")


def test_controller_paths_from_cwd(tmp_path, monkeypatch):
    from snoworm.config.yamlio import controller_paths_from_cwd

    monkeypatch.chdir(tmp_path)
    ov = controller_paths_from_cwd(
        [
            ("mode.controller", "ctl.py:C"),
            ("mode.controller", "pkg.mod:C"),
            ("mode", {"type": "controller", "controller": "sub/c.py:D"}),
            ("tow.force_N", "x.py:C"),
        ]
    )
    assert ov == [
        ("mode.controller", f"{tmp_path / 'ctl.py'}:C"),
        ("mode.controller", "pkg.mod:C"),
        ("mode", {"type": "controller", "controller": f"{tmp_path / 'sub' / 'c.py'}:D"}),
        ("tow.force_N", "x.py:C"),
    ]


def test_set_controller_on_a_shipped_scenario_is_taken_from_the_working_directory(tmp_path, monkeypatch):
    """`snoworm run tow6_uniform --set mode=...controller: ctl.py:Go` finds ./ctl.py (not one in the
    installed package); a scenario file of the user's keeps its own folder as the base."""
    from snoworm import load_scenario

    (tmp_path / "ctl.py").write_text(
        "class Go:\n    def __init__(self, params, scenario):\n        self.n = "
        "scenario.vehicle.segments\n    def __call__(self, obs):\n        return "
        "{'wheel_speed_mps': [1.0] * self.n}\n"
    )
    monkeypatch.chdir(tmp_path)
    sc = load_scenario("tow6_uniform", ["mode={type: controller, controller: 'ctl.py:Go', period_s: 0.1}"])
    assert sc.mode.controller == f"{tmp_path / 'ctl.py'}:Go"
    own = tmp_path / "mine"
    own.mkdir()
    (own / "ctl.py").write_text((tmp_path / "ctl.py").read_text())
    from snoworm.config.scenario import scenario_path

    (own / "s.yaml").write_text(Path(scenario_path("tow6_uniform")).read_text())
    sc = load_scenario(own / "s.yaml", ["mode={type: controller, controller: 'ctl.py:Go', period_s: 0.1}"])
    assert sc.mode.controller == f"{own / 'ctl.py'}:Go"  # the user's file: its own folder


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
def test_a_fifo_scenario_is_refused_at_once(tmp_path):
    """`mkfifo s.yaml; snoworm validate s.yaml` blocked forever before (found by the trust battery)."""
    p = tmp_path / "s.yaml"
    os.mkfifo(p)
    with pytest.raises(ScenarioError, match=r"s\.yaml: not a regular file \(a FIFO, a device or a folder\)"):
        read_yaml(p)
