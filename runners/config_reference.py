"""Write ``docs/configuration.md``: every config group, option and key, from the schema and the YAML files.

``python -m runners.config_reference`` rewrites the file; ``--check`` only says whether it is up to date (exit 1 when
not). The reference is built from two sources and nothing else:

- the typed schema dataclasses of :mod:`curiosity.config.schema`: each key's type (an enum as its allowed values), its
  schema default and the comment written beside it (or the class docstring), read from the source with ``ast`` and
  ``tokenize``;
- the YAML options under ``conf/``: the values an option sets over its schema, its leading comment, and the comment
  beside a key where the schema has none. Options that change other groups (``@package _global_``: ``baseline``,
  ``+experiment``, ``+sweep``) are composed with Hydra and listed by what they change against the default config.

The range checks of :data:`curiosity.config.validate.RULES` give the "allowed" column. The output is deterministic, so
``tests/test_docs.py`` compares the committed file with what this module writes.
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import io
import re
import sys
import tokenize
from collections.abc import Iterator
from enum import Enum
from pathlib import Path
from typing import Any

import yaml
from omegaconf import OmegaConf

from curiosity.config import schema, setup
from curiosity.config.compose import CONF_DIR, compose_config
from curiosity.config.validate import RULES

REPO = CONF_DIR.parent
OUT = REPO / "docs" / "configuration.md"
SCHEMA_FILE = Path(schema.__file__)
GROUPS = ("env", "encoder", "entropy", "estimator", "backward", "intrinsic", "planner", "budget", "baseline")
PRESET_GROUPS = ("experiment", "sweep")  # added with +group=option
ALLOWED = {key: allowed for key, _, allowed in RULES}
SCHEMA_REF = re.compile(r"^/schema/([^/]+)/([^@]+)@(.+)$")


# ---------------------------------------------------------------- the schema's comments and types
def _clean_comment(text: str) -> str:
    """A source comment without its ``#`` marks and any ``type: ignore[...]`` part."""
    parts = [p.strip() for p in text.split("#")]
    return " ".join(p for p in parts if p and not p.startswith("type: ignore"))


def _schema_comments() -> tuple[dict[tuple[str, str], str], dict[str, str]]:
    """(class, field) -> the comment beside the field (with ``# |`` continuation lines), and class -> docstring."""
    source = SCHEMA_FILE.read_text()
    comments: dict[int, str] = {}
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type == tokenize.COMMENT:
            comments[tok.start[0]] = tok.string
    lines = source.splitlines()
    fields: dict[tuple[str, str], str] = {}
    docs: dict[str, str] = {}
    for node in ast.parse(source).body:
        if not isinstance(node, ast.ClassDef):
            continue
        if doc := ast.get_docstring(node):
            docs[node.name] = " ".join(doc.split()).replace("``", "`")
        for stmt in node.body:
            if not (isinstance(stmt, ast.AnnAssign) and isinstance(stmt.target, ast.Name)):
                continue
            end = stmt.end_lineno or stmt.lineno
            text = [_clean_comment(comments[end])] if end in comments else []
            line = end + 1
            while line <= len(lines) and lines[line - 1].strip().startswith("# |"):
                text.append(_clean_comment(lines[line - 1]))
                line += 1
            fields[(node.name, stmt.target.id)] = " ".join(t for t in text if t)
    return fields, docs


FIELD_COMMENTS, CLASS_DOCS = _schema_comments()


def _schema_class(name: str) -> type | None:
    found = getattr(schema, name, None)
    return found if isinstance(found, type) else None


def _type_text(annotation: str) -> str:
    """An annotation as the reference shows it: an enum as its values (``pixels | state``), else as written."""
    cls = _schema_class(annotation)
    if cls is not None and issubclass(cls, Enum):
        return " | ".join(str(member.value) for member in cls)
    return annotation


def _comment(cls: type, name: str) -> str:
    """The comment beside field ``name`` of ``cls`` or of the class it inherits the field from."""
    for klass in cls.__mro__:
        if (klass.__name__, name) in FIELD_COMMENTS:
            return FIELD_COMMENTS[(klass.__name__, name)]
    return ""


@dataclasses.dataclass
class KeyInfo:
    type: str
    comment: str


def _schema_keys(cls: type, prefix: str) -> dict[str, KeyInfo]:
    """Dotted key -> type and comment for every field of the dataclass ``cls`` below ``prefix`` (nested ones too)."""
    keys: dict[str, KeyInfo] = {}
    for f in dataclasses.fields(cls):
        path = f"{prefix}.{f.name}" if prefix else f.name
        nested = _schema_class(str(f.type))
        if nested is not None and dataclasses.is_dataclass(nested):
            keys.update(_schema_keys(nested, path))
        else:
            keys[path] = KeyInfo(_type_text(str(f.type)), _comment(cls, f.name))
    return keys


def _schema_values(cls: type) -> dict[str, Any]:
    """The schema's defaults of ``cls`` as a plain nested dict (enums as their values, MISSING as ``???``)."""
    return OmegaConf.to_container(OmegaConf.structured(cls), resolve=False, enum_to_str=True)  # type: ignore[return-value]


# ---------------------------------------------------------------- YAML files: comments and bodies
def _yaml_comments(path: Path) -> dict[str, str]:
    """Dotted key -> the comment beside it in a YAML file (comment-only lines aligned under it continue it)."""
    found: dict[str, str] = {}
    stack: list[tuple[int, str]] = []  # (indent, key) of the enclosing mappings
    last: tuple[str, int] | None = None  # (key, column of its '#') of the previous commented key
    for raw in path.read_text().splitlines():
        stripped = raw.strip()
        if stripped.startswith("#"):
            if last and raw.index("#") == last[1]:
                found[last[0]] += " " + _clean_comment(stripped)
            continue
        last = None
        match = re.match(r"^(\s*)([A-Za-z_][\w]*|\"[^\"]+\"):(.*)$", raw)
        if not match or not stripped or stripped.startswith("-"):
            continue
        indent, key, rest = len(match[1]), match[2].strip('"'), match[3]
        while stack and stack[-1][0] >= indent:
            stack.pop()
        dotted = ".".join([k for _, k in stack] + [key])
        if "#" in rest:
            column = len(raw) - len(rest) + rest.index("#")
            found[dotted] = _clean_comment(rest[rest.index("#") :])
            last = (dotted, column)
        if not rest.split("#")[0].strip():  # a mapping opens here
            stack.append((indent, key))
    return found


def _header(path: Path) -> list[str]:
    """The comment block at the top of a YAML file as Markdown, in order: prose lines joined into paragraphs, indented
    lines (example commands) as code blocks; ``@package`` lines left out."""
    blocks: list[tuple[bool, list[str]]] = []  # (is code, lines)
    for raw in path.read_text().splitlines():
        if not raw.startswith("#"):
            break
        text = raw[1:]
        if text.strip().startswith("@package") or not text.strip():
            continue
        is_code = text.startswith("   ")
        if not blocks or blocks[-1][0] != is_code:
            blocks.append((is_code, []))
        blocks[-1][1].append(text.strip())
    lines: list[str] = []
    for is_code, block in blocks:
        lines += ["```bash", *block, "```", ""] if is_code else [_citations(" ".join(block)), ""]
    return lines


def _describe(schema_comment: str, yaml_comment: str) -> str:
    """The "what" of a key: the schema's comment, and the option file's where it adds to it (alone where it restates
    and extends the schema's)."""
    if not (schema_comment and yaml_comment):
        return schema_comment or yaml_comment
    words = set(re.findall(r"\w+", schema_comment.lower()))
    shared = words & set(re.findall(r"\w+", yaml_comment.lower()))
    return yaml_comment if len(shared) >= 0.6 * len(words) else f"{schema_comment}; {yaml_comment}"


def _is_global(path: Path) -> bool:
    return path.read_text().startswith("# @package _global_")


def _body(path: Path) -> tuple[list[Any], dict[str, Any]]:
    """A YAML option's defaults list and the rest of its body."""
    data = yaml.safe_load(path.read_text()) or {}
    return data.pop("defaults", []), data


def _merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for key, value in over.items():
        out[key] = _merge(out[key], value) if isinstance(value, dict) and isinstance(out.get(key), dict) else value
    return out


def _flatten(node: Any, prefix: str) -> Iterator[tuple[str, Any]]:
    if isinstance(node, dict) and node:
        for key, value in node.items():
            yield from _flatten(value, f"{prefix}.{key}" if prefix else str(key))
    else:
        yield prefix, node


# ---------------------------------------------------------------- rendering
def _citations(text: str) -> str:
    """The citations of ``docs/method.md`` and ``docs/protocol.md`` in a YAML comment, as paths from ``docs/`` itself."""
    return re.sub(r"docs/(method|protocol)\.md", r"\1.md", text)


def _cell(text: str) -> str:
    return _citations(text).replace("|", "\\|").replace("\n", " ")


def _value(value: Any) -> str:
    """A value as YAML writes it on one line (``???``: required, ``${...}``: resolved when the run starts)."""
    if isinstance(value, str):
        return value
    return yaml.safe_dump(value, default_flow_style=True, width=10**6).strip().removesuffix("...").strip()


def _code(text: str) -> str:
    return f"`{text}`" if text else ""


def _table(rows: list[tuple[str, str, Any, str]]) -> list[str]:
    out = ["| key | type | default | allowed | what |", "|---|---|---|---|---|"]
    for key, kind, value, comment in rows:
        allowed = ALLOWED.get(key, "")
        out.append(f"| {_code(key)} | {_cell(kind)} | {_cell(_code(_value(value)))} | {_cell(allowed)} | {_cell(comment)} |")
    return out


def _rows(values: dict[str, Any], prefix: str, infos: dict[str, KeyInfo], comments: dict[str, str]) -> list:
    """Table rows for a nested dict of values below ``prefix`` (``infos``: schema keys; ``comments``: YAML comments
    by key relative to the file)."""
    rows = []
    for key, value in _flatten(values, prefix):
        info = infos.get(key) or next((infos[k] for k in infos if key.startswith(k + ".")), None)
        kind = info.type if info else f"{type(value).__name__} (no schema)"
        relative = key.removeprefix(prefix + ".") if prefix else key
        comment = _describe(info.comment if info else "", comments.get(relative, ""))
        rows.append((key, kind, value, comment))
    return rows


def _option_values(group: str, path: Path) -> tuple[dict[str, Any], dict[str, KeyInfo]]:
    """An option of a plain group: its values (schema defaults, then its body) and the schema keys below ``group``."""
    defaults, body = _body(path)
    values: dict[str, Any] = {}
    infos: dict[str, KeyInfo] = {}
    for entry in defaults:
        match = SCHEMA_REF.match(str(entry)) if isinstance(entry, str) else None
        if not match:
            continue
        cls = schema._GROUP_SCHEMAS[match[1]][match[2]]
        where = "" if match[3] == "_here_" else match[3]
        node = _schema_values(cls)
        for part in reversed(where.split(".") if where else []):
            node = {part: node}
        values = _merge(values, node)
        infos.update(_schema_keys(cls, f"{group}.{where}" if where else group))
        if cls.__name__ in CLASS_DOCS:
            infos.setdefault(f"__doc__{where}", KeyInfo("", CLASS_DOCS[cls.__name__]))
    return _merge(values, body), infos


def _docs_of(infos: dict[str, KeyInfo]) -> list[str]:
    return [info.comment for key, info in sorted(infos.items()) if key.startswith("__doc__")]


def _plain_option(group: str, path: Path) -> list[str]:
    values, infos = _option_values(group, path)
    lines = [f"### `{group}={path.stem}`", ""]
    lines += _header(path)
    for doc in _docs_of(infos):
        lines += [f"Schema: {_citations(doc)}", ""]
    keys = {k: v for k, v in infos.items() if not k.startswith("__doc__")}
    return [*lines, *_table(_rows(values, group, keys, _yaml_comments(path))), ""]


class _Composer:
    """Composed configs (unresolved, as plain dicts) and their group choices, the default one first."""

    def __init__(self) -> None:
        setup()
        self.default, self.default_choices = self.compose([])

    @staticmethod
    def compose(overrides: list[str]) -> tuple[dict[str, Any], dict[str, str]]:
        cfg = compose_config(overrides, hydra_node=True)
        choices = {k: str(v) for k, v in cfg.hydra.runtime.choices.items() if not str(k).startswith("hydra/")}
        data = OmegaConf.to_container(cfg, resolve=False, enum_to_str=True)
        assert isinstance(data, dict)
        return data, choices


def _changes(composer: _Composer, overrides: list[str], plain: dict[str, dict[str, Any]]) -> tuple[list[str], dict]:
    """What ``overrides`` change against the default config: group choices, then keys (against the default, or, in a
    group whose option changed, against that option's own values); and the composed config's ``hydra`` node."""
    data, choices = composer.compose(overrides)
    lines = [f"- `{group}={choice}` (default `{composer.default_choices.get(group)}`)"
             for group, choice in sorted(choices.items())
             if composer.default_choices.get(group) != choice and group not in PRESET_GROUPS]  # fmt: skip
    default = dict(_flatten({k: v for k, v in composer.default.items() if k != "hydra"}, ""))
    for group, choice in choices.items():
        if composer.default_choices.get(group) != choice and (group, choice) in plain:
            default = {k: v for k, v in default.items() if not k.startswith(group + ".")}
            default.update(dict(_flatten(plain[(group, choice)], group)))
    for key, value in _flatten({k: v for k, v in data.items() if k != "hydra"}, ""):
        if key not in default:
            lines.append(f"- `{key}={_value(value)}` (added)")
        elif default[key] != value:
            lines.append(f"- `{key}={_value(value)}` (was `{_value(default[key])}`)")
    return lines, data.get("hydra", {})


def _global_option(composer: _Composer, group: str, path: Path, plain: dict) -> list[str]:
    added = group in PRESET_GROUPS
    override = f"+{group}={path.stem}" if added else f"{group}={path.stem}"
    lines = [f"### `{override}`", ""]
    lines += _header(path)
    changes, hydra = _changes(composer, [override], plain)
    if group == "sweep":
        sweep_dir = hydra.get("sweep", {}).get("dir")
        params = hydra.get("sweeper", {}).get("params") or {}
        lines += [f"Sweep directory `{sweep_dir}`; one job per combination of:", ""]
        lines += [f"- `{key}`: `{_value(value)}`" for key, value in params.items()] + [""]
    lines += ["What it changes against the default config:" if changes else "It changes nothing in the default config.", ""]
    return [*lines, *[_citations(line) for line in changes], ""]


def _top_level() -> list[str]:
    """The keys outside the groups: the run's own and ``agent.*``, with the defaults of ``conf/config.yaml``."""
    defaults, body = _body(CONF_DIR / "config.yaml")
    comments = _yaml_comments(CONF_DIR / "config.yaml")
    values = _merge(_schema_values(schema.AgentKeysConfig), body.get("agent", {}))
    groups = set(GROUPS) | {"backward", "method_label", "agent"}
    infos = {k: v for k, v in _schema_keys(schema.Config, "").items() if k.split(".")[0] not in groups}
    run = {k: body.get(k, v) for k, v in _schema_values(schema.Config).items() if k in infos}
    chosen = [entry for entry in defaults if isinstance(entry, dict)]
    lines = ["## Top-level keys", "", "The run's own keys (`conf/config.yaml`; `key=value` on the command line):", ""]
    lines += [*_table(_rows(run, "", infos, comments)), ""]
    lines += ["## `agent`", "", f"Schema: {CLASS_DOCS['AgentKeysConfig']} The defaults are `conf/config.yaml`'s.", ""]
    agent_infos = _schema_keys(schema.AgentKeysConfig, "agent")
    lines += [*_table(_rows(values, "agent", agent_infos, {k.removeprefix("agent."): v for k, v in comments.items()})), ""]
    lines += ["## Default options", "", "`conf/config.yaml` picks one option of each group:", ""]
    lines += [f"- `{k}={v}`" for entry in chosen for k, v in entry.items() if not str(k).startswith("override")]
    return [*lines, ""]


def render() -> str:
    """The whole reference, as ``docs/configuration.md`` holds it."""
    composer = _Composer()
    plain: dict[tuple[str, str], dict[str, Any]] = {}
    sections: list[str] = []
    for group in GROUPS:
        options = sorted((CONF_DIR / group).glob("*.yaml"))
        sections += [f"## `{group}`", "", f"Options (`conf/{group}/`): " + ", ".join(f"`{p.stem}`" for p in options) + ".", ""]
        for path in options:
            if _is_global(path):
                continue
            plain[(group, path.stem)] = _option_values(group, path)[0]
        for path in options:
            sections += _global_option(composer, group, path, plain) if _is_global(path) else _plain_option(group, path)
    for group in PRESET_GROUPS:
        options = sorted((CONF_DIR / group).glob("*.yaml"))
        sections += [f"## `+{group}`", "", f"Presets (`conf/{group}/`), added with `+{group}=<option>`: "
                     + ", ".join(f"`{p.stem}`" for p in options) + ".", ""]  # fmt: skip
        for path in options:
            sections += _global_option(composer, group, path, plain)
    launcher = CONF_DIR / "hydra" / "launcher"
    sections += ["## `hydra/launcher`", "",
                 "Hydra's launchers: `basic` (the default: one job after another), `joblib` (local processes, "
                 "`hydra.launcher.n_jobs`), `submitit_local`, `submitit_slurm` (the plugins' own keys: `--cfg hydra`), "
                 "and this repository's example:", ""]  # fmt: skip
    for path in sorted(launcher.glob("*.yaml")):
        defaults, body = _body(path)
        sections += [f"### `hydra/launcher={path.stem}`", "", *_header(path),
                     f"Built on `{', '.join(str(d) for d in defaults if d != '_self_')}`; it sets:", ""]  # fmt: skip
        sections += [f"- `hydra.launcher.{k}={_value(v)}`" for k, v in _flatten(body, "")] + [""]
    head = [
        "# Configuration reference",
        "",
        "<!-- Generated by `python -m runners.config_reference` from curiosity/config/schema.py and conf/; do not edit."
        " tests/test_docs.py checks that this file is what the generator writes. -->",
        "",
        "Every group, option and key of `python -m runners.train`. How to set them on the command line and sweep them:"
        " [usage.md](usage.md); what they mean for the method: [method.md](method.md).",
        "",
        "Columns: **key** as the command line names it (`encoder.blur_sigma=2`); **type** (an enum as its allowed"
        " values); **default**, the value the option gives it (`???`: required; `${...}`: an interpolation, resolved when"
        " the run starts); **allowed**, the range that config validation checks before anything runs; **what**, the"
        " comment beside the key in the schema, or else in the option's YAML file.",
        "",
        "Groups: " + ", ".join(f"`{g}`" for g in GROUPS) + ", " + ", ".join(f"`+{g}`" for g in PRESET_GROUPS)
        + ", `hydra/launcher`; and the [top-level keys](#top-level-keys) and [`agent`](#agent) keys.",
        "",
    ]  # fmt: skip
    text = "\n".join([*head, *_top_level(), *sections]).rstrip() + "\n"
    return re.sub(r"\n{3,}", "\n\n", text)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m runners.config_reference", description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=OUT, help=f"where to write (default: {OUT.relative_to(REPO)})")
    parser.add_argument("--check", action="store_true", help="write nothing; exit 1 if the file differs")
    args = parser.parse_args(argv)
    text = render()
    if args.check:
        current = args.out.read_text() if args.out.exists() else ""
        if current != text:
            print(f"error: {args.out} is out of date; run python -m runners.config_reference", file=sys.stderr)
            return 1
        return 0
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
