"""A stability study's 1-D figures say what they mean on a slide: bifurcation lines that
coincide on the page are one line whose one label names each, labels never overlap, and a
point without an exact value (the saddle-node, a failure) is a band across the whole height,
named in the legend, never a marker at a value. Read back from the drawn Axes."""

from __future__ import annotations

import itertools

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import xarray as xr  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from atlas.stability import bifurcations as bif  # noqa: E402
from atlas.views.study_plot import _NAN_BAND_PT, _shock_curve, _stability_curves  # noqa: E402
from atlas.views.style import CURVE_SIZE  # noqa: E402

ALPHA, OMEGA0 = 0.05, 1.0


def _study(torque, status=None, **bifurcations) -> xr.Dataset:
    """A 1-D study over ``torque`` (rest state and running shares that sum to 1; NaN where
    ``status`` flags a point), with the bifurcation values given."""
    n = torque.size
    status = np.zeros(n, np.int8) if status is None else np.asarray(status, np.int8)
    rest = np.where(status == 0, 1.0 - torque / torque.max(), np.nan)
    return xr.Dataset(
        {"basin_stability": (("k", "torque"), [0.3 * rest, 0.7 * rest]),
         "running_stability": ("torque", 1.0 - rest),
         "minimal_fatal_shock": (("k", "torque"), [2.0 * rest, 3.0 * rest]),
         "point_status": ("torque", status),
         **{name: ((), value) for name, value in bifurcations.items()}},
        coords={"k": [0, 1], "torque": torque, "alpha": ALPHA, "omega0": OMEGA0},
        attrs={"window_theta": [-np.pi, np.pi], "window_theta_dot": [-3.0, 3.0]})


def _draw(draw, ds):
    fig = Figure(figsize=CURVE_SIZE)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    draw(ds, "torque")(ax)
    fig.tight_layout()
    fig.canvas.draw()
    return ax


def _vertical_lines(ax) -> list[float]:
    """The x of every vertical line across the axes (an axvline: two points, one x)."""
    return sorted(float(ln.get_xdata()[0]) for ln in ax.lines
                  if len(ln.get_xdata()) == 2 and ln.get_xdata()[0] == ln.get_xdata()[1])


def _no_two_overlap(ax) -> None:
    boxes = [t.get_window_extent() for t in ax.texts]
    for a, b in itertools.combinations(boxes, 2):
        assert not a.overlaps(b), (a, b)


@pytest.mark.parametrize("draw", [_stability_curves, _shock_curve])
def test_coinciding_bifurcations_are_one_line_with_one_label(draw):
    """At α = 0.05 the focus–node torque √(ω0⁴ − α⁴) lies 3·10⁻⁶ below the saddle-node ω0²
    (one line on any page): one line there, one label naming both with their values; the
    homoclinic torque its own line and label; no two labels overlap."""
    focus_node = bif.focus_node_torque(ALPHA, OMEGA0)
    saddle_node = bif.saddle_node_torque(OMEGA0)
    assert 0 < saddle_node - focus_node < 1e-5
    ds = _study(np.linspace(0.0, 1.0, 101), homoclinic_torque=0.127,
                saddle_node_torque=saddle_node, focus_node_torque=focus_node)
    ax = _draw(draw, ds)
    assert _vertical_lines(ax) == [0.127, saddle_node]
    texts = [t.get_text() for t in ax.texts]
    assert len(texts) == 2
    (both,) = [t for t in texts if "saddle-node" in t]
    assert f"focus → node τ = {focus_node:.10g}" in both and f"= {saddle_node:.10g}" in both
    _no_two_overlap(ax)


def test_lines_apart_on_the_page_keep_their_own_labels_apart():
    """Two bifurcations 0.02 apart on a range of 1 (some 10 pt on the page): two lines,
    two labels, on rows of their own (they would overlap on one row)."""
    ds = _study(np.linspace(0.0, 1.0, 101), homoclinic_torque=0.95, focus_node_torque=0.97)
    ax = _draw(_stability_curves, ds)
    assert _vertical_lines(ax) == [0.95, 0.97]
    assert len(ax.texts) == 2 and len({t.xyann[1] for t in ax.texts}) == 2
    _no_two_overlap(ax)


@pytest.mark.parametrize("draw", [_stability_curves, _shock_curve])
def test_a_point_without_exact_value_is_a_band_never_a_value(draw):
    """The saddle-node (last point) and a failed point (NaN numbers): nothing drawn at any
    y there (the old cross at y = 0 read as a basin stability of 0); a band over the whole
    height at each, at least _NAN_BAND_PT wide, named in the legend by what it is."""
    torque = np.linspace(0.0, 1.0, 101)
    status = np.zeros(101, np.int8)
    status[[40, 100]] = 2, 1
    ax = _draw(draw, _study(torque, status, saddle_node_torque=1.0))
    for ln in ax.lines:
        x, y = np.asarray(ln.get_xdata(), float), np.asarray(ln.get_ydata(), float)
        if len(x) == 2 and x[0] == x[1]:  # a bifurcation line, across the axes
            continue
        at = np.isin(x, torque[[40, 100]])
        assert not np.isfinite(y[at]).any(), (ln.get_label(), x[at], y[at])
    frame = ax.get_window_extent()
    bands = [p.get_window_extent() for p in ax.patches]
    assert len(bands) == 2
    to_pixels = ax.figure.dpi / 72.0
    for value in torque[[40, 100]]:
        px = ax.transData.transform((value, 0.0))[0]
        (band,) = [b for b in bands if b.x0 <= px <= b.x1]
        assert band.y0 == pytest.approx(frame.y0) and band.y1 == pytest.approx(frame.y1)
        assert min(band.x1, frame.x1) - band.x0 >= 0.5 * _NAN_BAND_PT * to_pixels
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels.count("no exact value (saddle-node / failed)") == 1
