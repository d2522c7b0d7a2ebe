"""atlas against a published Python peer, side by side: the basins of the driven pendulum
θ̈ + 0.2θ̇ + sin θ = 1.66 cos t (``configs/driven.yaml``: Wagemakers, Daza & Sanjuán, "How to
detect Wada basins", DCDS-B 26 (2021), Fig. 2(a)) labelled by pynamicalsys (M. Rolim Sales
et al., "pynamicalsys: A Python toolkit for the analysis of dynamical systems", Chaos,
Solitons and Fractals 201, 117269 (2025)) and by atlas, on the same n × n points of the
config's window and on the same machine:

    python -m tools.peer_driven --peer-python .venv-peers/bin/python --out outputs/peer_driven.json
    python -m tools.peer_driven --n 32          # a quick look

The peer runs in its own interpreter (``--peer-python``, a venv with pynamicalsys; it is
no dependency of atlas) on :mod:`tools.peer_driven_pynamicalsys`, with fixed-step RK4 at
atlas's step dt = T/200, a transient of ``--transient`` drive periods, then the centroid of
``--samples`` returns to the stroboscopic map P clustered by DBSCAN (its default eps 0.05).
Each cluster is named by the attractor of atlas's ``/attractors`` nearest to the final
states on P of a few of its members (θ compared mod 2π); a cluster whose members reach none
of them, or different ones, is unmatched and its points count as unlabelled by the peer.

atlas runs the same grid in process (:func:`atlas.run`, in memory), timed end to end after
one warm-up run (its attractors' search and the labels' check at dt/2 included), and its
labelling alone (:meth:`atlas.models.driven.points.DrivenPoint.label`). Where the two
disagree, up to ``--check`` points are followed by scipy's DOP853 at rtol 1e-11 (an
independent integrator of the exact equation) to say who is right.

Prints a short table and writes the numbers as JSON (``--out``): the label agreement (the
share of the points both label on which they agree, and the counts of points either leaves
unlabelled) and the speed ratio, peer seconds / atlas seconds, warm and cold.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
CONFIG = REPO / "configs" / "driven.yaml"
PEER_SCRIPT = Path(__file__).with_name("peer_driven_pynamicalsys.py")
#: Unlabelled, in both tools' label arrays here.
NONE = -1
#: The largest distance [rad and rad s⁻¹ as one unit] from a final state on P to an
#: attractor's point that names it: the attractors' points lie ≥ 1 apart here, the RK4 and
#: DOP853 maps' points 1e-4 apart.
MATCH_RADIUS = 0.1


def wrapped_distance(theta, theta_dot, theta_ref, theta_dot_ref) -> np.ndarray:
    """Euclidean distance in (θ [rad], θ̇ [rad s⁻¹]) with θ compared mod 2π; broadcasts."""
    d_theta = (np.asarray(theta) - theta_ref + math.pi) % (2.0 * math.pi) - math.pi
    return np.hypot(d_theta, np.asarray(theta_dot) - theta_dot_ref)


def nearest_attractor(theta, theta_dot, points_theta, points_theta_dot,
                      radius: float = MATCH_RADIUS) -> np.ndarray:
    """The index of the attractor whose point on P is nearest to each state (θ, θ̇) (1-D
    arrays), or NONE where none lies within ``radius``. ``points_theta``,
    ``points_theta_dot``: (attractor, sample) as in ``/attractors``, NaN-padded."""
    theta, theta_dot = np.atleast_1d(theta), np.atleast_1d(theta_dot)
    d = wrapped_distance(theta[:, None, None], theta_dot[:, None, None],
                         np.asarray(points_theta)[None], np.asarray(points_theta_dot)[None])
    d = np.where(np.isnan(d), np.inf, d).min(axis=2)  # (state, attractor)
    best = d.argmin(axis=1)
    return np.where(d[np.arange(len(best)), best] <= radius, best, NONE)


def name_clusters(clusters: dict, points_theta, points_theta_dot) -> dict[int, int]:
    """{peer cluster: atlas attractor or NONE}: the attractor every followed member of the
    cluster reaches (``clusters``: {label: {"theta": [...], "theta_dot": [...]}}, the members'
    final states on P); NONE where a member reaches none or the members disagree."""
    names = {}
    for label, c in clusters.items():
        reached = set(nearest_attractor(np.asarray(c["theta"]), np.asarray(c["theta_dot"]),
                                        points_theta, points_theta_dot).tolist())
        names[int(label)] = reached.pop() if len(reached) == 1 else NONE
    return names


def peer_attractors(labels, names: dict[int, int]) -> np.ndarray:
    """The peer's cluster labels (DBSCAN's −1: noise) as atlas attractor indices (NONE:
    noise or an unmatched cluster)."""
    labels = np.asarray(labels)
    table = {**{int(k): v for k, v in names.items()}, -1: NONE}
    return np.array([table.get(int(x), NONE) for x in labels.ravel()],
                    np.int64).reshape(labels.shape)


@dataclass(frozen=True)
class Agreement:
    """How two labellings of the same points compare: ``agree`` of the ``both`` points
    that both label; the points only atlas, only the peer, and neither left unlabelled."""

    points: int
    both: int
    agree: int
    atlas_only_unlabelled: int
    peer_only_unlabelled: int
    neither: int

    @property
    def share(self) -> float:
        """agree / both (NaN when no point is labelled by both)."""
        return self.agree / self.both if self.both else math.nan

    def as_dict(self) -> dict:
        return {**self.__dict__, "share": self.share}


def agreement(atlas_labels, peer_labels) -> Agreement:
    """Compare two label arrays of the same shape (NONE or negative: unlabelled)."""
    a, p = np.asarray(atlas_labels).ravel(), np.asarray(peer_labels).ravel()
    if a.shape != p.shape:
        raise ValueError(f"{a.shape} points against {p.shape}")
    la, lp = a >= 0, p >= 0
    both = la & lp
    return Agreement(points=int(a.size), both=int(both.sum()),
                     agree=int((both & (a == p)).sum()),
                     atlas_only_unlabelled=int((~la & lp).sum()),
                     peer_only_unlabelled=int((la & ~lp).sum()),
                     neither=int((~la & ~lp).sum()))


def grid_config(n: int, config: Path = CONFIG):
    """``config`` with an n × n grid over its window (everything else as written)."""
    import atlas

    cfg = atlas.load_config(config)
    g = cfg.grid
    axes = {name: getattr(g, name).model_copy(update={"num": n})
            for name in ("theta0", "theta_dot0")}
    return cfg.model_copy(update={"grid": g.model_copy(update=axes)})


def _timed(call) -> tuple:
    """call()'s result, its wall seconds and its CPU seconds (all this process's threads:
    on a shared machine the steadier measure of the work done)."""
    start, cpu_start = time.perf_counter(), time.process_time()
    out = call()
    return out, time.perf_counter() - start, time.process_time() - cpu_start


def run_atlas(cfg, repeats: int) -> tuple:
    """atlas's tree of ``cfg`` and its seconds, wall and CPU: the first (cold: Numba's cache
    as found) and the fastest later (warm) in-memory run end to end; then the labelling
    alone (warm)."""
    import atlas
    from atlas.models.driven import points as driven
    from atlas.pipeline.sweep import layout_of

    runs = [_timed(lambda: atlas.run(cfg, output=None, quiet=True)) for _ in range(1 + repeats)]
    tree = runs[0][0]
    warm = min(runs[1:], key=lambda r: r[1])
    layout = layout_of(cfg)
    point = driven.plan(cfg, layout, driven.begin(cfg, layout)).points[0]
    x0, v0 = layout.x0[None, :], layout.v0[:, None]
    point.label(x0, v0)  # compiled (cached) before it is timed
    _, labelling, labelling_cpu = _timed(lambda: point.label(x0, v0))
    return tree, {"cold_s": runs[0][1], "warm_s": warm[1], "labelling_s": labelling,
                  "cold_cpu_s": runs[0][2], "warm_cpu_s": warm[2],
                  "labelling_cpu_s": labelling_cpu}


def run_peer(peer_python: str, theta0, theta_dot0, cfg, args) -> dict:
    """The peer's result (:mod:`tools.peer_driven_pynamicalsys`) on the points."""
    p = cfg.pendulum
    job = {"theta0": np.asarray(theta0).tolist(), "theta_dot0": np.asarray(theta_dot0).tolist(),
           "alpha": p.alpha, "omega0": p.omega0, "amplitude": p.drive.amplitude,
           "frequency": p.drive.frequency, "steps_per_period": steps_per_period(cfg),
           "transient_periods": args.transient, "samples": args.samples, "eps": args.eps,
           "min_samples": 1, "repeats": 1 + args.repeats, "members": args.members}
    done = subprocess.run([peer_python, str(PEER_SCRIPT)], input=json.dumps(job), text=True,
                          capture_output=True, check=False)
    if done.returncode:
        raise SystemExit(f"the peer failed ({peer_python}):\n{done.stderr[-2000:]}")
    return json.loads(done.stdout)


def steps_per_period(cfg) -> int:
    """N, the fewest RK4 steps per drive period with T/N ≤ ``integrator.dt`` (atlas's rule,
    :func:`atlas.models.driven.points.drives`)."""
    period = 2.0 * math.pi / cfg.pendulum.drive.frequency
    return int(math.ceil(period / cfg.integrator.dt - 1e-9))


def exact_attractor(theta0: float, theta_dot0: float, drive: tuple[float, float, float, float],
                    points_theta, points_theta_dot, periods: int = 300,
                    rtol: float = 1e-11) -> int:
    """The attractor reached from (θ0 [rad], θ̇0 [rad s⁻¹]) by the exact equation
    θ̈ + 2αθ̇ + ω0² sin θ = A cos Ω t (``drive``: α [s⁻¹], ω0 [rad s⁻¹], A [rad s⁻²],
    Ω [rad s⁻¹]), followed by scipy's DOP853 (Hairer, Nørsett & Wanner, *Solving ODEs I*,
    §II.10) at rtol = atol = ``rtol`` for ``periods`` drive periods: the one whose points the
    last 4 returns to P all lie within MATCH_RADIUS of, else NONE."""
    from scipy.integrate import solve_ivp

    alpha, omega0, amplitude, frequency = drive
    period = 2.0 * math.pi / frequency

    def field(t, y):
        return (y[1], amplitude * math.cos(frequency * t) - omega0 ** 2 * math.sin(y[0])
                - 2.0 * alpha * y[1])

    returns = np.arange(periods - 3, periods + 1) * period
    sol = solve_ivp(field, (0.0, returns[-1]), (theta0, theta_dot0), method="DOP853",
                    rtol=rtol, atol=rtol, t_eval=returns)
    reached = set(nearest_attractor(sol.y[0], sol.y[1], points_theta,
                                    points_theta_dot).tolist())
    return reached.pop() if len(reached) == 1 else NONE


def exact_attractors(picked, theta0, theta_dot0, cfg, points_theta, points_theta_dot
                     ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`exact_attractor` of the points ``picked`` at rtol 1e-11 and, to tell whether
    that reference is itself settled, at 1e-12; one process per CPU."""
    from concurrent.futures import ProcessPoolExecutor
    from functools import partial

    p = cfg.pendulum
    drive = (p.alpha, p.omega0, p.drive.amplitude, p.drive.frequency)
    with ProcessPoolExecutor(os.cpu_count()) as pool:
        return tuple(np.array(list(pool.map(
            partial(exact_attractor, drive=drive, points_theta=points_theta,
                    points_theta_dot=points_theta_dot, rtol=rtol),
            theta0[picked], theta_dot0[picked])), np.int64) for rtol in (1e-11, 1e-12))


def check_disagreements(where, theta0, theta_dot0, atlas_labels, peer_labels, half_dt,
                        cfg, points_theta, points_theta_dot, count: int) -> dict:
    """Up to ``count`` disagreeing points (spread over them evenly) followed by DOP853:
    how often each tool has the exact equation's attractor, and how many of them atlas
    flags as changing at dt/2 (on the fractal boundary at this resolution)."""
    picked = where[np.linspace(0, len(where) - 1, min(count, len(where))).astype(int)] \
        if len(where) else where
    exact, tight = exact_attractors(picked, theta0, theta_dot0, cfg, points_theta,
                                    points_theta_dot)
    rows = [{"theta0": float(theta0[i]), "theta_dot0": float(theta_dot0[i]),
             "atlas": int(atlas_labels[i]), "peer": int(peer_labels[i]), "dop853": int(e),
             "dop853_rtol_1e-12": int(t), "changes_at_half_dt": int(half_dt[i])}
            for i, e, t in zip(picked, exact, tight)]
    return {"checked": len(rows),
            "atlas_right": sum(r["atlas"] == r["dop853"] for r in rows),
            "peer_right": sum(r["peer"] == r["dop853"] for r in rows),
            "neither_right": sum(r["dop853"] not in (r["atlas"], r["peer"]) for r in rows),
            "flagged_at_half_dt": sum(r["changes_at_half_dt"] for r in rows),
            "dop853_unsettled": sum(r["dop853"] != r["dop853_rtol_1e-12"] for r in rows),
            "points": rows}


def check_sample(theta0, theta_dot0, atlas_labels, peer_labels, half_dt, cfg, points_theta,
                 points_theta_dot, count: int, seed: int = 0) -> dict:
    """``count`` points drawn at random (fixed ``seed``) from all, followed by DOP853: each
    tool's share of labels that are the exact equation's, on the grid as a whole rather than
    where the two disagree."""
    picked = np.random.default_rng(seed).choice(len(theta0), min(count, len(theta0)),
                                                replace=False)
    exact, tight = exact_attractors(picked, theta0, theta_dot0, cfg, points_theta,
                                    points_theta_dot)
    return {"checked": len(picked),
            "dop853_unsettled": int(np.sum(exact != tight)),
            "atlas_right": int(np.sum(atlas_labels[picked] == exact)),
            "peer_right": int(np.sum(peer_labels[picked] == exact)),
            "exact_unlabelled": int(np.sum(exact == NONE)),
            "flagged_at_half_dt": int(half_dt[picked].sum()),
            "atlas_wrong_flagged": int(np.sum((atlas_labels[picked] != exact)
                                              & (half_dt[picked] == 1)))}


def compare(args) -> dict:
    """Both tools on the same n × n points; the numbers of the module's docstring."""
    load_before = os.getloadavg()[0]  # a shared machine's other work slows both tools
    cfg = grid_config(args.n, Path(args.config))
    tree, atlas_seconds = run_atlas(cfg, args.repeats)
    root = tree.to_dataset(inherit=False)
    found = tree["attractors"].to_dataset()
    points_theta, points_theta_dot = found["theta"].values, found["theta_dot"].values
    theta0, theta_dot0 = (a.ravel() for a in np.meshgrid(root["theta0"].values,
                                                         root["theta_dot0"].values))
    atlas_labels = root["attractor"].values.ravel().astype(np.int64)
    atlas_labels[atlas_labels < 0] = NONE

    peer = run_peer(args.peer_python, theta0, theta_dot0, cfg, args)
    names = name_clusters(peer["clusters"], points_theta, points_theta_dot)
    peer_labels = peer_attractors(peer["labels"], names)
    agreed = agreement(atlas_labels, peer_labels)
    half_dt = root["changes_at_half_dt"].values.ravel()
    disagree = np.flatnonzero((atlas_labels >= 0) & (peer_labels >= 0)
                              & (atlas_labels != peer_labels))
    warm = int(np.argmin(peer["seconds"][1:])) + 1 if len(peer["seconds"]) > 1 else None
    peer_warm = peer["seconds"][warm] if warm else math.nan
    peer_warm_cpu = peer["cpu_seconds"][warm] if warm else math.nan
    return {
        "points": int(theta0.size), "n": args.n, "config": str(args.config),
        "machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                    "processor": platform.processor() or platform.machine(),
                    "load_average_1min": [load_before, os.getloadavg()[0]]},
        "settings": {"integrator": "rk4", "steps_per_period": steps_per_period(cfg),
                     "dt_s": 2.0 * math.pi / cfg.pendulum.drive.frequency
                     / steps_per_period(cfg),
                     "peer_transient_periods": args.transient, "peer_samples": args.samples,
                     "peer_eps": args.eps, "peer_min_samples": 1,
                     "peer_state": "(cos θ, sin θ, θ̇)",
                     "atlas_t_max_s": cfg.integrator.t_max},
        "atlas": {**atlas_seconds,
                  "attractors": [{"period": int(p), "winding": int(w),
                                  "theta": th[~np.isnan(th)].tolist(),
                                  "theta_dot": v[~np.isnan(v)].tolist()}
                                 for p, w, th, v in zip(found["period"].values,
                                                        found["winding"].values,
                                                        points_theta, points_theta_dot)],
                  "t_trap_max_s": float(np.nanmax(root["t_trap"].values)),
                  "changes_at_half_dt": int(half_dt.sum())},
        "peer": {"cold_s": peer["seconds"][0], "warm_s": peer_warm,
                 "cold_cpu_s": peer["cpu_seconds"][0], "warm_cpu_s": peer_warm_cpu,
                 "clusters": {k: {"size": c["size"], "attractor": names[int(k)]}
                              for k, c in peer["clusters"].items()},
                 "noise": int(np.sum(np.asarray(peer["labels"]) < 0))},
        "agreement": agreed.as_dict(),
        "points_per_attractor": {
            name: np.bincount(labels[labels >= 0], minlength=len(points_theta)).tolist()
            for name, labels in (("atlas", atlas_labels), ("peer", peer_labels))},
        "disagreeing_flagged_at_half_dt": int(half_dt[disagree].sum()),
        "disagreements": check_disagreements(disagree, theta0, theta_dot0, atlas_labels,
                                             peer_labels, half_dt, cfg, points_theta,
                                             points_theta_dot, args.check),
        "random_sample": check_sample(theta0, theta_dot0, atlas_labels, peer_labels, half_dt,
                                      cfg, points_theta, points_theta_dot, args.sample),
        "speed_ratio": {"warm_end_to_end": peer_warm / atlas_seconds["warm_s"],
                        "warm_labelling": peer_warm / atlas_seconds["labelling_s"],
                        "cold_end_to_end": peer["seconds"][0] / atlas_seconds["cold_s"],
                        "warm_end_to_end_cpu": peer_warm_cpu / atlas_seconds["warm_cpu_s"],
                        "warm_labelling_cpu": peer_warm_cpu
                        / atlas_seconds["labelling_cpu_s"]},
    }


def table(result: dict) -> str:
    """The short printed summary of :func:`compare`'s result."""
    a, p, g, d = result["atlas"], result["peer"], result["agreement"], result["disagreements"]
    s = result["random_sample"]
    r = result["speed_ratio"]
    return "\n".join([
        f"{result['n']}² = {result['points']:,} points, {result['machine']['cpus']} CPUs",
        f"{'':24}{'atlas':>10}{'pynamicalsys':>14}{'ratio':>9}",
        f"{'warm, end to end [s]':24}{a['warm_s']:>10.2f}{p['warm_s']:>14.2f}"
        f"{r['warm_end_to_end']:>8.0f}×",
        f"{'atlas labelling only [s]':24}{a['labelling_s']:>10.2f}{p['warm_s']:>14.2f}"
        f"{r['warm_labelling']:>8.0f}×",
        f"{'cold (JIT included) [s]':24}{a['cold_s']:>10.2f}{p['cold_s']:>14.2f}"
        f"{r['cold_end_to_end']:>8.0f}×",
        f"{'warm, end to end [CPU s]':24}{a['warm_cpu_s']:>10.2f}{p['warm_cpu_s']:>14.2f}"
        f"{r['warm_end_to_end_cpu']:>8.0f}×",
        f"{'labelling only [CPU s]':24}{a['labelling_cpu_s']:>10.2f}{p['warm_cpu_s']:>14.2f}"
        f"{r['warm_labelling_cpu']:>8.0f}×",
        f"load average (1 min) before and after: "
        f"{' and '.join(f'{x:.1f}' for x in result['machine']['load_average_1min'])}",
        f"agreement: {g['agree']:,} of {g['both']:,} points both label "
        f"({100 * g['share']:.2f} %); unlabelled by atlas only {g['atlas_only_unlabelled']}, "
        f"by the peer only {g['peer_only_unlabelled']}, by neither {g['neither']}",
        f"disagreements: {g['both'] - g['agree']}, {result['disagreeing_flagged_at_half_dt']} "
        f"of them flagged by atlas as changing at dt/2; DOP853 on {d['checked']}: atlas "
        f"right {d['atlas_right']}, peer right {d['peer_right']}, neither "
        f"{d['neither_right']} (DOP853 at rtol 1e-12 differs on {d['dop853_unsettled']})",
        f"DOP853 on {s['checked']} points drawn at random: atlas right {s['atlas_right']}, "
        f"peer right {s['peer_right']} ({s['flagged_at_half_dt']} flagged at dt/2, "
        f"{s['atlas_wrong_flagged']} of them where atlas is wrong; DOP853 at rtol 1e-12 "
        f"differs on {s['dop853_unsettled']})",
    ])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=128, help="points per axis (default 128)")
    parser.add_argument("--peer-python", default=str(REPO / ".venv-peers" / "bin" / "python"),
                        help="an interpreter with pynamicalsys (default .venv-peers)")
    parser.add_argument("--config", default=str(CONFIG), help="a driven config (its window)")
    parser.add_argument("--transient", type=int, default=100,
                        help="the peer's transient [drive periods] (default 100)")
    parser.add_argument("--samples", type=int, default=10,
                        help="returns to P the peer averages (even: period 2; default 10)")
    parser.add_argument("--eps", type=float, default=0.05, help="DBSCAN eps (peer default)")
    parser.add_argument("--members", type=int, default=5,
                        help="members of each peer cluster followed to name it (default 5)")
    parser.add_argument("--repeats", type=int, default=1,
                        help="warm runs of each tool after its cold one (default 1)")
    parser.add_argument("--check", type=int, default=20,
                        help="disagreeing points followed by DOP853 (default 20)")
    parser.add_argument("--sample", type=int, default=40,
                        help="points drawn at random followed by DOP853 (default 40)")
    parser.add_argument("--out", help="write the numbers here as JSON")
    args = parser.parse_args(argv)
    result = compare(args)
    print(table(result))
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
