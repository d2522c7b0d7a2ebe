"""Attractors of the driven pendulum's stroboscopic map P followed across a swept parameter.

At each point of a 1-D sweep (of A, Ω, α, τ, …) :func:`~atlas.models.driven.attractors.
find_attractors` gives a list of attractors in no order that survives a change of the
parameter. Consecutive points' attractors are matched here, as Attractors.jl's
``match_statespacesets!``/``MatchBySSSetDistance`` does (Datseris, Luiz & Datseris,
*Chaos* 33, 073151, 2023), so that each attractor keeps one **global id** along the sweep:

- the **distance** between two attractors is the set distance between their points on P:
  the least Euclidean distance between a point of one and a point of the other, θ
  differences wrapped to [−π, π) (θ [rad] and θ̇ [rad s⁻¹] as one unit). A periodic
  orbit's p points are its set (so a period-1 orbit and the period-2 orbit it doubles into
  are near: the new orbit's points straddle the old one's); a chaotic attractor's is its
  recorded cloud (:data:`MATCH_POINTS` of them at most).
- consecutive points' attractors are paired by the assignment of least total distance
  (the Hungarian method, :func:`scipy.optimize.linear_sum_assignment`) among the pairs
  nearer than the **threshold** (:data:`THRESHOLD`); a pair farther apart is no match.
- where, between two points, some attractors have no match on either side, the step is
  halved (:func:`bridge`): the attractors found at the midpoint are matched to both ends,
  so that an attractor that moved farther than the threshold over the whole step is
  followed through the halves (down to :data:`BRIDGE_DEPTH` halvings).
- an attractor of the later point with no match is **born** (it gets the next unused
  global id; ids are never reused), one of the earlier point with no match **dies**; a
  matched pair whose kind or period differs (a period doubling, a periodic orbit turning
  chaotic) is a **period change**. These are the **events** between the two points.

Each event is then located in the parameter by bisection (:func:`locate`): at the midpoint
of its bracket the attractors are found again and matched to the bracket's ends, and the
half of the bracket on whose side the midpoint looks like the later point is dropped…
until the bracket is narrower than ``rtol`` times the parameter (or ``max_steps``
bisections). The event lies in the final bracket *as the finite search of find_attractors
sees it*: an attractor whose basin misses every seed of the search is not seen, so a
located birth is where the search first finds it, at or after the bifurcation itself.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from atlas.models.driven.attractors import Attractor, wrap

__all__ = ["THRESHOLD", "MATCH_POINTS", "BRIDGE_DEPTH", "EVENT_KINDS", "Event", "Located",
           "set_distance", "distances", "match", "bridge", "changes", "follow", "locate"]

#: Two attractors of consecutive points farther apart than this (set distance, θ [rad] and
#: θ̇ [rad s⁻¹] as one unit) are not the same attractor.
THRESHOLD = 0.5
#: The most points of a chaotic cloud compared (evenly thinned beyond).
MATCH_POINTS = 500
#: Halvings of a step through which an attractor that moved farther than the threshold is
#: followed (:func:`bridge`): a step of 0.05 in A is bridged by steps of 0.00625.
BRIDGE_DEPTH = 3
#: The events between consecutive points, as stored (flag values 0, 1, 2).
EVENT_KINDS = ("birth", "death", "period_change")


def _thin(points: np.ndarray, most: int = MATCH_POINTS) -> np.ndarray:
    if len(points) <= most:
        return points
    return points[np.linspace(0, len(points) - 1, most).astype(np.int64)]


def set_distance(a: np.ndarray, b: np.ndarray) -> float:
    """The least distance between the points a (n, 2) and b (m, 2) on P, θ differences
    wrapped (module docstring); inf where either is empty."""
    a, b = _thin(np.asarray(a, np.float64)), _thin(np.asarray(b, np.float64))
    if not len(a) or not len(b):
        return math.inf
    d_theta = wrap(a[:, None, 0] - b[None, :, 0])
    return float(np.hypot(d_theta, a[:, None, 1] - b[None, :, 1]).min())


def distances(before: list[Attractor], after: list[Attractor]) -> np.ndarray:
    """The set distances (len(before), len(after)) between two lists of attractors."""
    return np.array([[set_distance(a.points, b.points) for b in after] for a in before]
                    ).reshape(len(before), len(after))


def match(before: list[Attractor], after: list[Attractor], threshold: float = THRESHOLD
          ) -> dict[int, int]:
    """{index in ``after``: index in ``before``} of the pairs of least total distance among
    those nearer than ``threshold``."""
    from scipy.optimize import linear_sum_assignment

    if not before or not after:
        return {}
    d = distances(before, after)
    far = ~(d <= threshold)
    cost = np.where(far, 1e6 + threshold, d)  # a far pair is taken only where nothing else
    rows, cols = linear_sum_assignment(cost)
    return {int(j): int(i) for i, j in zip(rows, cols) if not far[i, j]}


def _signature(a: Attractor) -> tuple[str, int]:
    return a.kind, int(a.period)


@dataclass(frozen=True)
class Event:
    """A change between sweep points ``step`` and ``step + 1``: ``kind`` (one of
    :data:`EVENT_KINDS`) of the attractor with global id ``attractor``; ``before``/``after``
    its index in each point's list (−1: not there); ``period_before``/``period_after``
    (−1: not there; 0: chaotic)."""

    step: int
    kind: str
    attractor: int
    before: int
    after: int
    period_before: int
    period_after: int


def bridge(find: Callable[[float], list[Attractor]], lo: float, hi: float,
           at_lo: list[Attractor], at_hi: list[Attractor], threshold: float = THRESHOLD,
           depth: int = BRIDGE_DEPTH) -> dict[int, int]:
    """:func:`match` of two consecutive points' attractors, where an attractor moved
    farther than the threshold between them followed through midpoints: where some of
    ``at_lo`` have no match and some of ``at_hi`` neither, the attractors are found at the
    midpoint (``find``) and each half is bridged in turn, down to ``depth`` halvings; a
    dying attractor chained through the midpoints to a born one is the same attractor."""
    pairs = match(at_lo, at_hi, threshold)
    dying = set(range(len(at_lo))) - set(pairs.values())
    born = set(range(len(at_hi))) - set(pairs)
    if depth <= 0 or not dying or not born:
        return pairs
    m = 0.5 * (lo + hi)
    mid = find(m)
    left = bridge(find, lo, m, at_lo, mid, threshold, depth - 1)  # mid index -> lo index
    right = bridge(find, m, hi, mid, at_hi, threshold, depth - 1)  # hi index -> mid index
    for j, k in sorted(right.items()):
        i = left.get(k)
        if j in born and i in dying:
            pairs[j] = i
            dying.discard(i)
    return pairs


def changes(before: list[Attractor], after: list[Attractor], pairs: dict[int, int],
            step: int = -1, ids_before=None, ids_after=None) -> list[Event]:
    """The events between two consecutive points whose attractors are paired by ``pairs``
    ({index in ``after``: index in ``before``}): births, deaths, period changes, in this
    order, each by its attractor's global id (``ids_before``, ``ids_after``; −1 where not
    given)."""
    def gid(ids, i):
        return -1 if ids is None else int(ids[i])

    out = [Event(step, "birth", gid(ids_after, j), -1, j, -1, int(after[j].period))
           for j in range(len(after)) if j not in pairs]
    paired = set(pairs.values())
    out += [Event(step, "death", gid(ids_before, i), i, -1, int(before[i].period), -1)
            for i in range(len(before)) if i not in paired]
    out += [Event(step, "period_change", gid(ids_after, j), i, j, int(before[i].period),
                  int(after[j].period))
            for j, i in sorted(pairs.items()) if _signature(before[i]) != _signature(after[j])]
    out.sort(key=lambda e: (EVENT_KINDS.index(e.kind), e.attractor))
    return out


def follow(found: list[list[Attractor]], threshold: float = THRESHOLD,
           pairs: dict[int, dict[int, int]] | None = None
           ) -> tuple[list[np.ndarray], list[Event]]:
    """Global ids along a sweep: (per point the id of each of its attractors (int64), the
    events between consecutive points in order of step, then kind, then id). The first
    point's attractors get ids 0, 1, … in their order; a born attractor the next unused id.
    ``pairs``: {step: the pairs of points step − 1 and step, as :func:`match` gives them},
    where they were bridged (:func:`bridge`); else they are matched here."""
    ids: list[np.ndarray] = []
    events: list[Event] = []
    next_id = 0
    for step, now in enumerate(found):
        if step == 0:
            ids.append(np.arange(len(now), dtype=np.int64))
            next_id = len(now)
            continue
        before = found[step - 1]
        paired = (pairs or {}).get(step)
        paired = match(before, now, threshold) if paired is None else paired
        here = np.empty(len(now), np.int64)
        for j in range(len(now)):
            if j in paired:
                here[j] = ids[-1][paired[j]]
            else:
                here[j] = next_id
                next_id += 1
        events += changes(before, now, paired, step - 1, ids[-1], here)
        ids.append(here)
    return ids, events


@dataclass
class Located:
    """Where an event was located: the bracket [``lo``, ``hi``] of the parameter it lies in,
    ``value`` its middle, the ``steps`` of bisection taken."""

    lo: float
    hi: float
    steps: int
    value: float = field(init=False)

    def __post_init__(self):
        self.value = 0.5 * (self.lo + self.hi)

    @property
    def error(self) -> float:
        """Half the bracket: how far the event may lie from ``value``."""
        return 0.5 * (self.hi - self.lo)


def locate(find: Callable[[float], list[Attractor]], lo: float, hi: float,
           at_lo: list[Attractor], at_hi: list[Attractor], events: list[Event], *,
           threshold: float = THRESHOLD, rtol: float = 1e-4, max_steps: int = 16
           ) -> list[Located]:
    """Each of ``events`` (between the sweep's points at parameter ``lo`` and ``hi``, whose
    attractors are ``at_lo`` and ``at_hi``) located by bisection: ``find(value)`` gives the
    attractors at a midpoint (each value found once, whichever event asks), which are
    matched to the bracket's ends (module docstring) to decide which half holds the event:

    - a birth: the midpoint has the born attractor (matched to it at the bracket's upper
      end) → the birth is below the midpoint;
    - a death: the midpoint has the dying attractor (matched at the lower end) → above;
    - a period change: the attractor matched at the lower end keeps its kind and period at
      the midpoint → above; else below.

    The attractor followed is updated to the midpoint's as the bracket closes in (it moves
    with the parameter). Bisection stops when hi − lo ≤ ``rtol`` · max(|lo|, |hi|) or after
    ``max_steps``."""
    cache: dict[float, list[Attractor]] = {}

    def at(value: float) -> list[Attractor]:
        if value not in cache:
            cache[value] = find(value)
        return cache[value]

    out = []
    for event in events:
        a, b = lo, hi
        set_a, set_b = at_lo, at_hi
        i, j = event.before, event.after  # the followed attractor at each end
        steps = 0
        while b - a > rtol * max(abs(a), abs(b)) and steps < max_steps:
            m = 0.5 * (a + b)
            mid = at(m)
            steps += 1
            if event.kind == "birth":
                k = next((k for k, jj in match(set_b, mid, threshold).items() if jj == j),
                         None)  # the midpoint's attractor matched to the born one
                if k is None:
                    a, set_a = m, mid
                else:
                    b, set_b, j = m, mid, k
                continue
            k = next((k for k, ii in match(set_a, mid, threshold).items() if ii == i), None)
            if event.kind == "death":
                if k is None:
                    b, set_b = m, mid
                else:
                    a, set_a, i = m, mid, k
            elif k is not None and _signature(mid[k]) == _signature(set_a[i]):
                a, set_a, i = m, mid, k
            else:
                b, set_b = m, mid
        out.append(Located(a, b, steps))
    return out
