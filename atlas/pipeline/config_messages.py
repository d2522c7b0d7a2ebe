"""A config's validation errors as one line: the key, what is wrong, what was given, and for
an unknown key the key it most likely meant (difflib, as Python's own suggestions).
"""

from __future__ import annotations

import difflib
from typing import get_args

from pydantic import BaseModel, ValidationError

__all__ = ["first_error"]


def _key_path(loc: tuple) -> list:
    """The config keys of a pydantic error location, without the tags pydantic inserts for
    unions and validators (``function-before[...]``, ``list[float]``); the last part is
    always kept: it may be a user's unknown key (``theta-dot0``)."""
    keys = [p for p in loc[:-1] if not (isinstance(p, str) and ("[" in p or "-" in p))]
    return keys + list(loc[-1:])


def _section_model(annotation):
    """The config section (a pydantic model) an annotation holds, e.g. ``X | None`` → X."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    return next((m for m in map(_section_model, get_args(annotation)) if m is not None), None)


def _schema_keys(root: type[BaseModel], section: list) -> list[str]:
    """The keys the schema ``root`` allows in ``section`` (its keys from the top; [] for the
    top level): the field names of its model, [] where ``section`` is no section."""
    model = root
    for key in section:
        field = model.model_fields.get(key) if isinstance(key, str) else None
        model = None if field is None else _section_model(field.annotation)
        if model is None:
            return []
    return list(model.model_fields)


def _did_you_mean(root: type[BaseModel], loc: list, errors: list[dict]) -> str:
    """`` (did you mean KEY?)`` for the unknown key at ``loc``: the required key missing
    beside it that it most resembles (``n`` for ``num``), else the nearest key the schema
    allows there (difflib, as Python's own suggestions); "" where none is close."""
    section, key = loc[:-1], str(loc[-1])
    missing = [str(e["loc"][-1]) for e in errors
               if e["type"] == "missing" and _key_path(e["loc"])[:-1] == section]
    match = (difflib.get_close_matches(key, missing, n=1, cutoff=0.4)
             or difflib.get_close_matches(key, _schema_keys(root, section), n=1, cutoff=0.6))
    return f" (did you mean {match[0]}?)" if match else ""


def first_error(exc: ValidationError, root: type[BaseModel]) -> str:
    """One line from pydantic's errors of validating the schema ``root``: ``<key>: <problem>
    (got <value>)``. An unknown key comes first, with the key it most likely meant: a
    misspelt key is what makes the right one missing (``n:`` for ``num:`` says
    "grid.theta0.n: unknown key (did you mean num?)", not "grid.theta0.num: missing")."""
    errors = exc.errors()
    err = next((e for e in errors if e["type"] == "extra_forbidden"), errors[0])
    loc = _key_path(err["loc"])
    kind = err["type"]
    msg = err["msg"].removeprefix("Value error, ").replace("Input should be", "must be")
    if kind == "extra_forbidden":
        msg = "unknown key" + _did_you_mean(root, loc, errors)
    elif kind == "missing":
        msg = "missing"
    elif kind != "value_error":
        msg = f"{msg} (got {err.get('input')!r})"
    if isinstance(loc[-1:] and loc[-1], int):  # an item of a list: name it
        msg = f"item {loc.pop()}: {msg}"
    key = ".".join(str(p) for p in loc)
    return f"{key}: {msg}" if key else msg
