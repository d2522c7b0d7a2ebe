"""Reading a config file: YAML without its traps (a key given twice, anchors and aliases,
a file too large), and what to say where the file given is no config at all (an atlas, a
study, another HDF5 file).
"""

from __future__ import annotations

from pathlib import Path

import yaml

from atlas.errors import ConfigError

__all__ = ["parse_yaml", "not_a_config", "MAX_CONFIG_BYTES"]

#: Largest config file read [bytes]: a config is a few hundred bytes, a long parameter list a
#: few kilobytes.
MAX_CONFIG_BYTES = 1 << 20


class _StrictLoader(yaml.SafeLoader):
    """YAML's safe loader that refuses a key given twice in one mapping (naming the key and
    both lines) instead of letting the last one win silently."""

    def construct_mapping(self, node, deep=False):
        seen = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            line = key_node.start_mark.line + 1
            try:
                hash(key)
            except TypeError:  # SafeLoader itself refuses an unhashable key, with its line
                continue
            if key in seen:
                raise ConfigError(f"line {line}: key {key!r} given twice (first on line "
                                  f"{seen[key]})")
            seen[key] = line
        return super().construct_mapping(node, deep=deep)


def parse_yaml(text: str):
    """The YAML document in ``text``, or one ConfigError line ("line N: …"). Anchors and
    aliases are refused before anything is built (configs never need them, and nested
    aliases expand exponentially: the "billion laughs"), so reading takes time linear in the
    file's size."""
    try:
        for event in yaml.parse(text, Loader=yaml.SafeLoader):
            if isinstance(event, yaml.AliasEvent) or getattr(event, "anchor", None):
                line = event.start_mark.line + 1
                raise ConfigError(f"line {line}: YAML anchors and aliases (&, *) are not "
                                  "allowed in a config")
        return yaml.load(text, Loader=_StrictLoader)  # noqa: S506 (a SafeLoader subclass)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}: " if mark is not None else ""
        problem = getattr(exc, "problem", None) or "invalid YAML"
        raise ConfigError(f"{where}YAML syntax error: {problem}") from None


def not_a_config(path: Path) -> str | None:
    """The hint for an atlas file given where a config is expected (``atlas run OUT.h5``),
    or None where ``path`` is no atlas file: asked only once the file failed to read as a
    config, so a config is read without importing the store."""
    from atlas.store.reader import is_atlas_file
    from atlas.store.study import is_study_file

    if is_atlas_file(path):
        return (f"{path}: an atlas file, not a config; look at it with `atlas info {path}` "
                "(`atlas run` reads a YAML config such as configs/default.yaml)")
    if is_study_file(path):
        return (f"{path}: a stability study, not a config; look at it with "
                f"`atlas info {path}` (`atlas stability` reads a YAML config such as "
                "configs/swing_stability.yaml)")
    from atlas.store.formats import FORMATS

    fmt = next((fmt for fmt in FORMATS.values() if fmt.recognises(path)), None)
    return f"{path}: {fmt.kind}, not a YAML config" if fmt is not None else None
