"""The models atlas knows, by name: the one place a config's ``model`` key or a file's
``model`` attribute becomes a :class:`~atlas.models.base.Model`.

The pendulum (:mod:`atlas.models.pendulum`) is registered here and is the default: a config
without ``model`` and a file without the attribute (every file written before models had
names) are the pendulum's; a pendulum config with a ``drive`` is the driven pendulum's
(:mod:`atlas.models.driven`). Another model registers itself with :func:`register` (a test's
model does, from the test's own folder); nothing else in atlas changes for it.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping

from atlas.models.base import Model
from atlas.models.driven.description import DRIVEN_PENDULUM
from atlas.models.pendulum.description import PENDULUM

__all__ = ["DEFAULT", "DRIVEN", "register", "lookup", "known", "of_attrs", "planner"]

#: The model of a config without a ``model`` key and of a file without the attribute.
DEFAULT = PENDULUM.name
#: The model of a pendulum config with a ``drive``: the periodically driven pendulum.
DRIVEN = DRIVEN_PENDULUM.name

_MODELS: dict[str, Model] = {PENDULUM.name: PENDULUM, DRIVEN_PENDULUM.name: DRIVEN_PENDULUM}


def register(model: Model) -> Model:
    """Make ``model`` known by its name (again, where a model of that name is registered:
    the new one replaces it). Returns it."""
    _MODELS[model.name] = model
    return model


def known() -> tuple[str, ...]:
    """The names of every registered model."""
    return tuple(_MODELS)


def lookup(name: str) -> Model:
    """The model called ``name``; ValueError (one line naming the known ones) otherwise."""
    try:
        return _MODELS[name]
    except (KeyError, TypeError):
        raise ValueError(f"model {str(name)[:40]!r} is not one atlas knows (known: "
                         f"{', '.join(_MODELS)})") from None


def of_attrs(attrs: Mapping) -> Model:
    """The model of a file (or dataset) from its ``model`` attribute (bytes decoded; the
    pendulum where absent). ValueError for a name no registered model has."""
    name = attrs.get("model", DEFAULT)
    if isinstance(name, bytes):
        name = name.decode("utf-8", "replace")
    return lookup(name)


def planner(model: Model):
    """The model's planner module (:class:`~atlas.models.base.Planner`), imported on first
    use: only the pipeline asks for it, so that reading a file imports no physics."""
    return importlib.import_module(model.planner)
