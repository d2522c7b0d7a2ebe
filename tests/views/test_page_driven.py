"""``atlas view`` of a driven pendulum's atlas: a click on a map follows the orbit on the
stroboscopic map P in the browser, as atlas does.

The page's script (``atlas/views/view_assets/driven.js``) integrates the orbit with its own
RK4 code; here, in headless Chromium (``tests/browser.py``; skipped with the reason where
there is none), its returns to P are compared with the kernel's P iterates
(:func:`atlas.kernels.driven.sample`) and its labels with :meth:`DrivenPoint.label` of the
point the file describes (the stored attractors' points, capture radii and statuses, the
file's N and t_max), and with the file's own labels at every grid point of every parameter
point. Without a browser: the page is self-contained, runs one script by its hash, and
carries each point's data.
"""

from __future__ import annotations

import base64
import hashlib
import json
import math
import re
from html import unescape
from pathlib import Path

import numpy as np
import pytest

import atlas
from atlas.kernels import driven as kernels
from atlas.layout import at_point, point_group, points
from atlas.models.driven.description import UNRESOLVED
from atlas.models.driven.points import DrivenPoint, stored_point
from atlas.views.info_driven import attractor_names
from atlas.views.page import write_view
from tests.browser import (
    find_browser,
    headless_page,
    playwright_missing,
    skip_without_browser,
)
from tests.helpers import write_config

pytestmark = pytest.mark.slow  # an atlas run of two parameter points, a browser

BROWSER = find_browser()
NO_PLAYWRIGHT = playwright_missing()
needs_browser = skip_without_browser()
REPO = Path(__file__).resolve().parents[2]

CONFIG = """\
name: driven page
pendulum:
  alpha: 0.1
  omega0: 1.0
  drive: {{amplitude: [1.66, 1.2], frequency: 1.0}}
grid:
  theta0: {{start: -pi, stop: pi, num: 8}}
  theta_dot0: {{start: -2, stop: 4, num: 8}}
integrator: {{dt: pi/100, t_max: 320}}
output: {output}
"""


@pytest.fixture(scope="module")
def driven(tmp_path_factory):
    """An 8 × 8 atlas of the Wada case and of a weaker drive (t_max: 50 periods), its page."""
    tmp = tmp_path_factory.mktemp("driven_page")
    cfg = atlas.load_config(write_config(tmp / "d.yaml", CONFIG.format(output=tmp / "d.h5")))
    atlas.run(cfg, quiet=True)
    return {"h5": tmp / "d.h5", "page": write_view(tmp / "d.h5")}


def _point(tree, params: dict, t_max: float) -> DrivenPoint:
    """The labelling of one parameter point as the run made it, from what the file stores."""
    return stored_point(point_group(tree, "attractors", params), params, t_max)


@pytest.fixture(scope="module")
def stored(driven):
    """Per parameter point: its map and its :class:`DrivenPoint`, which labels the grid as
    the file stores it (so it is the run's)."""
    tree = atlas.open(driven["h5"])
    ds = tree.to_dataset(inherit=False)
    out = []
    for params in points(ds):
        here = at_point(ds, params)
        point = _point(tree, params, float(ds.attrs["t_max"]))
        theta0, theta_dot0 = here["theta0"].values, here["theta_dot0"].values
        attractor, status, _, _ = point.label(theta0[None, :], theta_dot0[:, None])
        np.testing.assert_array_equal(attractor, here["attractor"].values)
        np.testing.assert_array_equal(status, here["status"].values)
        out.append({"ds": here, "point": point,
                    "names": attractor_names(point_group(tree, "attractors", params))})
    return out


@pytest.fixture(scope="module")
def browser():
    if BROWSER is None or NO_PLAYWRIGHT is not None:
        pytest.fail("ATLAS_REQUIRE_BROWSER is set but there is no browser: "
                    f"{NO_PLAYWRIGHT or 'no Chromium-family executable'}")
    with headless_page(BROWSER, width=1280, height=1200) as page:
        yield page


def _open(browser, page: Path):
    browser.goto(page.resolve().as_uri())
    assert browser.evaluate("window.atlasDriven.ready") is True


# ---- the page, without a browser ------------------------------------------------------

def test_the_page_is_self_contained_and_runs_one_script_by_its_hash(driven):
    html = driven["page"].read_text(encoding="utf-8")
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:|//)""", html, re.I)
    assert "<link" not in html and not re.search(r"<script[^>]*\ssrc=", html)
    assert "default-src 'none'" in html
    assert html.count("<script") == 1
    script = re.search(r"<script>(.*?)</script>", html, re.S).group(1)
    script_path = REPO / "atlas" / "views" / "view_assets" / "driven.js"
    assert script == script_path.read_text(encoding="utf-8")
    digest = base64.b64encode(hashlib.sha256(script.encode()).digest()).decode()
    assert f"script-src 'sha256-{digest}'" in html
    assert 'id="atlas-data"' in html  # atlas view recognises its page: may write it again
    assert write_view(driven["h5"]) == driven["page"]


def test_each_section_carries_its_own_points_data(driven, stored):
    html = driven["page"].read_text(encoding="utf-8")
    data = json.loads(unescape(re.search(r'data-json="([^"]*)"', html).group(1)))
    assert [int(i) for i in re.findall(r'<section data-point="(\d+)">', html)] == [0, 1]
    for d, s in zip(data, stored):
        point = s["point"]
        assert d["amplitude"] == point.drive.amplitude
        assert d["steps_per_period"] == point.drive.steps_per_period
        assert d["max_periods"] == point.max_periods
        assert d["confirm"] == [int(c) for c in point.confirm]
        np.testing.assert_array_equal(d["targets"]["theta"], point.targets[:, 0])
        np.testing.assert_array_equal(d["targets"]["attractor"], point.target_attractor)
        assert [d["radius"][k] for k in d["targets"]["attractor"]] == point.radius.tolist()


# ---- the page in a browser ----------------------------------------------------------------

@needs_browser
def test_a_click_follows_the_orbit_as_atlas_does(driven, stored, browser):
    """A mouse click on the first map at a grid point: the returns the page draws are the
    kernel's P iterates (to 1e-9, the first five), its label is DrivenPoint.label's, and the
    readout names it as the key does, next to the stored label of the grid point."""
    _open(browser, driven["page"])
    s = stored[0]
    ds, point = s["ds"], s["point"]
    i, j = 5, 4
    xy = browser.evaluate(f"atlasDriven.clientXY(0, {float(ds.theta0[i])!r}, "
                          f"{float(ds.theta_dot0[j])!r})")
    assert 0 < xy["y"] < 1200
    browser.click(xy["x"], xy["y"])
    last = browser.evaluate("atlasDriven.last")
    th0, v0 = last["theta0"], last["theta_dot0"]
    assert abs(th0 - float(ds.theta0[i])) < 0.02 and abs(v0 - float(ds.theta_dot0[j])) < 0.02
    drive = point.drive
    expected = kernels.sample(np.array([th0]), np.array([v0]), drive.alpha, drive.omega0,
                              drive.torque, drive.table, drive.dt, 0, 5)[0]
    np.testing.assert_allclose(np.array(last["returns"][:5]), expected, rtol=0, atol=1e-9)
    attractor, status, t_trap, _ = point.label(th0, v0)
    assert last["decided"] and last["attractor"] == int(attractor)
    assert last["periods"] * drive.period == pytest.approx(float(t_trap), rel=1e-6)
    readout = browser.evaluate("document.querySelector('section[data-point=\"0\"] "
                               ".orbit-readout').innerText")
    names = s["names"]
    assert f"It reaches {names[int(attractor)]}" in readout
    stored_k = int(ds["attractor"].values[j, i])
    assert f"nearest grid point (θ0 = {float(ds.theta0[i]):.4f} rad" in readout
    assert f"): {names[stored_k]}" in readout
    # the returns are drawn: the overlay is dark at a return inside the window
    inside = [r for r in last["returns"] if -2 < r[1] < 4]
    th = (inside[0][0] + math.pi) % (2 * math.pi) - math.pi
    at = browser.evaluate(f"atlasDriven.clientXY(0, {th!r}, {inside[0][1]!r})")
    pixel = browser.evaluate(f"""(() => {{
        const c = document.querySelector('section[data-point="0"] canvas');
        const b = c.getBoundingClientRect(), r = c.width / b.width;
        return [...c.getContext('2d').getImageData(({at['x']} - b.left) * r,
                                                   ({at['y']} - b.top) * r, 1, 1).data]; }})()""")
    assert pixel[3] == 255 and max(pixel[:3]) < 60, pixel
    assert browser.errors == []


@needs_browser
def test_every_grid_point_of_every_parameter_point_gets_the_files_label(driven, stored,
                                                                        browser):
    """The page's orbit from each grid point of each map (that point's own drive and
    attractors) gets the label the file stores there, undecided ones included, and at the
    period the file stores wherever the page's returns follow the kernel's (to 1e-9) up to
    it: the page's sine and its lack of FMA differ from the kernel's in the last bits, which a
    chaotic transient may grow until a return falls on the other side of a capture circle."""
    from atlas.kernels import driven as kernels

    _open(browser, driven["page"])
    undecided = followed = decided = 0
    for index, s in enumerate(stored):
        ds, drive = s["ds"], s["point"].drive
        grid = [[float(t), float(v)] for v in ds.theta_dot0.values for t in ds.theta0.values]
        got = browser.evaluate(f"""{json.dumps(grid)}.map(([t, v]) => {{
            const o = atlasDriven.follow({index}, t, v);
            return [o.attractor === null ? -32768 : o.attractor, o.status, o.periods,
                    o.returns]; }})""")
        attractor = np.array([g[0] for g in got]).reshape(ds["attractor"].shape)
        np.testing.assert_array_equal(attractor, ds["attractor"].values)
        unresolved = ds["status"].values.ravel() == UNRESOLVED
        assert [g[1] == "unresolved" for g in got] == unresolved.tolist()
        for g in np.array(got, dtype=object)[unresolved]:
            assert g[2] == s["point"].max_periods
        undecided += int(unresolved.sum())
        t = ds["t_trap"].values.ravel()
        for (th0, v0), g, stored_t in zip(grid, got, t):
            if not np.isfinite(stored_t):
                continue
            decided += 1
            periods = int(round(stored_t / drive.period))
            kernel = kernels.sample(np.array([th0]), np.array([v0]), drive.alpha,
                                    drive.omega0, drive.torque, drive.table, drive.dt, 0,
                                    periods)[0]
            page = np.array(g[3][:periods])
            if len(page) == periods and np.abs(page - kernel).max() <= 1e-9:
                assert g[2] == periods, (th0, v0)
                followed += 1
    assert followed >= 0.75 * decided  # most follow (108 of 127 here): not vacuous
    assert undecided >= 1  # the "undecided" readout is met
    assert browser.errors == []


@needs_browser
def test_an_undecided_orbit_says_so(driven, stored, browser):
    """From a grid point the file stores as unresolved (one at least: the test above), the
    readout says undecided after t_max's periods, next to the stored "no label"."""
    _open(browser, driven["page"])
    index, j, i = next((index, *where) for index, s in enumerate(stored)
                       for where in np.argwhere(s["ds"]["status"].values == UNRESOLVED))
    ds = stored[index]["ds"]
    browser.evaluate(f"atlasDriven.follow({index}, {float(ds.theta0[i])!r}, "
                     f"{float(ds.theta_dot0[j])!r})")
    readout = browser.evaluate(f"document.querySelector('section[data-point=\"{index}\"] "
                               ".orbit-readout').innerText")
    assert (f"Undecided after {stored[index]['point'].max_periods} periods (t_max = 320 s)."
            in readout)
    assert "no label (unresolved)" in readout
    assert browser.errors == []
