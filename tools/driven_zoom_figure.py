"""The driven pendulum's zoom sequence of docs/driven.md (docs/images/driven_zoom.png):
``atlas zoom`` of ``outputs/driven.h5`` (``make atlas CONFIG=configs/driven.yaml``) around
a boundary point at widths 1, 1e-2, 1e-4 and 1e-6, each window run with 201² orbits, drawn
side by side in the attractors' colours, each panel titled with its share of labels that
change at dt/2.

    python -m tools.driven_zoom_figure [--centre THETA THETA_DOT] [--out PNG]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

WIDTHS = ("1", "1e-2", "1e-4", "1e-6")
#: A grid point of configs/driven.yaml's atlas whose 3 × 3 neighbourhood holds all three
#: basins (the first such point from the middle of its 400² grid).
CENTRE = ("-0.6220195980791821", "0.25563909774436055")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--centre", nargs=2, default=CENTRE)
    parser.add_argument("--source", default="outputs/driven.h5")
    parser.add_argument("--out", default="docs/images/driven_zoom.png")
    args = parser.parse_args(argv)
    atlas_cli = [sys.executable, "-m", "atlas"]
    with tempfile.TemporaryDirectory(prefix="atlas-zoom-") as tmp:
        files = []
        for width in WIDTHS:
            config = Path(tmp) / f"z{width}.yaml"
            subprocess.run([*atlas_cli, "zoom", args.source, *args.centre, "--width", width,
                            "--num", "201", "-o", str(config)], check=True,
                           stdout=subprocess.DEVNULL)
            out = Path(tmp) / f"z{width}.h5"
            subprocess.run([*atlas_cli, "run", str(config), "-q", "-o", str(out)], check=True)
            files.append(out)
        _draw(files, args.out)
    print(f"wrote {args.out}")
    return 0


def _draw(files: list[Path], out: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import BoundaryNorm, ListedColormap

    import atlas
    from atlas.views.info_driven import attractor_key

    fig, axes = plt.subplots(1, len(files), figsize=(16, 5.0), layout="constrained")
    for ax, width, path in zip(axes, WIDTHS, files):
        tree = atlas.open(path)
        ds = tree.to_dataset(inherit=False)
        names, colours = attractor_key(tree["attractors"].to_dataset())
        k = ds["attractor"].values.astype(float)
        k[k < 0] = np.nan
        cmap = ListedColormap([colours[i] for i in sorted(colours)]).with_extremes(bad="white")
        norm = BoundaryNorm(np.arange(len(colours) + 1) - 0.5, cmap.N)
        th, v, w = ds.theta0.values, ds.theta_dot0.values, float(width)
        ax.pcolormesh((th - th[len(th) // 2]) / w, (v - v[len(v) // 2]) / w, k, cmap=cmap,
                      norm=norm, shading="nearest", rasterized=True)
        ax.set_aspect("equal")
        ax.set_title(f"width w = {w:g}\n{float(ds['changed_at_half_dt_fraction']):.0%} of its "
                     "labels change at dt/2", fontsize=10)
        ax.set_xlabel("(θ0 − θc) / w")
        if ax is axes[0]:
            ax.set_ylabel("(θ̇0 − θ̇c) / w")
        tree.close()
    handles = [plt.Rectangle((0, 0), 1, 1, color=colours[i]) for i in sorted(colours)]
    fig.legend(handles, [names[i] for i in sorted(names)], loc="outside upper center", ncol=3,
               frameon=False)
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    raise SystemExit(main())
