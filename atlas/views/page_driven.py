"""``atlas view`` of a driven pendulum's atlas: what its page needs to follow a clicked orbit
on the stroboscopic map P in the browser (``view_assets/driven.js``).

Per parameter point, read from the file and nothing rebuilt: the equation's parameters
(α, ω0, τ, A, Ω, φ), the steps per drive period N of ``/attractors`` (dt = T/N, T = 2π/Ω),
the most periods an orbit is followed (t_max / T, as the run's labels), the returns in a row
that decide each attractor's label (``confirm``), every attractor's points on P with its
capture radius, status and name (as the key names it), and the stored label of every grid
point. The script integrates the orbit with
the RK4 step of :mod:`atlas.kernels.driven` (the drive read at t, t + dt/2, t + dt of each
step from a table of the 2N + 1 half-step times of one period, the same table every period),
draws its returns to P and labels it by the rule of
:func:`atlas.kernels.driven.label_driven`.
"""

from __future__ import annotations

import base64
import hashlib
import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from atlas.layout import point_group
from atlas.models.driven.description import stored_confirm
from atlas.views.info_driven import attractor_names

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["orbit_data", "script", "script_hash"]

ASSET = Path(__file__).with_name("view_assets") / "driven.js"


def _targets(group: xr.Dataset) -> dict:
    """Every attractor's stored points on P (θ wrapped, θ̇; the NaN padding dropped), the
    attractor of each and their capture radius: the targets of the labelling rule."""
    theta, theta_dot, owner = [], [], []
    for i in range(group.sizes.get("attractor", 0)):
        th, v = group["theta"].values[i], group["theta_dot"].values[i]
        kept = np.isfinite(th) & np.isfinite(v)
        theta += th[kept].tolist()
        theta_dot += v[kept].tolist()
        owner += [i] * int(kept.sum())
    return {"theta": theta, "theta_dot": theta_dot, "attractor": owner}


def _blob(values: np.ndarray, dtype: str) -> str:
    """A little-endian array as base64 (the script reads it as a typed array)."""
    return base64.b64encode(np.ascontiguousarray(values, dtype).tobytes()).decode()


def _axis(values: np.ndarray) -> list:
    """[first, last, n] of a grid axis (the map's pixels are its points, evenly spaced)."""
    return [float(values[0]), float(values[-1]), int(values.size)]


def orbit_data(tree: xr.DataTree, ds: xr.Dataset, point: dict[str, float], t_max: float,
               statuses: dict[int, str]) -> dict | None:
    """What the page needs to follow an orbit at the parameter ``point`` (``ds``: its map;
    its ``/attractors`` node; None where the file has none for it): JSON-ready."""
    group = point_group(tree, "attractors", point)
    if group is None:
        return None
    n = int(group.attrs["steps_per_period"])
    period = 2.0 * math.pi / point["frequency"]
    return {
        "alpha": point["alpha"], "omega0": point["omega0"], "torque": point.get("torque", 0.0),
        "amplitude": point["amplitude"], "frequency": point["frequency"],
        "phase": point["phase"], "steps_per_period": n, "t_max": t_max,
        "max_periods": max(1, int(t_max / period)),
        "confirm": [int(c) for c in stored_confirm(group)],
        "radius": [float(r) for r in group["capture_radius"].values],
        "attractor_status": [int(s) for s in group["status"].values],
        "names": list(attractor_names(group).values()),
        "kinds": [str(kind) for kind in group["kind"].values],
        "targets": _targets(group),
        "grid": {"theta0": _axis(ds["theta0"].values),
                 "theta_dot0": _axis(ds["theta_dot0"].values)},
        "stored_attractor": _blob(ds["attractor"].transpose("theta_dot0", "theta0").values,
                                  "<i2"),
        "stored_status": _blob(ds["status"].transpose("theta_dot0", "theta0").values, "<i1"),
        "status_names": {str(k): v for k, v in statuses.items()},
    }


def script() -> str:
    """The driven page's script."""
    return ASSET.read_text(encoding="utf-8")


def script_hash(text: str) -> str:
    """The CSP hash ("sha256-…") that lets the page run ``text`` and nothing else."""
    return "sha256-" + base64.b64encode(hashlib.sha256(text.encode("utf-8")).digest()).decode()
