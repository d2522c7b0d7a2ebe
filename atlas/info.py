"""``atlas info``: what an atlas file holds, in a few lines, without loading its arrays."""

from __future__ import annotations

from pathlib import Path

from . import store


def info_lines(path: str | Path) -> list[str]:
    """Parameters, completeness, basin fractions ± standard error, separatrices, provenance."""
    path = Path(path)
    d = store.describe(path)
    attrs = d["attrs"]
    state = ("complete" if d["complete"] else
             f"partial: {d['tiles_done']} of {d['tiles']} tiles done (continue with --resume)")
    lines = [f"{path}: atlas file, {state}"]
    if d["complete"]:
        from .sweep import summary_lines

        tree = store.open_atlas(path)
        lines += ["  " + line for line in summary_lines(tree)]
        if "separatrices" in tree.children:
            from .separatrices import summary

            lines += ["  " + line for line in
                      summary(tree["separatrices"].to_dataset(inherit=False))]
    lines.append(f"  created   {attrs.get('created', '?')} by atlas "
                 f"{attrs.get('atlas_version', '?')} (numba {attrs.get('numba_version', '?')}, "
                 f"numpy {attrs.get('numpy_version', '?')})")
    lines.append(f"  method    {attrs.get('method', '?')}, dt = {attrs.get('dt', '?')} s, "
                 f"t_max = {attrs.get('t_max', '?')} s, config hash {attrs.get('config_hash')}")
    return lines
