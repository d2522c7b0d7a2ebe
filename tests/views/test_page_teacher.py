"""The page a teacher would use (``atlas view``) and ``atlas orbit``'s wrapped orbits.

In the real browser (headless Chromium through ``tests/browser.py``; skipped with the reason
where there is none): the colour key lists every basin of the map in its own colour, the map
is drawn before the load event ends, the hover line reads the stored label with units, the
layer switch shows t_trap and the boundary distance, several orbits are kept until cleared,
exact coordinates can be typed, a clicked orbit that leaves the window is drawn inside it (a
whole number of turns away), the energy readout prints both sides of its inequality to one
precision, the layout fits a 1920 px and a 400 px screen, and no script reports an error.
Without a browser: the wrapping of :func:`atlas.commands.orbit_integrate.wrapped` and the
running orbits followed onto the limit cycle (checked against
:func:`atlas.physics.running.limit_cycle`, an independent computation of the cycle).
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

import atlas
from atlas.commands.orbit_integrate import integrate, window_period, wrapped
from atlas.status import RUNNING
from atlas.views.page import write_view
from tests.browser import (
    find_browser,
    headless_page,
    playwright_missing,
    skip_without_browser,
)
from tests.helpers import SWING, small_atlas

BROWSER = find_browser()
NO_PLAYWRIGHT = playwright_missing()
needs_browser = skip_without_browser()
TWO_PI = 2 * math.pi


# ---- wrapping and following, without a browser ------------------------------------------

def test_wrapped_keeps_a_curve_in_the_window_a_whole_number_of_turns_away():
    lo, hi = -2.5, 4.0  # 6.5 rad wide: one turn fits
    theta = np.linspace(-20.0, 30.0, 2001)
    theta_dot = np.sin(theta)
    th, v = wrapped(theta, theta_dot, lo, hi)
    kept = ~np.isnan(th)
    assert np.all((th[kept] >= lo) & (th[kept] <= hi))
    # each drawn point is an orbit point moved by whole turns, θ̇ untouched, order kept
    np.testing.assert_array_equal(v[kept], theta_dot)
    turns = (th[kept] - theta) / TWO_PI
    np.testing.assert_allclose(turns, np.round(turns), atol=1e-9)
    np.testing.assert_array_equal(th[kept][(theta >= lo) & (theta <= hi)],
                                  theta[(theta >= lo) & (theta <= hi)])
    # the line breaks exactly where the shift changes: once per turn crossed
    assert np.isnan(th).sum() == np.count_nonzero(np.diff(np.round(turns)))
    # a window of three turns shifts by three turns at a time; narrower than one: unchanged
    assert window_period(-3 * math.pi, 3 * math.pi) == pytest.approx(3 * TWO_PI)
    th3, _ = wrapped(theta, theta_dot, -3 * math.pi, 3 * math.pi)
    assert np.nanmin(th3) >= -3 * math.pi and np.nanmax(th3) <= 3 * math.pi
    assert window_period(0.0, 6.0) == 0.0
    same, _ = wrapped(theta, theta_dot, 0.0, 6.0)
    np.testing.assert_array_equal(same, theta)


@pytest.mark.slow  # the running barrier (about 2 s)
def test_a_running_orbit_is_followed_onto_the_limit_cycle():
    """From (0, 3), 2 rad/s below the cycle, certified running at once: followed on until it
    is on the cycle. The cycle here is physics.running.limit_cycle's (its own shooting
    method), not the return-speed test that stops the orbit."""
    from atlas.commands.orbit import running_barrier_for
    from atlas.physics.running import limit_cycle

    barrier, _ = running_barrier_for(SWING["alpha"], SWING["omega0"], SWING["torque"], 0.01)
    orbit = integrate(0.0, 3.0, running=barrier, t_max=200.0, **SWING)
    cycle = limit_cycle(SWING["alpha"], SWING["omega0"], SWING["torque"])
    ct, cv = np.asarray(cycle.theta), np.asarray(cycle.theta_dot)

    def gap(i):  # θ̇ − the cycle's θ̇ at the same phase [rad/s]
        phase = ct[0] + np.mod(orbit.theta[i] - ct[0], TWO_PI)
        return orbit.theta_dot[i] - np.interp(phase, ct, cv)

    assert orbit.status == RUNNING and orbit.t_trap == 0.0
    assert abs(gap(0)) > 1.5
    assert orbit.settled and orbit.turns >= 2 and orbit.t[-1] < 200.0
    assert abs(gap(-1)) < 0.05  # on the cycle, to the width of a drawn line


# ---- the page in a browser ----------------------------------------------------------------

@pytest.fixture(scope="module")
def pages(swing_atlas, tmp_path_factory):
    """The pages of the shared swing atlas (torque: tilted wells, the running basin, the
    separatrices) and of a 32² default-window atlas without separatrices."""
    tmp = tmp_path_factory.mktemp("teacher")
    small_atlas(tmp, "plain", {"alpha": 0.1, "omega0": 1.0}, theta=("-3pi", "3pi"),
                speed=(-4.0, 4.0), num=(32, 32), t_max=200.0, separatrices=False)
    return {"swing": write_view(swing_atlas, tmp / "swing.html"), "swing_h5": swing_atlas,
            "plain": write_view(tmp / "plain.h5"), "plain_h5": tmp / "plain.h5"}


@pytest.fixture(scope="module")
def browser():
    if BROWSER is None or NO_PLAYWRIGHT is not None:
        pytest.fail("ATLAS_REQUIRE_BROWSER is set but there is no browser: "
                    f"{NO_PLAYWRIGHT or 'no Chromium-family executable'}")
    with headless_page(BROWSER, width=1280, height=800) as page:
        yield page


def _open(browser, page, width=1280, height=800):
    browser.page.set_viewport_size({"width": width, "height": height})
    browser.goto(page.resolve().as_uri())
    browser.evaluate("atlasView.ready")


def _click(browser, theta0, theta_dot0):
    xy = browser.evaluate(f"atlasView.clientXY({theta0!r}, {theta_dot0!r})")
    browser.click(xy["x"], xy["y"])
    return browser.evaluate("Object.assign({}, document.getElementById('readout').dataset)")


def _text(browser, selector):
    return browser.evaluate(f"document.querySelector({json.dumps(selector)}).innerText")


def _stored(path):
    return atlas.open(path).to_dataset(inherit=False)


def _inner_cells(ds, good):
    """Grid indices (j, i) whose 3 × 3 neighbourhood is all ``good`` (away from edges)."""
    inner = np.zeros_like(good)
    inner[1:-1, 1:-1] = True
    for dj in (-1, 0, 1):
        for di in (-1, 0, 1):
            inner &= np.roll(good, (dj, di), axis=(0, 1))
    return np.argwhere(inner)


@needs_browser
def test_the_key_names_every_basin_in_its_own_colour(pages, browser):
    ds = _stored(pages["swing_h5"])
    status, k = ds["status"].values, ds["attractor"].values
    wells = sorted({int(x) for x in k[np.isin(status, (0, 3))]})
    _open(browser, pages["swing"])
    items = browser.evaluate("""[...document.querySelectorAll('#key .item')].map((e) => ({
        k: e.dataset.k ?? null, text: e.textContent,
        colour: getComputedStyle(e.querySelector('.swatch')).backgroundColor}))""")
    keyed = [it for it in items if it["k"] is not None]
    assert [int(it["k"]) for it in keyed] == wells
    colours = [it["colour"] for it in keyed] + [it["colour"] for it in items
                                                if it["text"] == "running"]
    assert len(colours) == len(wells) + 1 and len(set(colours)) == len(colours)
    texts = [it["text"] for it in items]
    assert "separatrices (basin boundaries)" in texts and "running limit cycle" in texts
    # the map's pixel at an inner grid point of a well (off the θ̇ = 0 axis, where the
    # critical points are marked) has that well's key colour
    cells = _inner_cells(ds, np.isin(status, (0, 3)) & (k == wells[-1]))
    j, i = cells[np.abs(ds.theta_dot0.values[cells[:, 0]]) > 0.5][0]
    xy = browser.evaluate(f"atlasView.clientXY({float(ds.theta0[i])!r}, "
                          f"{float(ds.theta_dot0[j])!r})")
    pixel = browser.evaluate(f"""(() => {{
        const c = document.getElementById('map'), b = c.getBoundingClientRect();
        const d = c.getContext('2d').getImageData({xy['x']} - b.left, {xy['y']} - b.top, 1, 1).data;
        return 'rgb(' + d[0] + ', ' + d[1] + ', ' + d[2] + ')'; }})()""")
    assert pixel == keyed[-1]["colour"]
    assert browser.errors == []


@needs_browser
def test_no_separatrix_words_on_a_page_without_separatrices(pages, browser):
    _open(browser, pages["plain"])
    body = _text(browser, "body")
    assert "separatri" not in body.lower() and "Red" not in body
    assert "k = 0" in _text(browser, "#key") and "running" not in _text(browser, "#key")
    assert browser.errors == []


@needs_browser
def test_the_map_is_drawn_before_the_load_event_ends(pages, browser):
    """A load listener registered before the page's own script looks at the map canvas: the
    basin image is already on it (the centre of the plot is not transparent)."""
    browser.page.add_init_script("""window.addEventListener('load', () => {
        const c = document.getElementById('map');
        const d = c.getContext('2d').getImageData(c.width / 2, c.height / 2, 1, 1).data;
        window.atLoad = { drawn: c.dataset.drawn || '', alpha: d[3] };
    });""")
    _open(browser, pages["plain"])
    assert browser.evaluate("window.atLoad") == {"drawn": "basins", "alpha": 255}
    assert browser.errors == []


@needs_browser
def test_hover_reads_the_stored_label_with_units(pages, browser):
    ds = _stored(pages["swing_h5"])
    status, k = ds["status"].values, ds["attractor"].values
    _open(browser, pages["swing"])
    labelled = np.isin(status, (0, 3))
    well = max(set(k[labelled].tolist()), key=lambda w: len(_inner_cells(ds, labelled & (k == w))))
    j, i = _inner_cells(ds, labelled & (k == well))[0]
    xy = browser.evaluate(f"atlasView.clientXY({float(ds.theta0[i])!r}, "
                          f"{float(ds.theta_dot0[j])!r})")
    browser.page.mouse.move(xy["x"], xy["y"])
    text = _text(browser, "#hover")
    assert re.search(r"θ0 = −?[\d.]+ rad, θ̇0 = −?[\d.]+ rad/s", text), text
    assert f"k = {well:+d}".replace("+0", "0").replace("-", "−") in text and "trapped" in text
    d = float(ds["boundary_distance"].values[j, i])
    assert f"boundary distance {d:.3g}".replace("-", "−") in text
    hovered = browser.evaluate("document.getElementById('hover').dataset.thetaDot0")
    assert float(hovered) == pytest.approx(float(ds.theta_dot0[j]), abs=0.2)
    running = _inner_cells(ds, status == 4)[0]
    xy = browser.evaluate(f"atlasView.clientXY({float(ds.theta0[running[1]])!r}, "
                          f"{float(ds.theta_dot0[running[0]])!r})")
    browser.page.mouse.move(xy["x"], xy["y"])
    assert "running, certified to converge to the running limit cycle" in _text(browser, "#hover")
    assert browser.errors == []


@needs_browser
def test_the_layer_switch_shows_time_and_distance(pages, browser):
    _open(browser, pages["swing"])
    shown = {}
    for layer, words in (("t_trap", "time to trap"), ("distance", "distance to the nearest"),
                         ("basins", "the well k")):
        browser.page.check(f"input[name=layer][value={layer}]")
        assert browser.evaluate("document.getElementById('map').dataset.drawn") == layer
        assert words in _text(browser, "#key")
        shown[layer] = browser.evaluate("document.getElementById('map').toDataURL()")
        if layer != "basins":  # a colour bar with its range
            assert browser.evaluate("document.querySelector('#key canvas.bar') !== null")
    assert len(set(shown.values())) == 3
    assert browser.errors == []


@needs_browser
def test_several_orbits_are_kept_then_cleared(pages, browser):
    _open(browser, pages["plain"])
    pristine = browser.evaluate("document.getElementById('map').toDataURL()")
    for n, (th, v) in enumerate(((-1.0, 2.5), (2.0, -1.0), (-6.0, 0.5)), start=1):
        assert _click(browser, th, v)["orbits"] == str(n)
    rows = _text(browser, "#readout")
    assert "orbits on the map" in rows and rows.count("from (") == 3
    assert browser.evaluate("document.getElementById('map').toDataURL()") != pristine
    browser.page.click("#clear")
    assert "orbits" not in browser.evaluate(
        "Object.assign({}, document.getElementById('readout').dataset)")
    assert browser.evaluate("document.getElementById('clear').disabled") is True
    assert browser.evaluate("document.getElementById('map').toDataURL()") == pristine
    assert browser.errors == []


@needs_browser
def test_exact_coordinates_can_be_typed(pages, browser):
    _open(browser, pages["plain"])
    browser.page.fill("#in-theta0", "-pi/2")
    browser.page.fill("#in-theta-dot0", "1.5")
    browser.page.click("#goto button[type=submit]")
    r = browser.evaluate("Object.assign({}, document.getElementById('readout').dataset)")
    assert float(r["theta0"]) == -math.pi / 2 and float(r["thetaDot0"]) == 1.5
    expect = integrate(-math.pi / 2, 1.5, alpha=0.1, omega0=1.0)
    assert r["orbitStatus"] == "trapped" and int(r["orbitK"]) == expect.k
    browser.page.fill("#in-theta0", "two")
    browser.page.click("#goto button[type=submit]")
    assert "θ0: not a number" in _text(browser, "#goto-error")
    assert browser.evaluate("document.getElementById('readout').dataset.orbits") == "1"
    assert browser.evaluate("['3pi', '-π/4', '2*pi', '1e-3', '.5'].map(atlasView.parseValue)") \
        == [3 * math.pi, -math.pi / 4, 2 * math.pi, 1e-3, 0.5]
    assert browser.errors == []


@needs_browser
def test_an_orbit_that_leaves_the_window_is_drawn_inside_it(pages, browser):
    """The issue's orbit: with torque, from (0, −3.1) it settles at θ* − 2π = −5.76, outside
    the one-turn window; drawn one turn away, every drawn point is inside the map."""
    _open(browser, pages["swing"])
    r = _click(browser, 0.0, -3.1)
    assert r["orbitStatus"] == "trapped" and r["orbitK"] == "-1"
    drawn = browser.evaluate("atlasView.drawn()")
    assert drawn["thmin"] < drawn["A"] - 1.0  # the orbit itself leaves the window
    assert drawn["left"] <= drawn["xmin"] and drawn["xmax"] <= drawn["right"]
    assert drawn["shifted"] and drawn["period"] == pytest.approx(TWO_PI)
    assert "shifted by whole turns" in _text(browser, "#readout")
    # a running orbit: followed for many turns, all drawn inside too
    r = _click(browser, 0.0, 3.0)
    drawn = browser.evaluate("atlasView.drawn()")
    assert r["orbitStatus"] == "running"
    assert drawn["thmax"] - drawn["thmin"] > 10 * TWO_PI
    assert drawn["left"] <= drawn["xmin"] and drawn["xmax"] <= drawn["right"]
    assert "on the cycle" in _text(browser, "#readout")
    assert browser.errors == []


def _printed_inequality(text):
    """(left, right, significant digits of each) of "E_k = a < … = b" in ``text``."""
    m = re.search(r"E_k = (−?[\d.e+−]+) < [^=]+= (−?[\d.e+−]+)", text)
    a, b = (s.replace("−", "-") for s in m.groups())
    digits = [len(re.sub(r"e.*", "", s).replace("-", "").replace(".", "").lstrip("0"))
              for s in (a, b)]
    return float(a), float(b), digits


@needs_browser
def test_the_energy_readout_prints_both_sides_to_one_precision(pages, browser):
    _open(browser, pages["plain"])
    # the case: E_k within 1e-8 of the level, which "2.00 < 1.999999968" misread
    text = browser.evaluate("atlasView.energyText(1.9999999612, 1.999999968, 'cap')")
    left, right, digits = _printed_inequality(text)
    assert left < right and digits[0] == digits[1] and digits[0] <= 10
    assert "below the level by 6.8" in text
    _click(browser, -1.0, 2.5)
    left, right, digits = _printed_inequality(_text(browser, "#readout"))
    assert left < right and digits[0] == digits[1]
    assert browser.errors == []


@needs_browser
def test_the_layout_fits_a_wide_and_a_narrow_screen(pages, browser):
    _open(browser, pages["swing"], 1920, 1080)
    box = browser.evaluate("""(() => { const r = document.getElementById('map')
        .getBoundingClientRect(); const k = document.getElementById('key')
        .getBoundingClientRect(); return [r.width, r.bottom, k.bottom]; })()""")
    assert box[0] > 1200 and box[2] <= 1080  # the map fills the width; map and key fit
    _open(browser, pages["swing"], 400, 800)
    assert browser.evaluate("document.documentElement.scrollWidth") <= 400
    assert browser.evaluate("document.getElementById('map').getBoundingClientRect().right") \
        <= 400
    _click(browser, 0.0, -3.1)
    top = browser.evaluate("document.querySelector('#readout table').getBoundingClientRect().top")
    assert top < 800  # the readout starts above the fold
    assert browser.errors == []


# ---- atlas orbit's figure -------------------------------------------------------------------

@pytest.mark.slow  # atlas orbit of an atlas file: the exact certificate, the figure
def test_the_orbit_figure_draws_the_orbit_inside_the_map(swing_atlas, tmp_path, monkeypatch):
    """``atlas orbit FILE 0 −3.1`` (the issue's orbit, which settles at −5.76, outside the
    window): every drawn point of the phase curve lies in the map's θ window, the curve is
    the orbit moved by whole turns, the legend names the start and the certificate, and a
    θ̇(t) panel shows the orbit's speed."""
    from matplotlib.figure import Figure

    from atlas.commands.orbit import report
    from atlas.commands.orbit_figure import plot_orbit

    saved = []
    monkeypatch.setattr(Figure, "savefig", lambda fig, *a, **k: saved.append(fig))
    orbit, _, context = report(0.0, -3.1, file=swing_atlas)
    try:
        plot_orbit(orbit, tmp_path / "o.png", context["tree"], context["index"])
    finally:
        context["tree"].close()
    assert orbit.k == -1 and orbit.theta[-1] < -5.0
    ax = next(a for a in saved[0].axes if a.get_ylabel().startswith("θ̇0"))
    lo, hi = ax.get_xlim()
    curve = next(line for line in ax.lines if line.get_label().startswith("orbit"))
    theta = np.asarray(curve.get_xdata(), float)
    drawn = theta[~np.isnan(theta)]
    assert drawn.size == orbit.theta.size and "modulo 2π" in curve.get_label()
    assert np.all((drawn >= lo) & (drawn <= hi))
    turns = (drawn - orbit.theta) / TWO_PI
    np.testing.assert_allclose(turns, np.round(turns), atol=1e-9)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "initial condition (θ0, θ̇0)" in labels
    assert any(t.startswith("trapped in well −1 at t = ") for t in labels)
    speed = next(a for a in saved[0].axes if a.get_ylabel() == "θ̇ [rad/s]")
    np.testing.assert_array_equal(speed.lines[0].get_ydata(), orbit.theta_dot)
