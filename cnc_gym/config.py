"""The configs' schema and reader: one declaration per key (type, range, unit, meaning), one way to check.

Every key of a machine, task or training config is a dataclass field declared with one of
:func:`number`, :func:`text`, :func:`choice`, :func:`flag`, :func:`items`, :func:`table` or
:func:`section`; the field's metadata holds its :class:`Spec` (type, allowed range, unit, meaning, and
why the range is what it is).
:func:`from_mapping` builds a dataclass from YAML data with those specs, :func:`check_object` checks one
built in Python, and :func:`markdown_table` writes the docs' key tables from the same specs (a test
keeps the docs equal to them). Adding a key is one field declaration.

Rules that tie several keys together live in the dataclass's ``config_problems()`` method, which yields
``(key, problem)`` pairs.

YAML is read by :func:`read_yaml` with PyYAML's safe loader (no tags that build Python objects), bounded:
at most :data:`MAX_CONFIG_BYTES` bytes, :data:`MAX_NESTING` levels and :data:`MAX_NODES` values after
alias expansion (a "billion laughs" file is refused before anything expands it), UTF-8 only, no
duplicate keys, no alias that contains itself. Numbers may be written ``1e-3`` as in YAML 1.2 (PyYAML,
a YAML 1.1 parser, would read that as a string). Every problem is one :class:`~cnc_gym.errors.
ConfigError` line that names the file and the key.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math
import numbers
import os
import re
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

from cnc_gym.errors import ConfigError
from cnc_gym.files import read_regular_file

if TYPE_CHECKING:  # PyYAML loads when a config is read (`cnc-gym trace` of a program without one never does)
    import yaml

#: Largest config file read (the shipped ones are 1-3 KB).
MAX_CONFIG_BYTES = 256 * 1024
#: Deepest nesting of mappings and lists (the schemas need 3).
MAX_NESTING = 32
#: Most values (scalars, lists, mappings) in a file, counting every use of an alias in full.
MAX_NODES = 20_000
#: Longest text value (a program path or a description).
MAX_TEXT = 4096


def configs_dir() -> Path:
    """The folder of machine presets, task and training configs (set ``CNC_GYM_CONFIGS`` to use another).

    The repository keeps them at its top (``configs/``); an installed wheel ships the same files as
    package data, ``cnc_gym/configs`` (setup.py maps the one to the other).
    """
    env = os.environ.get("CNC_GYM_CONFIGS")
    if env:
        return Path(env)
    package = Path(__file__).resolve().parent
    installed = package / "configs"
    return installed if installed.is_dir() else package.parent / "configs"


# ------------------------------------------------------------------------------------------- messages
def escaped(text: str, limit: int = 200) -> str:
    """``text`` safe for one terminal line: non-ASCII and control characters escaped, at most ``limit``
    characters (a config or model file cannot clear the screen or flood it through an error line)."""
    text = text.encode("ascii", "backslashreplace").decode("ascii")
    text = "".join(c if c.isprintable() else f"\\x{ord(c):02x}" for c in text)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def shown(value: Any, limit: int = 60) -> str:
    """``repr(value)`` for an error line, escaped and bounded as :func:`escaped`."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 10**30:
        return f"an integer of about {int(abs(value).bit_length() * 0.30103) + 1} digits"
    try:
        text = repr(value)
    except Exception:  # a user object whose repr fails still gets a clean line
        text = f"<{type(value).__name__}>"
    return escaped(text, limit)


def _place(source: str, path: str) -> str:
    """``source: path`` (either may be empty)."""
    return ": ".join(part for part in (source, path) if part)


class Invalid(Exception):
    """A value breaks its spec (message without file and key; :func:`from_mapping` adds them)."""


# ---------------------------------------------------------------------------------------------- specs
def _fmt(x: float) -> str:
    """A bound or default as people (and YAML) write it: ``0.002``, ``15000``, ``1e6``, ``1e-6``."""
    if isinstance(x, int):
        return str(x)
    if x.is_integer() and abs(x) < 1e5:
        return str(int(x))
    return re.sub(r"e\+?(-?)0*(\d)", r"e\1\2", f"{x:g}")


@dataclass(frozen=True)
class Spec:
    """What one config key may hold and what it means (the base of the kinds below)."""

    doc: str = ""
    #: Why the allowed range is what it is (docs only).
    why: str = ""
    #: ``None`` is allowed (and means what ``doc`` says).
    optional: bool = False

    def parse(self, raw: Any) -> Any:
        """The checked value, or :class:`Invalid`."""
        if raw is None and self.optional:
            return None
        return self._parse(raw)

    def _parse(self, raw: Any) -> Any:
        return raw

    def allowed(self) -> str:
        """The allowed values, for the docs' tables (``null`` first where allowed)."""
        text = self._allowed()
        return f"null or {text}" if self.optional else text

    def _allowed(self) -> str:
        return "any value"


@dataclass(frozen=True)
class Number(Spec):
    """A real number (or an integer) within ``[low, high]``; ``off`` is one more value allowed outside it."""

    low: float = -math.inf
    high: float = math.inf
    unit: str = ""
    integer: bool = False
    low_open: bool = False
    high_open: bool = False
    off: float | None = None

    def _parse(self, raw: Any) -> Any:
        if isinstance(raw, bool) or not isinstance(raw, numbers.Real):
            raise Invalid(f"must be {'an integer' if self.integer else 'a number'}, got {shown(raw)}")
        value: int | float = int(raw) if isinstance(raw, numbers.Integral) else float(raw)
        if isinstance(value, float):
            if not math.isfinite(value):
                raise Invalid(f"must be finite, got {shown(raw)}")
            if self.integer and not value.is_integer():
                raise Invalid(f"must be an integer, got {shown(raw)}")
        if self.off is not None and value == self.off:
            return int(value) if self.integer else float(value)
        low_ok = value > self.low if self.low_open else value >= self.low
        high_ok = value < self.high if self.high_open else value <= self.high
        if not (low_ok and high_ok):
            article = "an " if self.integer and self.off is None else ""
            raise Invalid(f"must be {article}{self._allowed()}, got {shown(raw)}")
        return int(value) if self.integer else float(value)

    def _allowed(self) -> str:
        unit = f" {self.unit}" if self.unit else ""
        kind = "integer " if self.integer else ""
        interval = (f"{'(' if self.low_open else '['}{_fmt(self.low)}, {_fmt(self.high)}"
                    f"{')' if self.high_open else ']'}")  # fmt: skip
        text = f"{kind}in {interval}{unit}"
        return f"{_fmt(self.off)} (off) or {text}" if self.off is not None else text


@dataclass(frozen=True)
class Text(Spec):
    """A string of at most ``max_length`` characters, optionally matching ``pattern`` (full match)."""

    max_length: int = 200
    pattern: str | None = None
    #: What ``pattern`` means, for messages and docs.
    pattern_doc: str = ""

    def _parse(self, raw: Any) -> Any:
        if not isinstance(raw, str):
            raise Invalid(f"must be a string, got {shown(raw)}")
        if len(raw) > self.max_length:
            raise Invalid(f"must be at most {self.max_length} characters long, got {len(raw)}")
        if self.pattern is not None and not re.fullmatch(self.pattern, raw):
            raise Invalid(f"must be {self.pattern_doc}, got {shown(raw)}")
        return raw

    def _allowed(self) -> str:
        return self.pattern_doc or f"text (≤ {self.max_length} characters)"


@dataclass(frozen=True)
class Choice(Spec):
    """One of a fixed set of values."""

    choices: tuple[Any, ...] = ()

    def _parse(self, raw: Any) -> Any:
        if isinstance(raw, str | type(None)) and raw in self.choices:
            return raw
        names = ", ".join("null" if c is None else str(c) for c in self.choices)
        raise Invalid(f"must be one of {names}, got {shown(raw)}")

    def _allowed(self) -> str:
        return " or ".join("null" if c is None else f"`{c}`" for c in self.choices)


@dataclass(frozen=True)
class Flag(Spec):
    """``true`` or ``false``."""

    def _parse(self, raw: Any) -> Any:
        if not isinstance(raw, bool):
            raise Invalid(f"must be true or false, got {shown(raw)}")
        return raw

    def _allowed(self) -> str:
        return "true or false"


@dataclass(frozen=True)
class Items(Spec):
    """A list of ``min_items`` … ``max_items`` values of one spec (a single value counts as a list of one
    where ``single`` is set). Built as a tuple (``as_tuple``) or a list."""

    item: Spec = Spec()
    min_items: int = 1
    max_items: int = 100
    single: bool = False
    as_tuple: bool = True
    #: What an entry is, for messages ("program": "must name at least one program").
    noun: str = "entry"

    def _parse(self, raw: Any) -> Any:
        if self.single and not isinstance(raw, list | tuple):
            raw = [raw]
        if not isinstance(raw, list | tuple):
            raise Invalid(f"must be a list, got {shown(raw)}")
        if len(raw) < self.min_items:
            least = "one" if self.min_items == 1 else str(self.min_items)
            raise Invalid(f"must name at least {least} {self.noun}, got {len(raw)}")
        if len(raw) > self.max_items:
            raise Invalid(f"must name at most {self.max_items} {self.noun} entries, got {len(raw)}")
        values = []
        for i, item in enumerate(raw):
            try:
                values.append(self.item.parse(item))
            except Invalid as exc:
                raise Invalid(f"entry {i + 1} {exc}") from None
        return tuple(values) if self.as_tuple else values

    def _allowed(self) -> str:
        return f"list of {self.min_items}-{self.max_items}: {self.item.allowed()}"


@dataclass(frozen=True)
class Table(Spec):
    """A mapping whose keys are data (``G54``, a tool number): each key checked and made canonical by
    ``key`` (a callable that returns the key or raises :class:`Invalid`), each value by ``value`` (a spec,
    or a :class:`Section` for a mapping per key). Built as a :class:`~cnc_gym.frozen.FrozenDict`."""

    key: Callable[[Any], Any] | None = None
    #: What a key is, for messages and docs ("`G54`…`G59`, `G54.1 P1`…").
    key_doc: str = ""
    value: Spec = Spec()
    max_entries: int = 1000

    def _allowed(self) -> str:
        return f"mapping of {self.key_doc} → {self.value.allowed()} (at most {self.max_entries})"


@dataclass(frozen=True)
class Section(Spec):
    """A nested mapping read into the dataclass ``of``."""

    of: type | None = None

    def _allowed(self) -> str:
        return f"mapping ({self.of.__name__ if self.of else '?'})"


def declared(spec: Spec, default: Any = None, default_factory: Callable[[], Any] | None = None) -> Any:
    """A dataclass field declared by ``spec`` (for a spec shared by several configs)."""
    if default_factory is not None:
        return dataclasses.field(default_factory=default_factory, metadata={"spec": spec})
    return dataclasses.field(default=default, metadata={"spec": spec})


def number(default: float | None, low: float, high: float, *, unit: str = "", doc: str = "", why: str = "",
           integer: bool = False, low_open: bool = False, high_open: bool = False,
           off: float | None = None, optional: bool = False) -> Any:  # fmt: skip
    """A numeric config key (a dataclass field)."""
    spec = Number(doc=doc, why=why, optional=optional, low=low, high=high, unit=unit, integer=integer,
                  low_open=low_open, high_open=high_open, off=off)  # fmt: skip
    return declared(spec, default)


def text(default: str, *, doc: str = "", why: str = "", max_length: int = 200, pattern: str | None = None,
         pattern_doc: str = "") -> Any:  # fmt: skip
    """A text config key."""
    return declared(Text(doc=doc, why=why, max_length=max_length, pattern=pattern,
                                pattern_doc=pattern_doc), default)  # fmt: skip


def choice(default: Any, choices: Iterable[Any], *, doc: str = "") -> Any:
    """A config key that takes one of ``choices``."""
    return declared(Choice(doc=doc, choices=tuple(choices)), default)


def flag(default: bool, *, doc: str = "") -> Any:
    """A true/false config key."""
    return declared(Flag(doc=doc), default)


def items(default_factory: Callable[[], Any], item: Spec, *, min_items: int = 1, max_items: int = 100,
          single: bool = False, as_tuple: bool = True, noun: str = "entry", doc: str = "",
          why: str = "") -> Any:  # fmt: skip
    """A list-valued config key."""
    spec = Items(doc=doc, why=why, item=item, min_items=min_items, max_items=max_items, single=single,
                 as_tuple=as_tuple, noun=noun)  # fmt: skip
    return declared(spec, default_factory=default_factory)


def table(key: Callable[[Any], Any], key_doc: str, value: Spec, *, doc: str = "", why: str = "",
          max_entries: int = 1000) -> Any:  # fmt: skip
    """A config key that maps data keys to values (:class:`Table`); the default is empty."""
    from cnc_gym.frozen import FrozenDict

    spec = Table(doc=doc, why=why, key=key, key_doc=key_doc, value=value, max_entries=max_entries)
    return declared(spec, default_factory=FrozenDict)


def section(of: type, *, doc: str = "", optional: bool = False) -> Any:
    """A nested section (a mapping read into the dataclass ``of``)."""
    spec = Section(doc=doc, optional=optional, of=of)
    return declared(spec, default_factory=None if optional else of)


def schema(cls: type) -> dict[str, Spec]:
    """The config keys of a dataclass and their specs, in declaration order."""
    return {f.name: f.metadata["spec"] for f in dataclasses.fields(cls) if "spec" in f.metadata}


def spec_of(cls: type, key: str) -> Spec:
    """The spec of one key (for checking a value that arrives another way, e.g. a command-line option)."""
    return schema(cls)[key]


# ------------------------------------------------------------------------------------------- building
def check_keys(data: dict, allowed: Iterable[str], source: str, where: str = "") -> None:
    """ConfigError naming the first key of ``data`` that is not in ``allowed`` (``where`` = its parent)."""
    allowed = set(allowed)
    unknown = sorted(shown(k, 40) if not isinstance(k, str) else k for k in data if k not in allowed)
    if unknown:
        prefix = f"{where}." if where else ""
        names = ", ".join(sorted(allowed))
        raise ConfigError(f"{source}: unknown key {prefix}{unknown[0]} (allowed: {names})")


def mapping(data: Any, source: str, where: str) -> dict:
    """``data`` if it is a mapping, else ConfigError naming ``where``. An empty section (None) is an
    empty mapping; an empty file (``where`` = "") is an error."""
    if data is None and where:
        return {}
    if not isinstance(data, dict):
        what = f"'{where}'" if where else "the config"
        got = "an empty file" if data is None else shown(data, 40)
        raise ConfigError(f"{source}: {what} must be a mapping, got {got}")
    return data


def parse_value(spec: Spec, raw: Any, source: str, path: str) -> Any:
    """One value checked against its spec; ConfigError ``source: path problem``."""
    if isinstance(spec, Table):
        return _parse_table(spec, raw, source, path)
    if isinstance(spec, Section) and spec.of is not None:
        if raw is None and spec.optional:
            return None
        if isinstance(raw, spec.of):
            check_object(raw, source, path)
            return raw
        return from_mapping(spec.of, raw, source, path)
    try:
        return spec.parse(raw)
    except Invalid as exc:
        raise ConfigError(f"{_place(source, path)} {exc}") from None


def _parse_table(spec: Table, raw: Any, source: str, path: str) -> Any:
    from cnc_gym.frozen import FrozenDict

    data = mapping(raw, source, path)
    if len(data) > spec.max_entries:
        raise ConfigError(f"{_place(source, path)} must have at most {spec.max_entries} entries, "
                          f"got {len(data)}")  # fmt: skip
    out: dict = {}
    for raw_key, raw_value in data.items():
        try:
            key = spec.key(raw_key) if spec.key is not None else raw_key
        except Invalid as exc:
            raise ConfigError(f"{_place(source, path)} key {shown(raw_key, 40)} {exc}") from None
        if key in out:
            raise ConfigError(f"{_place(source, path)} names {key} twice ({shown(raw_key, 40)})")
        out[key] = parse_value(spec.value, raw_value, source, f"{path}.{key}")
    return FrozenDict(out)


def _join(where: str, key: str) -> str:
    return f"{where}.{key}" if where else key


def from_mapping(cls: type, data: Any, source: str, where: str = "", extra: dict | None = None) -> Any:
    """Build the dataclass ``cls`` from YAML data: unknown keys, wrong types and out-of-range values are
    one ConfigError ``source: where.key problem``. ``extra`` fills fields that the caller built itself."""
    data = mapping(data, source, where)
    specs = schema(cls)
    check_keys(data, specs, source, where)
    values = {key: parse_value(specs[key], raw, source, _join(where, key)) for key, raw in data.items()}
    obj = cls(**values, **(extra or {}))
    _cross_check(obj, source, where)
    return obj


def check_object(obj: Any, source: str, where: str = "") -> None:
    """Check a config dataclass built in Python (e.g. a ``MachineConfig`` passed to the env) against its
    schema: the same rules and messages as a file."""
    for key, spec in schema(type(obj)).items():
        parse_value(spec, getattr(obj, key), source, _join(where, key))
    _cross_check(obj, source, where)


def _cross_check(obj: Any, source: str, where: str) -> None:
    problems: Callable[[], Iterator[tuple[str, str]]] | None = getattr(obj, "config_problems", None)
    for key, problem in problems() if problems else ():
        raise ConfigError(f"{_place(source, _join(where, key))} {problem}")


# ---------------------------------------------------------------------------------------------- docs
def markdown_table(cls: type, prefix: str = "") -> str:
    """The docs' table of a config section: key, default, allowed values, meaning (and why the range)."""
    rows = ["| key | default | allowed | meaning |", "|---|---|---|---|"]
    defaults = {f.name: f for f in dataclasses.fields(cls)}
    for key, spec in schema(cls).items():
        f = defaults[key]
        if isinstance(spec, Section):
            default = "see below"
        else:
            factory = f.default_factory
            value = factory() if callable(factory) else f.default
            default = "null" if value is None else f"`{_default_text(value) or chr(34) * 2}`"
        meaning = spec.doc + (f" *Range:* {spec.why}" if spec.why else "")
        rows.append(f"| `{prefix}{key}` | {default} | {spec.allowed()} | {meaning} |")
    return "\n".join(rows)


def _default_text(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {_default_text(v)}" for k, v in value.items()) + "}"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_default_text(v) for v in value) + "]"
    if isinstance(value, float):
        return _fmt(value) if value.is_integer() else repr(value)
    return str(value)


# ----------------------------------------------------------------------------------------------- YAML
@cache
def _config_loader() -> type:
    """The loader class, made on first use (importing PyYAML costs start-up time a config-less command
    need not pay)."""
    import yaml

    class ConfigLoader(yaml.SafeLoader):
        """PyYAML's safe loader with a nesting cap and YAML 1.2 exponent floats (``1e-3``)."""

        def __init__(self, stream: str) -> None:
            super().__init__(stream)
            self._depth = 0
            self._nodes = 0

        def compose_node(self, parent: Any, index: Any) -> Any:
            self._depth += 1
            self._nodes += 1
            try:
                if self._depth > MAX_NESTING or self._nodes > MAX_NODES:
                    line = self.peek_event().start_mark.line + 1
                    too_deep = self._depth > MAX_NESTING
                    raise _Bound(line, f"nested deeper than {MAX_NESTING} levels" if too_deep
                                 else f"more than {MAX_NODES} values")  # fmt: skip
                return super().compose_node(parent, index)
            finally:
                self._depth -= 1

    ConfigLoader.add_implicit_resolver(
        "tag:yaml.org,2002:float",
        re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE][-+]?[0-9]+$"),
        list("-+0123456789."),
    )
    return ConfigLoader


class _Bound(Exception):
    """The composer stopped at a bound (before building the rest of the tree)."""

    def __init__(self, line: int, problem: str) -> None:
        self.line = line
        self.problem = problem


def _tree_problem(root: yaml.Node) -> tuple[int, str] | None:
    """``(line, problem)`` of the composed YAML tree, or None: too many values or too deep once aliases are
    expanded, an alias inside itself, a duplicate key. Each node is walked once (sizes and heights are
    remembered), so a "billion laughs" file costs as much as its text."""
    import yaml

    seen_nodes: dict[int, tuple[int, int]] = {}  # id → (values in the expanded subtree, its height)
    open_nodes: set[int] = set()

    def walk(node: yaml.Node, depth: int) -> tuple[int, int]:
        key = id(node)
        if key in open_nodes:
            raise _Stop(node, "an alias refers to a node that contains it")
        if key not in seen_nodes:
            open_nodes.add(key)
            count, height = 1, 1
            children: list[yaml.Node] = []
            if isinstance(node, yaml.SequenceNode):
                children = list(node.value)
            elif isinstance(node, yaml.MappingNode):
                keys: set[str] = set()
                for k, v in node.value:
                    if isinstance(k, yaml.ScalarNode) and k.tag != "tag:yaml.org,2002:merge":
                        if k.value in keys:
                            raise _Stop(k, f"duplicate key {shown(k.value, 40)}")
                        keys.add(k.value)
                    children += (k, v)
            for child in children:
                child_count, child_height = walk(child, depth + 1)
                count += child_count
                height = max(height, child_height + 1)
            open_nodes.discard(key)
            seen_nodes[key] = (count, height)
        count, height = seen_nodes[key]
        if depth + height - 1 > MAX_NESTING:
            raise _Stop(node, f"nested deeper than {MAX_NESTING} levels once aliases are expanded")
        if count > MAX_NODES:
            raise _Stop(node, f"more than {MAX_NODES} values once aliases are expanded")
        return count, height

    try:
        walk(root, 1)
    except _Stop as stop:
        return stop.node.start_mark.line + 1, stop.problem
    return None


class _Stop(Exception):
    def __init__(self, node: yaml.Node, problem: str) -> None:
        self.node = node
        self.problem = problem


def _yaml_message(exc: yaml.YAMLError) -> tuple[int | None, str]:
    import yaml

    if isinstance(exc, yaml.reader.ReaderError):
        return None, f"character #x{exc.character:04x} at offset {exc.position} is not allowed in YAML"
    if isinstance(exc, yaml.MarkedYAMLError) and exc.problem_mark is not None:
        problem = " ".join(str(part) for part in (exc.context, exc.problem) if part)
        return exc.problem_mark.line + 1, problem
    return None, " ".join(str(exc).split())


def parse_yaml(text_: str, source: str) -> Any:
    """The data of one YAML document, read with the bounded safe loader; ConfigError on any problem."""
    import yaml

    loader = None
    try:
        loader = _config_loader()(text_)
        root = loader.get_single_node()
        if root is None:
            return None
        problem = _tree_problem(root)
        if problem is not None:
            raise ConfigError(f"{source}:{problem[0]}: {problem[1]}")
        return loader.construct_document(root)
    except _Bound as exc:
        raise ConfigError(f"{source}:{exc.line}: {exc.problem}") from None
    except yaml.YAMLError as exc:
        line, message = _yaml_message(exc)
        where = f"{source}:{line}" if line else source
        raise ConfigError(f"{where}: invalid YAML: {escaped(message)}") from None
    except (ValueError, OverflowError):  # Python's int() refuses literals of more than 4300 digits
        raise ConfigError(f"{source}: invalid YAML: a number literal is too long") from None
    finally:
        if loader is not None:
            loader.dispose()


def read_yaml(path: str | Path, what: str) -> Any:
    """The data of a YAML config file (``what`` names the kind of config in messages), or ConfigError."""
    try:
        raw = read_regular_file(path, limit=MAX_CONFIG_BYTES, what=what)  # a FIFO or /dev/zero: refused
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read {what}: {exc.strerror or exc}") from None
    try:
        decoded = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(
            f"{path}: {what} is not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset {exc.start})"
        ) from None
    # A bench run reads the same preset hundreds of times (every episode's env): parsed once per text, and
    # every caller gets its own copy to change.
    return copy.deepcopy(_parse_yaml_cached(decoded, str(path)))


#: parse_yaml's results by (text, source); a failed parse raises every time (nothing is kept of it).
_parse_yaml_cached = functools.lru_cache(maxsize=64)(parse_yaml)
