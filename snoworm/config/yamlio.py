"""Hardened YAML reading for user scenario files.

:func:`read_yaml` and :func:`load_yaml_text` read YAML as :func:`yaml.safe_load` does, but hostile or broken
input (unknown tags, duplicate keys, alias bombs, deep nesting, huge or non-UTF-8 files) gives a short ScenarioError.
"""

from __future__ import annotations

import codecs
import os
from pathlib import Path

import yaml
from yaml.events import MappingStartEvent, SequenceStartEvent
from yaml.nodes import ScalarNode, SequenceNode

from ..infra.files import FileProblem, read_regular_file
from .schema import ScenarioError, quote

__all__ = [
    "MAX_BYTES",
    "MAX_DEPTH",
    "MAX_INT_CHARS",
    "MAX_NODES",
    "load_yaml_text",
    "quote",
    "read_yaml",
    "controller_paths_from_cwd",
]

MAX_NODES = 100_000  #: node budget after expanding aliases (scenario ~100, 30 000-point profile 90 000)
MAX_DEPTH = 50  #: deepest nesting of mappings and sequences, through aliases too (scenarios use 4)
MAX_BYTES = 4 * 2**20  #: largest input: bytes of a file, characters of a text (scenarios are ~1 kB)
MAX_INT_CHARS = 4300  #: longest int text: Python's decimal limit (sexagesimal 1:2:3... is quadratic)

_SYNTAX_HINT = "Fix the syntax (indentation, colons, quotes)."
_BOMB = f"more than {MAX_NODES} values after expanding aliases: too many aliases / nodes (a YAML alias bomb?)."
_LONG = (
    f"more than {MAX_NODES} values: too long for a list written inline (a table of tens of thousands of "
    "points?). Give a long elevation or X_t table as a route file: terrain.route: FILE.csv with the columns "
    "distance_m,elevation_m,xt (docs/model.md section 7)."
)
_DEEP = f"nested more than {MAX_DEPTH} levels deep (counting aliases); a scenario needs only a few levels."
_SKIP_KEY_TAGS = ("tag:yaml.org,2002:merge", "tag:yaml.org,2002:value")  # '<<' and '=' keys


def _clip(text, limit: int = 120) -> str:
    """PyYAML's or Python's own problem text, cut (it may echo a long alias, tag or value)."""
    return str(text) if len(str(text)) <= limit else f"{str(text)[:limit]}... ({len(str(text))} characters)"


def _error(source: str, mark, message: str) -> ScenarioError:
    """A ScenarioError naming the source and the line and column of ``mark``."""
    where = f", line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
    return ScenarioError(f"{source}{where}: {message}")


class _Loader(yaml.SafeLoader):
    """SafeLoader with size and depth guards while composing, and graph checks before constructing."""

    def __init__(self, text: str, source: str):
        super().__init__(text)
        self.source, self._depth, self._composed, self._memo = source, 0, 0, {}

    def compose_node(self, parent, index):
        """Compose one node, refusing more than MAX_NODES nodes or MAX_DEPTH nesting."""
        event = self.peek_event()
        nested = isinstance(event, (SequenceStartEvent, MappingStartEvent))
        self._composed, self._depth = self._composed + 1, self._depth + nested
        try:
            if self._composed > MAX_NODES or self._depth > MAX_DEPTH:
                # composing counts an alias once: past the budget here, the text itself is that long
                raise _error(self.source, event.start_mark, _LONG if self._composed > MAX_NODES else _DEEP)
            return super().compose_node(parent, index)
        finally:
            self._depth -= nested

    def fetch_flow_collection_start(self, token_class):
        """Refuse '[' or '{' beyond MAX_DEPTH in the scanner already (it reads ~1 kB ahead, slowly)."""
        if self.flow_level >= MAX_DEPTH:
            raise _error(self.source, self.get_mark(), _DEEP)
        super().fetch_flow_collection_start(token_class)

    def walk(self, node, level: int = 0):
        """(expanded size, nesting height) of ``node`` inside ``level`` collections; checks it.

        Aliases share nodes (and constructed objects: the blow-up would hit whoever walks the data later),
        so sizes are memoised per node and the walk stops once one passes MAX_NODES, before constructing.
        """
        if isinstance(node, ScalarNode):
            return 1, 0
        key = id(node)
        if key in self._memo and self._memo[key] is None:  # met again while walking its own children
            raise _error(
                self.source,
                node.start_mark,
                "recursive alias: this node contains an alias to "
                "itself. Recursive structures are not allowed; remove the alias.",
            )
        if key not in self._memo:
            if level >= MAX_DEPTH:
                raise _error(self.source, node.start_mark, _DEEP)
            self._memo[key] = None
            children = node.value if isinstance(node, SequenceNode) else self._checked_pairs(node)
            count, height = 1, 0
            for child in children:
                n, h = self.walk(child, level + 1)
                count, height = count + n, max(height, h)
                if count > MAX_NODES:
                    raise _error(self.source, child.start_mark, _BOMB)
            self._memo[key] = (count, height + 1)
        if level + self._memo[key][1] > MAX_DEPTH:
            raise _error(self.source, node.start_mark, _DEEP)
        return self._memo[key]

    def _checked_pairs(self, node) -> list:
        """The key and value nodes of a mapping, refusing a key given twice (PyYAML keeps the last)."""
        seen = {}
        for key_node, _ in node.value:
            if not isinstance(key_node, ScalarNode) or key_node.tag in _SKIP_KEY_TAGS:
                continue  # merged keys may be overridden; complex keys fail when constructed
            key = self.construct_object(key_node)  # scalars construct to hashable values
            first = seen.setdefault(key, key_node)
            if first is not key_node:
                raise _error(
                    self.source,
                    key_node.start_mark,
                    f"duplicate key {quote(key)} (first at line "
                    f"{first.start_mark.line + 1}); YAML would silently keep only the last. "
                    "Remove or rename one.",
                )
        return [n for pair in node.value for n in pair]

    def construct_object(self, node, deep=False):
        """Construct a node; a value its tag cannot read, or an absurdly long int, is a ScenarioError."""
        if node.tag == "tag:yaml.org,2002:int" and len(node.value) > MAX_INT_CHARS:
            raise _error(
                self.source,
                node.start_mark,
                f"integer {quote(node.value)} is too long (more than {MAX_INT_CHARS} characters).",
            )
        try:
            return super().construct_object(node, deep=deep)
        except ScenarioError:
            raise
        except (ValueError, TypeError, AttributeError, LookupError, OverflowError) as exc:  # !!bool x, !!int ''
            what = quote(node.value) if isinstance(node, ScalarNode) else "this value"
            why = f" ({_clip(exc)})" if isinstance(exc, ValueError) else ""
            raise _error(self.source, node.start_mark, f"cannot read {what} as {quote(node.tag)}{why}.") from None

    def construct_unknown(self, node):
        """Refuse any tag SafeLoader does not know (``!!python/object``, custom ``!tags``)."""
        raise _error(
            self.source,
            node.start_mark,
            f"unknown tag {quote(node.tag)}: tags that create "
            "Python objects or custom types are not allowed. Remove the tag.",
        )


_Loader.add_constructor(None, _Loader.construct_unknown)


def _load(text: str, source: str):
    """``(True, data)``, or ``(False, None)`` when ``text`` holds no YAML document."""
    if len(text) > MAX_BYTES:
        raise ScenarioError(f"{source}: {len(text)} characters, over the {MAX_BYTES} allowed (a scenario is a few kB).")
    try:
        loader = _Loader(text, source)
        node = loader.get_single_node()
        if node is None:
            return False, None
        loader.walk(node)
        return True, loader.construct_document(node)
    except yaml.MarkedYAMLError as exc:
        at = f" at line {exc.context_mark.line + 1}" if exc.context_mark else ""
        context = f" ({_clip(exc.context)}{at})" if exc.context else ""
        raise _error(
            source,
            exc.problem_mark or exc.context_mark,
            f"not valid YAML: {_clip(exc.problem)}{context}. {_SYNTAX_HINT}",
        ) from None
    except yaml.reader.ReaderError as exc:
        line = text.count("\n", 0, exc.position) + 1
        raise ScenarioError(
            f"{source}, line {line}: character #x{exc.character:04x} is not allowed in YAML "
            "(write control characters as escapes in double quotes). Remove it."
        ) from None
    except yaml.YAMLError as exc:
        raise ScenarioError(f"{source}: not valid YAML: {_clip(exc)}. {_SYNTAX_HINT}") from None
    except RecursionError:
        raise ScenarioError(f"{source}: {_DEEP}") from None


def load_yaml_text(text: str, source: str):
    """Parse YAML text like :func:`yaml.safe_load`, with the guards of this module.

    Parameters
    ----------
    text : str
        YAML text.
    source : str
        Name of the text (a path, ``--set key``) that starts each error message.

    Returns
    -------
    object
        What :func:`yaml.safe_load` returns for ordinary input (None for an empty text).

    Raises
    ------
    ScenarioError
        Syntax errors, unknown tags, duplicate keys, recursive aliases, more than :data:`MAX_NODES`
        nodes after expanding aliases, nesting beyond :data:`MAX_DEPTH`, text beyond :data:`MAX_BYTES`.
    """
    return _load(text, source)[1]


def read_yaml(path):
    """Read and parse a UTF-8 YAML file (a byte-order mark is allowed) safely.

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    object
        The parsed data, as :func:`load_yaml_text`.

    Raises
    ------
    ScenarioError
        A missing, unreadable, empty (blank or comments only), oversized or non-UTF-8 file, or any
        error of :func:`load_yaml_text`; the message starts with the path.
    """
    name = os.fsdecode(path)
    try:
        data = read_regular_file(name, MAX_BYTES)
    except FileNotFoundError:
        raise ScenarioError(f"{name}: no such file. Check the path.") from None
    except OSError as exc:
        raise ScenarioError(f"{name}: cannot read the file ({exc.strerror or exc}).") from None
    except FileProblem as exc:
        if exc.too_large:
            raise ScenarioError(
                f"{name}: larger than {MAX_BYTES} bytes (a scenario is a few kB); wrong file?"
            ) from None
        raise ScenarioError(f"{name}: {exc}; give a YAML file saved on disk.") from None
    if data[:2] in (codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE) or b"\0" in data:  # UTF-32 BOMs are caught too
        raise ScenarioError(
            f"{name}: the file is not UTF-8 text (a UTF-16 or UTF-32 byte-order mark or NUL "
            "bytes: UTF-16, UTF-32 or a binary file); save it as UTF-8."
        )
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise ScenarioError(
            f"{name}, line {line}: byte {data[exc.start]:#04x} is not valid UTF-8 (Latin-1, "
            "Windows-1252 or another encoding?); save it as UTF-8."
        ) from None
    found, value = _load(text, name)
    if not found:
        raise ScenarioError(f"{name}: the file is empty (no YAML content, only blanks or comments).")
    return value


def _cwd_spec(value):
    target, sep, name = value.rpartition(":")
    if sep and (target.endswith(".py") or "/" in target or "\\" in target) and not Path(target).is_absolute():
        return f"{Path.cwd() / target}:{name}"
    return value


def controller_paths_from_cwd(overrides) -> list:
    """``(key, value)`` overrides with a relative controller file (``mode.controller=ctl.py:Cls``,
    or ``controller`` inside a ``mode`` mapping) made absolute from the working directory: a path
    typed on a command line means the user's folder, not the folder of a shipped scenario file."""
    out = []
    for key, value in overrides:
        if key == "mode.controller" and isinstance(value, str):
            value = _cwd_spec(value)
        elif key == "mode" and isinstance(value, dict) and isinstance(value.get("controller"), str):
            value = {**value, "controller": _cwd_spec(value["controller"])}
        out.append((key, value))
    return out
