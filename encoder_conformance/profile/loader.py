"""Load device profiles from YAML: strict validation, ``extends:`` and EDS merging.

Every problem is reported as ``file:line: key.path: what is wrong; how to fix`` through
ProfileError; callers never see a pydantic or YAML traceback.
"""

from __future__ import annotations

import contextlib
import difflib
import hashlib
from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml
from pydantic import BaseModel, ValidationError

from encoder_conformance.errors import ProfileError
from encoder_conformance.paths import PROFILE_DIR
from encoder_conformance.profile import schema as profile_schema
from encoder_conformance.profile.quirk_effects import EFFECT_MODELS
from encoder_conformance.profile.quirks import DOCUMENTATION_ONLY
from encoder_conformance.profile.schema import SCHEMA_VERSION, DeviceProfile

if TYPE_CHECKING:
    from pydantic_core import ErrorDetails

QUIRK_TAGS = frozenset(EFFECT_MODELS) | {DOCUMENTATION_ONLY}

PROFILE_SUFFIXES = (".yaml", ".yml")
DEFAULT_PROFILE_DIR = PROFILE_DIR


@dataclass(frozen=True)
class LoadedProfile:
    """A validated profile plus where it came from (for the report header)."""

    profile: DeviceProfile
    path: Path
    sha256: str
    chain: tuple[Path, ...]  # the file and every file it extends, child first


def _all_field_names() -> set[str]:
    names: set[str] = set()
    for obj in vars(profile_schema).values():
        if isinstance(obj, type) and issubclass(obj, BaseModel):
            names.update(obj.model_fields)
    for effect in EFFECT_MODELS.values():
        names.update(effect.model_fields)
    return names


_FIELD_NAMES = _all_field_names()


def _parse_index(key: Any) -> Any:
    """Accept 0x6001 (int), '0x6001', '6001h' and '6001' as an object index."""
    if isinstance(key, int):
        return key
    if isinstance(key, str):
        text = key.strip().lower()
        try:
            if text.endswith("h"):
                return int(text[:-1], 16)
            if text.startswith("0x"):
                return int(text, 16)
            return int(text, 16)
        except ValueError:
            return key
    return key


def _normalise_keys(data: dict[str, Any]) -> dict[str, Any]:
    """Object indices and sub-indices become ints, so 'extends' merges by number."""
    objects = data.get("objects")
    if isinstance(objects, dict):
        fixed: dict[Any, Any] = {}
        for key, obj in objects.items():
            if isinstance(obj, dict) and isinstance(obj.get("subs"), dict):
                obj = {**obj, "subs": {_parse_sub(k): v for k, v in obj["subs"].items()}}
            fixed[_parse_index(key)] = obj
        data = {**data, "objects": fixed}
    return data


def _parse_sub(key: Any) -> Any:
    """Accept 3, '3', '0x0A' and '0Ah' as a sub-index ('h' suffix = hexadecimal)."""
    if isinstance(key, str):
        text = key.strip().lower()
        try:
            return int(text[:-1], 16) if text.endswith("h") else int(text, 0)
        except ValueError:
            return key
    return key


def _line_map(text: str) -> dict[tuple[Any, ...], int]:
    """Key path -> 1-based line, from the YAML node graph (indices parsed as numbers)."""
    lines: dict[tuple[Any, ...], int] = {}

    def walk(node: yaml.Node, path: tuple[Any, ...]) -> None:
        if isinstance(node, yaml.MappingNode):
            for key_node, value_node in node.value:
                key: Any = key_node.value
                if (len(path) in (1, 3) and path[:1] == ("objects",)) or path[-1:] == ("subs",):
                    key = _parse_index(key) if path == ("objects",) else _parse_sub(key)
                lines[(*path, key)] = key_node.start_mark.line + 1
                walk(value_node, (*path, key))
        elif isinstance(node, yaml.SequenceNode):
            for i, item in enumerate(node.value):
                lines[(*path, i)] = item.start_mark.line + 1
                walk(item, (*path, i))

    try:
        root = yaml.compose(text)
    except yaml.YAMLError:
        return lines
    if root is not None:
        walk(root, ())
    return lines


def _format_path(loc: tuple[Any, ...]) -> str:
    parts: list[str] = []
    for i, part in enumerate(loc):
        if isinstance(part, int) and i == 1 and loc[0] == "objects":
            parts.append(f"0x{part:04X}")
        else:
            parts.append(str(part))
    return ".".join(parts) or "(top level)"


def _hint(error: ErrorDetails) -> str:
    kind = error["type"]
    field = error["loc"][-1] if error["loc"] else ""
    if kind == "extra_forbidden":
        close = difflib.get_close_matches(str(field), _FIELD_NAMES, n=1)
        return f"unknown key{'; did you mean ' + repr(close[0]) + '?' if close else '; remove it'}"
    if kind == "missing":
        return "required key is missing; add it"
    if kind == "unknown_effect":
        given = error["input"].get("effect") if isinstance(error["input"], dict) else None
        close = difflib.get_close_matches(str(given), EFFECT_MODELS, n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        return f"unknown quirk effect {given!r}; {hint}known effects: {', '.join(sorted(EFFECT_MODELS))}"
    return error["msg"]


def _clean_loc(loc: tuple[Any, ...]) -> tuple[Any, ...]:
    """Drop pydantic's union/function markers (and a quirk's effect tag) from a location."""
    loc = tuple(p for p in loc if not (isinstance(p, str) and ("[" in p or p.startswith("function-"))))
    if loc[:1] == ("quirks",) and len(loc) > 2 and loc[2] in QUIRK_TAGS:
        loc = loc[:2] + loc[3:]
    return loc


def _read_yaml(path: Path) -> tuple[dict[str, Any], str]:
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ProfileError(str(path), [f"cannot read the file: {exc.strerror}"]) from None
    except UnicodeDecodeError as exc:
        raise ProfileError(str(path), [f"byte {exc.start} is not UTF-8; save the file as UTF-8"]) from None
    try:
        data = yaml.load(text, Loader=_StrictLoader)  # a SafeLoader subclass
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark else ""
        problem = getattr(exc, "problem", None) or str(exc)
        raise ProfileError(str(path), [f"{where}not valid YAML: {problem}"]) from None
    if not isinstance(data, dict):
        raise ProfileError(str(path), ["the file must hold a mapping (key: value pairs) at the top level"])
    return _normalise_keys(data), text


if TYPE_CHECKING:  # the checker takes no base class chosen at run time; libyaml's loader has SafeLoader's methods
    _SafeLoader = yaml.SafeLoader
else:
    #: libyaml's parser where PyYAML was built with it (about 10x faster on a 1,400-line profile), else PyYAML's own
    _SafeLoader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class _StrictLoader(_SafeLoader):
    """SafeLoader that refuses a key given twice in one mapping (it would silently replace the first)."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        seen: dict[Any, int] = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"key {key_node.value!r} given twice (first on line {seen[key]})", key_node.start_mark
                )
            seen[key] = key_node.start_mark.line + 1
        return super().construct_mapping(node, deep=deep)


def deep_merge(base: dict[Any, Any], override: dict[Any, Any]) -> dict[Any, Any]:
    """Merge ``override`` into ``base``: mappings merge, other values replace, null deletes."""
    merged = dict(base)
    for key, value in override.items():
        if value is None and key in merged and key not in ("default", "min", "max", "allowed", "notes", "effect"):
            del merged[key]
        elif isinstance(value, dict) and isinstance(merged.get(key), dict):
            merged[key] = deep_merge(merged[key], value)
        else:
            merged[key] = value
    return merged


def find_profile(name_or_path: str, search_dirs: list[Path] | None = None) -> Path:
    """Resolve a profile id ('wachendorff-wdga-mt') or a path to a file."""
    candidate = Path(name_or_path)
    if candidate.suffix in PROFILE_SUFFIXES or candidate.exists():
        if candidate.is_file():
            return candidate
        raise ProfileError(name_or_path, ["no such file; give a profile id or the path of a .yaml file"])
    dirs = search_dirs or [DEFAULT_PROFILE_DIR]
    for directory in dirs:
        for suffix in PROFILE_SUFFIXES:
            path = directory / f"{name_or_path}{suffix}"
            if path.is_file():
                return path
    known = ", ".join(p.id for p in iter_profile_ids(dirs))
    raise ProfileError(name_or_path, [f"no profile with this id in {', '.join(map(str, dirs))}; known: {known}"])


@dataclass(frozen=True)
class ProfileRef:
    id: str
    path: Path
    abstract: bool


def iter_profile_ids(dirs: list[Path] | None = None) -> Iterator[ProfileRef]:
    """Every profile file in the given directories (ids from the file names)."""
    for directory in dirs or [DEFAULT_PROFILE_DIR]:
        for path in sorted(directory.glob("*.yaml")):
            try:
                data = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
            except (OSError, yaml.YAMLError):
                data = {}
            yield ProfileRef(path.stem, path, bool(isinstance(data, dict) and data.get("abstract")))


def iter_own_profiles(folder: Path) -> Iterator[ProfileRef]:
    """The user's own profiles in ``folder`` and its device_profiles/: YAML files with a ``schema_version`` and
    an ``id`` (other YAML files are not profiles), the shipped folder left out."""
    shipped = DEFAULT_PROFILE_DIR.resolve()
    for directory in (folder, folder / "device_profiles"):
        if not directory.is_dir() or directory.resolve() == shipped:
            continue
        for path in sorted(directory.glob("*.yaml")):
            try:
                data = yaml.safe_load(path.read_text(encoding="utf-8"))
            except (OSError, yaml.YAMLError):
                continue
            if isinstance(data, dict) and "schema_version" in data and "id" in data:
                yield ProfileRef(path.stem, path, bool(data.get("abstract")))


def _resolve_raw(path: Path, seen: tuple[Path, ...]) -> tuple[dict[str, Any], tuple[Path, ...], list[str]]:
    """Raw merged data of ``path`` with its extends chain, plus the chain and texts."""
    path = path.resolve()
    if path in seen:
        cycle = " -> ".join(p.name for p in (*seen, path))
        raise ProfileError(str(path), [f"extends: circular chain {cycle}; remove one of the links"])
    data, text = _read_yaml(path)
    texts = [text]
    chain: tuple[Path, ...] = (path,)
    parent_name = data.pop("extends", None)
    if parent_name is not None:
        if not isinstance(parent_name, str):
            raise ProfileError(str(path), ["extends: must be a profile id or a file name (a string)"])
        parent_path = _parent_path(path, parent_name)
        parent, parent_chain, parent_texts = _resolve_raw(parent_path, (*seen, path))
        parent.pop("abstract", None)
        data = deep_merge(parent, data)
        chain += parent_chain
        texts += parent_texts
    eds_name = data.get("eds")
    if eds_name:
        data = _merge_eds(path, data, eds_name)
    return data, chain, texts


def _parent_path(path: Path, parent_name: str) -> Path:
    if parent_name.endswith(PROFILE_SUFFIXES):
        candidate = path.parent / parent_name
        if candidate.is_file():
            return candidate
        problem = f"{_where(path, 'extends')}extends: file {parent_name!r} not found next to the profile"
        raise ProfileError(str(path), [problem])
    try:
        return find_profile(parent_name, [path.parent, DEFAULT_PROFILE_DIR])
    except ProfileError:
        problem = f"{_where(path, 'extends')}extends: no profile {parent_name!r} in {path.parent}; check the id"
        raise ProfileError(str(path), [problem]) from None


def _where(path: Path, key: str) -> str:
    """'file:line: ' for a top-level key (for messages raised outside schema validation)."""
    line = _line_map(path.read_text(encoding="utf-8")).get((key,))
    return f"{path.name}:{line}: " if line else f"{path.name}: "


def _merge_eds(path: Path, data: dict[str, Any], eds_name: str) -> dict[str, Any]:
    from encoder_conformance.profile.eds import objects_from_eds  # canopen's EDS parser is only needed here

    eds_path = (path.parent / eds_name).resolve()
    try:
        eds_objects = objects_from_eds(eds_path)
    except (OSError, ValueError) as exc:
        raise ProfileError(str(path), [f"eds: cannot import {eds_path}: {exc}"]) from None
    return {**data, "objects": deep_merge(eds_objects, data.get("objects") or {})}


#: the profiles this process loaded, by file: a second load of one (a run's twin, forked from the run, loads the
#: profile the run loaded: 0.06-0.1 s of its start-up) takes the loaded one where every file of its chain still has
#: the bytes it was loaded from; a profile that merges an EDS is read again each time (the EDS is not in its chain)
_LOADED: dict[Path, LoadedProfile] = {}


def _chain_digest(chain: tuple[Path, ...]) -> str:
    digest = hashlib.sha256()
    for link in chain:
        digest.update(link.read_bytes())
    return digest.hexdigest()


def load_profile(name_or_path: str | Path, search_dirs: list[Path] | None = None) -> LoadedProfile:
    """Load, merge and validate a profile; raises ProfileError listing every problem."""
    path = find_profile(str(name_or_path), search_dirs)
    known = _LOADED.get(path.resolve())
    with contextlib.suppress(OSError):  # a file of its chain gone: loaded again, which says what is wrong
        if known is not None and _chain_digest(known.chain) == known.sha256:
            return known if known.path == path else replace(known, path=path)  # the path as this caller named it
    data, chain, _ = _resolve_raw(path, ())
    schema = data.get("schema_version")
    if schema != SCHEMA_VERSION:
        line = _line_map(path.read_text(encoding="utf-8")).get(("schema_version",))
        where = f"{path.name}:{line}: " if line else f"{path.name}: "
        raise ProfileError(
            str(path),
            [f"{where}schema_version: is {schema!r}; this tool reads schema_version {SCHEMA_VERSION}"],
        )
    if data.get("id") != path.stem:
        raise ProfileError(
            str(path), [f"{path.name}: id: is {data.get('id')!r}; it must equal the file name {path.stem!r}"]
        )
    try:
        profile = DeviceProfile.model_validate(data)
    except ValidationError as exc:
        raise ProfileError(str(path), _describe(exc, chain)) from None
    loaded = LoadedProfile(profile=profile, path=path, sha256=_chain_digest(chain), chain=chain)
    if not data.get("eds"):
        _LOADED[path.resolve()] = loaded
    return loaded


def _describe(exc: ValidationError, chain: tuple[Path, ...]) -> list[str]:
    """One line per validation error, naming the file (and line) that holds the key."""
    maps = [(p, _line_map(p.read_text(encoding="utf-8"))) for p in chain]
    problems: list[str] = []
    for error in exc.errors():
        loc = _clean_loc(tuple(error["loc"]))
        if error["type"] == "unknown_effect":
            loc = (*loc, "effect")
        where = ""
        for depth in range(len(loc), 0, -1):
            hit = next(((p, lines[loc[:depth]]) for p, lines in maps if loc[:depth] in lines), None)
            if hit:
                where = f"{hit[0].name}:{hit[1]}: "
                break
        problems.append(f"{where}{_format_path(loc)}: {_hint(error)}")
    return problems
