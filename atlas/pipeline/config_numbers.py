"""Numbers in a config: π expressions (``3pi``, ``-pi/2``, ``2*pi``, ``0.5pi``), and a
parameter's value as a number, a list or a range ``{start, stop, num}`` (inclusive, evenly
spaced): the annotated types :data:`Number` and :data:`Numbers` the config's sections
validate with (:mod:`atlas.pipeline.config_sections`).

A π expression is evaluated from its syntax tree (numbers, ``pi``, + − × ÷ and parentheses
only: never ``eval``); anything else is a ValueError naming what was given.
"""

from __future__ import annotations

import ast
import math
import operator
import re
from typing import Annotated

from pydantic import BeforeValidator

__all__ = ["parse_pi_expression", "Number", "Numbers", "MAX_RANGE_NUM"]

_BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
           ast.Div: operator.truediv}
_UNARY = {ast.USub: operator.neg, ast.UAdd: operator.pos}
_IMPLICIT_PI = re.compile(r"(\d|\.)\s*(?=pi\b)")


def _evaluate(node: ast.AST) -> float:
    if isinstance(node, ast.Expression):
        return _evaluate(node.body)
    if isinstance(node, ast.Constant) and type(node.value) in (int, float):
        return float(node.value)
    if isinstance(node, ast.Name) and node.id in ("pi", "π"):
        return math.pi
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        return _BINARY[type(node.op)](_evaluate(node.left), _evaluate(node.right))
    if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
        return _UNARY[type(node.op)](_evaluate(node.operand))
    raise ValueError("only numbers, pi, + - * / and parentheses are allowed")


def parse_pi_expression(text: str) -> float:
    """Evaluate a number written with π: ``"3pi"`` → 3π, ``"-pi/2"``, ``"2*pi"``, ``"1.5"``.

    Only numbers, ``pi`` (or ``π``), + − × ÷ and parentheses are accepted; implicit
    multiplication is allowed only directly before ``pi``.
    """
    source = _IMPLICIT_PI.sub(r"\1*", text.strip().replace("π", "pi"))
    try:
        value = _evaluate(ast.parse(source, mode="eval"))
    except (SyntaxError, ValueError, ZeroDivisionError) as exc:
        detail = "division by zero" if isinstance(exc, ZeroDivisionError) else str(exc)
        if isinstance(exc, SyntaxError):
            detail = "not a number or π expression (e.g. 3pi, -pi/2, 2*pi)"
        raise ValueError(f"cannot read {text!r}: {detail}") from None
    if not math.isfinite(value):
        raise ValueError(f"{text!r} is not a finite number")
    return value


def _number(value):
    """Accept ints, floats and π-expression strings; refuse bools, NaN and infinities."""
    if isinstance(value, bool):
        raise ValueError("expected a number, got a boolean")
    if isinstance(value, str):
        value = parse_pi_expression(value)
    if isinstance(value, (int, float)):
        try:
            value = float(value)
        except OverflowError:  # an integer beyond double precision
            raise ValueError("must be a finite number, got an integer beyond the range of "
                             "double precision") from None
        if not math.isfinite(value):
            raise ValueError(f"must be a finite number, got {value}")
        return value
    raise ValueError(f"expected a number or π expression, got {type(value).__name__}")


#: The most values a range {start, stop, num} of a pendulum parameter may hold.
MAX_RANGE_NUM = 1 << 20


def _parameter_range(value: dict) -> list[float]:
    """A range ``{start, stop, num}`` of a pendulum parameter: ``num`` values evenly spaced
    from ``start`` to ``stop`` inclusive (numpy's linspace: both ends exact), num ≥ 2 and
    start < stop."""
    unknown = sorted(set(value) - {"start", "stop", "num"})
    if unknown:
        raise ValueError(f"a range has the keys start, stop and num; unknown key {unknown[0]!r}")
    missing = [key for key in ("start", "stop", "num") if key not in value]
    if missing:
        raise ValueError(f"a range needs start, stop and num; {missing[0]} is missing")
    start, stop, num = _number(value["start"]), _number(value["stop"]), value["num"]
    if isinstance(num, bool) or not isinstance(num, int):
        raise ValueError(f"range num must be an integer, got {num!r}")
    if not 2 <= num <= MAX_RANGE_NUM:
        raise ValueError(f"range num must be between 2 and {MAX_RANGE_NUM}, got {num}")
    if not start < stop:
        raise ValueError(f"range start ({start:g}) must be less than stop ({stop:g})")
    import numpy as np

    return [float(v) for v in np.linspace(start, stop, num)]


def _number_or_list(value):
    if isinstance(value, dict):
        return _parameter_range(value)
    if isinstance(value, list):
        numbers = []
        for i, item in enumerate(value):
            try:
                numbers.append(_number(item))
            except ValueError as exc:
                raise ValueError(f"item {i}: {exc}") from None
        return numbers
    return _number(value)


Number = Annotated[float, BeforeValidator(_number)]
#: A number, or a list of numbers (or a range {start, stop, num}) for a parameter atlas.
Numbers = Annotated[float | list[float], BeforeValidator(_number_or_list)]
