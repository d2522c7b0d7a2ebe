"""``atlas view``: the page is self-contained, small and safe, and — in a real headless
browser — the orbits it integrates end in the wells atlas labelled.

The browser tests drive a Chromium-family browser already on the machine (Debian's
``chromium``, or $ATLAS_BROWSER) with Playwright (``tests/browser.py``; no browser download);
without one, or without the playwright package, they are skipped with the reason.
``ATLAS_UPDATE_SCREENSHOT`` makes the screenshot test write ``docs/images/view.png`` (see
:func:`test_screenshot`).
"""

from __future__ import annotations

import json
import os
import re
import time
from pathlib import Path

import numpy as np
import pytest

import atlas
from atlas.cli import main
from atlas.views.page import pack_distance, safe_json, unpack_distance, write_view
from tests.browser import (
    find_browser,
    headless_page,
    playwright_missing,
    skip_without_browser,
)
from tests.helpers import SWING

pytestmark = pytest.mark.slow  # two atlas runs for the page, a browser

REPO = Path(__file__).resolve().parents[2]
XSS = "</script><script>alert(1)</script>"
BROWSER = find_browser()
NO_PLAYWRIGHT = playwright_missing()
needs_browser = skip_without_browser()


def _run(tmp, name, alpha=0.1, num=(160, 96), sep=True, t_max=200.0, method="rk4"):
    cfg = atlas.Config.model_validate({
        "name": name, "pendulum": {"alpha": alpha, "omega0": 1.0},
        "grid": {"theta0": {"start": "-3pi", "stop": "3pi", "num": num[0]},
                 "theta_dot0": {"start": -4, "stop": 4, "num": num[1]}},
        "integrator": {"dt": 0.01, "t_max": t_max, "method": method},
        "separatrices": {"enabled": sep},
        "output": str(tmp / f"{abs(hash(name))}.h5")})
    atlas.run(cfg, quiet=True)
    return cfg.output


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("view")
    single = _run(tmp, "a quick look")
    sweep = _run(tmp, "two dampings", alpha=[0.1, 0.5], num=(48, 32), sep=False)
    xss = _run(tmp, XSS, num=(24, 16), sep=False)
    pages = {key: write_view(path) for key, path in
             (("single", single), ("sweep", sweep), ("xss", xss))}
    return {"single": single, "sweep": sweep, "xss": xss, "pages": pages}


def _data(page: Path) -> dict:
    html = page.read_text(encoding="utf-8")
    block = re.search(r'<script type="application/json" id="atlas-data">(.*?)</script>',
                      html, re.S)
    return json.loads(block.group(1))


# ---- the page, without a browser ------------------------------------------------------

def test_page_is_self_contained_and_small(files):
    page = files["pages"]["single"]
    html = page.read_text(encoding="utf-8")
    assert page == files["single"].with_suffix(".html")
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:|//)""", html, re.I)
    assert "<link" not in html and not re.search(r"<script[^>]*\ssrc=", html)
    assert "default-src 'none'" in html  # the page may not fetch anything
    assert html.count("<script") == 2  # the data block and the one script
    # bytes per grid point, fixed overhead included: a 512² page stays well under 5 MB
    n = 160 * 96
    assert len(html.encode()) / n < 8, len(html.encode()) / n


def test_strings_from_the_file_are_data_not_markup(files):
    html = files["pages"]["xss"].read_text(encoding="utf-8")
    assert XSS not in html and "<script>alert" not in html
    assert html.count("<script") == 2 and html.count("</script>") == 2
    assert _data(files["pages"]["xss"])["name"] == XSS
    for text in ("<", ">", "&", "\u2028", "</script>"):
        encoded = safe_json({"s": text})
        assert not set("<>&\u2028") & set(encoded) and json.loads(encoded) == {"s": text}


def test_packed_arrays_round_trip(files):
    d = np.array([0.0, np.nan, 1e-9, 5e-6, 0.035, 1.0, 7.5, 1e30, 1e-40])
    back = unpack_distance(pack_distance(d))
    assert back[0] == 0 and np.isnan(back[1])
    np.testing.assert_allclose(back[2:-2], d[2:-2], rtol=np.exp2(1 / 512) - 1)
    data = _data(files["pages"]["single"])
    assert data["dt"] == 0.01 and data["theta0"][2] == 160 and data["theta_dot0"][2] == 96
    assert len(data["points"]) == 1 and data["points"][0]["curves"]
    assert len(_data(files["pages"]["sweep"])["points"]) == 2


def test_band_names_keep_off_the_markers_and_the_edges():
    """19 horizontal bands across θ̇ ∈ [−12, 12], well 0's six wide around θ̇ = 0, the others
    one wide: each named inside its own band, off θ̇ = 0, where the rest states and saddles
    are marked (well 0's band is deepest there), and off the window's edges (every band is
    deepest, by the stored distance, at the left edge), wherever the band has room."""
    from atlas.views.page import _band_labels

    theta0, theta_dot0 = np.linspace(-3 * np.pi, 3 * np.pi, 60), np.linspace(-12, 12, 241)
    depth = np.abs(theta_dot0)
    k = np.where(depth < 3, 0, np.sign(theta_dot0) * np.ceil(depth - 3)).astype(int)
    lo, hi = np.where(k == 0, -3, np.where(k > 0, k + 2, k - 3)), np.where(
        k == 0, 3, np.where(k > 0, k + 3, k - 2))
    to_edge = np.minimum(theta_dot0 - lo, hi - theta_dot0)  # to the band's nearer boundary
    distance = to_edge[:, None] * np.linspace(2, 1, 60)[None, :]
    k = k[:, None] * np.ones((1, 60), int)
    wells = np.arange(-9, 10)
    labels = _band_labels(k, np.ones(k.shape, bool), wells, distance, theta0, theta_dot0)
    assert [w for w, _, _ in labels] == wells.tolist()
    for well, th, v in labels:
        assert k[int(np.argmin(np.abs(theta_dot0 - v))), 0] == well, (well, v)
        if abs(well) <= 8:  # room off the axis and the edges
            assert abs(v) >= 0.06 * 24 and 12 - abs(v) >= 0.06 * 24, (well, v)
            assert min(th - theta0[0], theta0[-1] - th) >= 0.06 * 6 * np.pi, (well, th)


def test_view_cli(files, tmp_path, capsys):
    out = tmp_path / "page.html"
    assert main(["view", str(files["single"]), "-o", str(out)]) == 0
    assert out.stat().st_size > 0 and f"wrote {out}" in capsys.readouterr().out
    for args, fragment in ((["view", str(tmp_path / "missing.h5")], "missing.h5: no such file"),
                           (["view", str(out), "-o", str(tmp_path / "other.html")],
                            "not an atlas file"),
                           (["view", str(files["single"]), "-o", str(tmp_path)], "directory"),
                           (["view", str(files["single"]), "-o", str(tmp_path / "x" / "p.html")],
                            "not a directory")):
        assert main(args) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("atlas: error: ") and fragment in err and "\n" not in err


# ---- in a real browser ----------------------------------------------------------------

@pytest.fixture(scope="module")
def browser():
    if BROWSER is None:
        pytest.fail("ATLAS_REQUIRE_BROWSER is set but no Chromium-family browser was found")
    if NO_PLAYWRIGHT is not None:
        pytest.fail(f"ATLAS_REQUIRE_BROWSER is set but {NO_PLAYWRIGHT}")
    with headless_page(BROWSER, width=1180, height=660) as page:
        yield page


def _open(browser, page: Path) -> None:
    browser.goto(page.resolve().as_uri())
    browser.evaluate("atlasView.ready")
    assert browser.evaluate("document.getElementById('readout').dataset.ready") == "1"


def _readout(browser) -> dict:
    return browser.evaluate("Object.assign({}, document.getElementById('readout').dataset)")


def _far_points(point, n, min_distance, rng):
    """Grid indices (row j, column i) of trapped labels far from every boundary."""
    status, dist = point["status"].values, point["boundary_distance"].values
    j, i = np.nonzero((status == 0) & (dist > min_distance))
    pick = rng.choice(j.size, size=min(n, j.size), replace=False)
    return j[pick], i[pick]


@needs_browser
def test_clicked_orbits_end_where_atlas_says(files, browser):
    """Real clicks on grid points far from the boundaries (farther than a few pixels, so the
    click's rounding to whole pixels cannot cross one): the page's orbit ends in the stored
    well, and its readout shows the stored values of that grid point."""
    ds = atlas.open(files["single"]).to_dataset(inherit=False)
    _open(browser, files["pages"]["single"])
    th, v = ds["theta0"].values, ds["theta_dot0"].values
    rows, cols = _far_points(ds, 10, 0.15, np.random.default_rng(1))
    for j, i in zip(rows, cols):
        xy = browser.evaluate(f"atlasView.clientXY({float(th[i])!r}, {float(v[j])!r})")
        browser.click(xy["x"], xy["y"])
        r = _readout(browser)
        assert abs(float(r["theta0"]) - th[i]) < 0.05 and abs(float(r["thetaDot0"]) - v[j]) < 0.05
        k = int(ds["attractor"].values[j, i])
        assert r["orbitStatus"] == "trapped" and int(r["orbitK"]) == k, (th[i], v[j], r)
        assert int(r["gridK"]) == k and r["gridStatus"] == "trapped"
        assert float(r["gridTTrap"]) == pytest.approx(float(ds["t_trap"].values[j, i]))
        assert float(r["gridDistance"]) == pytest.approx(
            float(ds["boundary_distance"].values[j, i]), rel=2e-3)
    assert int(_readout(browser)["clicks"]) == len(rows)
    assert browser.dialogs == [] and browser.errors == []


@needs_browser
def test_page_orbits_match_atlas_labels_at_grid_points(files, browser):
    """The page's integrator from exact grid points away from the boundaries: the same well
    and the same t_trap (same RK4 step, same trap every check_every steps) as the file."""
    ds = atlas.open(files["single"]).to_dataset(inherit=False)
    _open(browser, files["pages"]["single"])
    th, v = ds["theta0"].values, ds["theta_dot0"].values
    rows, cols = _far_points(ds, 300, 1e-6, np.random.default_rng(2))
    pairs = json.dumps([[float(th[i]), float(v[j])] for j, i in zip(rows, cols)])
    got = browser.evaluate(f"{pairs}.map(([a, b]) => atlasView.orbit(a, b))")
    k = ds["attractor"].values[rows, cols]
    t = ds["t_trap"].values[rows, cols]
    assert [g["status"] for g in got] == ["trapped"] * len(got)
    np.testing.assert_array_equal([g["k"] for g in got], k)
    # t_trap can differ only where the energy sits within rounding of the trap level at a test
    np.testing.assert_allclose([g["t_trap"] for g in got], t, atol=16 * 0.01 + 1e-9)
    assert np.mean(np.isclose([g["t_trap"] for g in got], t)) > 0.95
    # and the very same RK4 map: the state at the trap equals atlas's integrator's to rounding
    # (atlas.commands.orbit_integrate.integrate steps with the kernel's step;
    # tests/commands/test_orbit.py ties it to the kernel)
    from atlas.commands.orbit_integrate import integrate

    for g in got[:40]:
        ref = integrate(g["theta0"], g["theta_dot0"], alpha=0.1, omega0=1.0)
        assert ref.k == g["k"] and ref.t_trap == pytest.approx(g["t_trap"])
        i = ref.trap_index
        assert abs(ref.theta[i] - g["theta_trap"]) + abs(ref.theta_dot[i] - g["theta_dot_trap"]) \
            < 1e-9


@needs_browser
def test_a_trigfree_page_integrates_with_the_files_method(tmp_path, browser):
    """An atlas computed with method "rk4-trigfree": the page steps (θ, θ̇, cos θ, sin θ) as
    the file's kernels did, so its orbits end in the stored wells with the stored t_trap, and
    the state at the trap is atlas.commands.orbit_integrate.integrate's with that method (not
    classical RK4's, which differs by the methods' O(dt⁴) gap, far above rounding)."""
    from atlas.commands.orbit_integrate import integrate

    path = _run(tmp_path, "trig-free", num=(48, 32), method="rk4-trigfree")
    page = write_view(path)
    assert _data(page)["method"] == "rk4-trigfree"
    ds = atlas.open(path).to_dataset(inherit=False)
    _open(browser, page)
    th, v = ds["theta0"].values, ds["theta_dot0"].values
    rows, cols = _far_points(ds, 60, 1e-6, np.random.default_rng(5))
    pairs = json.dumps([[float(th[i]), float(v[j])] for j, i in zip(rows, cols)])
    got = browser.evaluate(f"{pairs}.map(([a, b]) => atlasView.orbit(a, b))")
    np.testing.assert_array_equal([g["k"] for g in got], ds["attractor"].values[rows, cols])
    assert np.mean(np.isclose([g["t_trap"] for g in got], ds["t_trap"].values[rows, cols])) \
        > 0.95
    gaps = []
    for g in got[:20]:
        ref = integrate(g["theta0"], g["theta_dot0"], alpha=0.1, omega0=1.0,
                        method="rk4-trigfree")
        rk4 = integrate(g["theta0"], g["theta_dot0"], alpha=0.1, omega0=1.0)
        i = ref.trap_index
        assert ref.k == g["k"] and ref.t_trap == pytest.approx(g["t_trap"])
        assert abs(ref.theta[i] - g["theta_trap"]) \
            + abs(ref.theta_dot[i] - g["theta_dot_trap"]) < 1e-9
        if rk4.trap_index == i:
            gaps.append(abs(rk4.theta[i] - g["theta_trap"]))
    assert gaps and max(gaps) > 1e-8  # the check above can tell the methods apart


@needs_browser
def test_a_malicious_name_is_shown_as_text_and_never_runs(files, browser):
    # the detector works: a page that does open a dialog is seen
    browser.goto("data:text/html,<script>alert(1)</script>")
    assert len(browser.dialogs) == 1
    _open(browser, files["pages"]["xss"])
    time.sleep(0.2)
    assert browser.dialogs == []
    assert browser.evaluate("document.getElementById('name').textContent") == XSS
    assert browser.evaluate("document.title").startswith(XSS)
    assert browser.evaluate("document.scripts.length") == 2
    assert browser.errors == []


@needs_browser
def test_parameter_slider(files, browser):
    ds = atlas.open(files["sweep"]).to_dataset(inherit=False)
    _open(browser, files["pages"]["sweep"])
    assert browser.evaluate("document.getElementById('controls').hidden") is False
    assert browser.evaluate("document.getElementById('point').max") == "1"
    th, v = ds["theta0"].values, ds["theta_dot0"].values
    # a grid point whose stored well differs between α = 0.1 and 0.5, inside a uniform patch
    k = ds["attractor"].values  # dims (alpha, theta_dot0, theta0): only α is swept
    assert ds["attractor"].dims == ("alpha", "theta_dot0", "theta0")
    same = np.ones(k.shape[1:], bool)
    for a in range(2):
        for dj in (-1, 0, 1):
            for di in (-1, 0, 1):
                same &= np.roll(k[a], (dj, di), axis=(0, 1)) == k[a]
    j, i = np.argwhere(same & (k[0] != k[1]) & (ds["status"].values != 1).all(0))[0]
    for a in range(2):
        browser.evaluate(f"atlasView.select({a})")
        label = browser.evaluate("document.getElementById('point-label').textContent")
        assert f"α = {ds['alpha'].values[a]:g}" in label
        xy = browser.evaluate(f"atlasView.clientXY({float(th[i])!r}, {float(v[j])!r})")
        browser.click(xy["x"], xy["y"])
        r = _readout(browser)
        assert r["point"] == str(a) and int(r["orbitK"]) == int(k[a, j, i]) == int(r["gridK"])


@needs_browser
def test_the_page_draws_in_the_pngs_colours(files, browser):
    """The page's colour of every well k (−40 … 40, through the palette's repeat) is the
    PNGs' well_colour(k), its key's swatches too; its time and distance layers use the PNGs'
    colour maps (at the nodes of their tables, exactly)."""
    from matplotlib import colormaps

    from atlas.views.style import DISTANCE_CMAP, T_TRAP_CMAP, well_colour

    _open(browser, files["pages"]["sweep"])
    page = browser.evaluate("[...Array(81).keys()].map((i) => atlasView.wellColour(i - 40))")
    assert page == [well_colour(k) for k in range(-40, 41)]
    swatches = browser.evaluate("""[...document.querySelectorAll('#key .item')]
        .filter((e) => e.dataset.k !== undefined).map((e) => [Number(e.dataset.k),
        getComputedStyle(e.querySelector('.swatch')).backgroundColor])""")
    assert swatches and all(
        colour == "rgb({}, {}, {})".format(*(int(well_colour(k)[i:i + 2], 16) for i in (1, 3, 5)))
        for k, colour in swatches)
    nodes = [0, 37, 128, 200, 255]
    for layer, name in (("t_trap", T_TRAP_CMAP), ("distance", DISTANCE_CMAP)):
        drawn = browser.evaluate(f"{nodes}.map((i) => atlasView.scaleColour('{layer}', i / 255))")
        assert drawn == [[round(255 * c) for c in colormaps[name](i / 255)[:3]] for i in nodes]
    assert browser.errors == []


@needs_browser
def test_a_saddle_on_the_windows_edge_is_drawn_whole(files, browser):
    """The saddle at θ = 3π sits on the right edge of the default window: its ring shows
    beside the frame too (it was clipped to the plot, half of it gone)."""
    _open(browser, files["pages"]["single"])
    pixel = browser.evaluate("""(() => {
        const xy = atlasView.clientXY(3 * Math.PI, 0), c = document.getElementById('map');
        const b = c.getBoundingClientRect(), dpr = window.devicePixelRatio || 1;
        const ring = 3.5 * 4 / 3;  // SADDLE_MARKER: 7 pt across, 1 pt = 4/3 px
        const x = (xy.x - b.left + ring) * dpr, y = (xy.y - b.top) * dpr;
        return { frame: atlasView.drawn().right, x: xy.x - b.left + ring,
                 rgba: [...c.getContext('2d').getImageData(x, y, 1, 1).data] }; })()""")
    assert pixel["x"] > pixel["frame"] + 1  # beside the frame, outside the plot
    assert pixel["rgba"][3] == 255 and max(pixel["rgba"][:3]) < 100, pixel
    assert browser.errors == []


@needs_browser
def test_at_900_by_700_the_controls_and_side_panel_are_on_screen(files, browser):
    """A 900 × 700 window (a projector, a small laptop): the parameter slider, the layer
    switch and the orbit form, the map, and the side panel (the readout and the pendulum)
    are all within it, no scrolling, the side panel beside the map (it was below the
    fold)."""
    browser.page.set_viewport_size({"width": 900, "height": 700})
    try:
        _open(browser, files["pages"]["sweep"])
        boxes = browser.evaluate("""Object.fromEntries(['controls', 'layers', 'goto', 'map',
            'readout', 'pendulum'].map((id) => { const r = document.getElementById(id)
            .getBoundingClientRect(); return [id, [r.left, r.top, r.right, r.bottom]]; }))""")
        for name, (left, top, right, bottom) in boxes.items():
            assert 0 <= left < right <= 900 and 0 <= top < bottom <= 700, (name, boxes)
        assert boxes["readout"][0] >= boxes["map"][2]  # beside the map, not under it
        assert browser.evaluate("document.documentElement.scrollWidth") <= 900
    finally:
        browser.page.set_viewport_size({"width": 1180, "height": 660})
    assert browser.errors == []


@needs_browser
def test_screenshot(files, browser, tmp_path):
    """A picture of the page after a click. ATLAS_UPDATE_SCREENSHOT=1 keeps it as
    docs/images/view.png for the README; ATLAS_UPDATE_SCREENSHOT=outputs/default.h5 takes it
    of that atlas instead of the test's."""
    update = os.environ.get("ATLAS_UPDATE_SCREENSHOT", "")
    page = files["pages"]["single"]
    if update.endswith(".h5"):
        page = write_view(update, tmp_path / "shown.html")
    browser.page.set_viewport_size({"width": 1180, "height": 720})
    _open(browser, page)
    xy = browser.evaluate("atlasView.clientXY(-1.0, 2.5)")
    browser.click(xy["x"], xy["y"])
    assert _readout(browser)["orbitStatus"] == "trapped"
    time.sleep(1.2)  # let the pendulum swing a little
    png = browser.page.screenshot()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
    target = REPO / "docs" / "images" / "view.png" if update else tmp_path / "view.png"
    target.write_bytes(png)


# ---- a torque atlas -------------------------------------------------------------------

@pytest.fixture(scope="module")
def swing(swing_atlas, tmp_path_factory):
    """A small atlas of the bistable swing pendulum (tilted wells and the running cycle:
    conftest's, shared) and its page."""
    return swing_atlas, write_view(swing_atlas, tmp_path_factory.mktemp("swing") / "swing.html")


def test_torque_page_carries_the_sweeps_certificates(swing):
    """τ, the kernels' tilted trap level and the very running barrier the sweep gave its
    kernels (g bit for bit, rebuilt from the stored cycle), the cycle to draw; still small."""
    import base64
    import zlib

    from atlas.labels.trap import energy_cap
    from atlas.physics.running import limit_cycle, running_barrier

    path, page = swing
    p = _data(page)["points"][0]
    assert p["torque"] == 0.5 and p["cap"] == energy_cap(0.01, 0.05, 1.0, 0.5)
    assert p["shift"] == pytest.approx(np.arcsin(0.5), abs=0)
    ref = running_barrier(0.05, 1.0, 0.5, limit_cycle(0.05, 1.0, 0.5), dt=0.01)
    b = p["barrier"]
    g = np.frombuffer(zlib.decompress(base64.b64decode(b["g"])), "<f8")
    np.testing.assert_array_equal(g, ref.g)
    assert (b["theta0"], b["top"], b["direction"]) == (ref.theta0, ref.top, 1)
    cycle = atlas.open(path)["limit_cycle"].to_dataset()
    assert p["cycle"]["theta"][0] == round(float(cycle["theta"][0]), 4)
    assert p["cycle"]["theta"][-1] == round(float(cycle["theta"][-1]), 4)
    assert len(p["cycle"]["theta"]) < 300 and page.stat().st_size < 120_000  # 20 kB: script
    assert "running" in _data(page)["status_names"].values()


def rewritten(source: Path, output: Path, change) -> Path:
    """A copy of the atlas file ``source`` at ``output`` with ``change(h5py.File)`` applied."""
    import shutil

    import h5py

    shutil.copyfile(source, output)
    with h5py.File(output, "a") as f:
        change(f)
    return output


def tamper(f) -> None:
    """Change the stored certificate of a one-point torque atlas (the shape of a valid one
    kept: g scaled, still below the top, which is raised; cap and margin changed): numbers
    no run would build."""
    node = f["limit_cycle"]
    node["barrier_g"][...] = 0.75 * node["barrier_g"][...]
    node.attrs["barrier_top"] = 1.25 * node.attrs["barrier_top"]
    f["trap_energy_cap"][()] = 0.5 * f["trap_energy_cap"][()]
    f["trap_margin"][()] = 3.0 * f["trap_margin"][()]


def as_format_3(f) -> None:
    """What a format-3 writer left of a one-point torque atlas: no cap, no barrier."""
    f.attrs["format_version"] = np.int64(3)
    del f["trap_energy_cap"]
    node = f["limit_cycle"]
    del node["barrier_g"], node["barrier_sample"]
    for name in [name for name in node.attrs if name.startswith("barrier_")]:
        del node.attrs[name]


def test_the_page_carries_the_stored_certificate_nothing_rebuilt(swing_atlas, tmp_path):
    """The page takes the certificate from the file, as the run stored it: with the barrier,
    the cap and the margin changed in a copy, the page carries the changed numbers bit for
    bit (a page that rebuilt or recomputed them would carry the run's)."""
    import base64
    import zlib

    path = rewritten(swing_atlas, tmp_path / "tampered.h5", tamper)
    stored = atlas.open(path)
    node = stored["limit_cycle"].to_dataset()
    root = stored.to_dataset(inherit=False)
    p = _data(write_view(path))["points"][0]
    g = np.frombuffer(zlib.decompress(base64.b64decode(p["barrier"]["g"])), "<f8")
    np.testing.assert_array_equal(g, node["barrier_g"].values)
    assert p["barrier"]["top"] == node.attrs["barrier_top"]
    assert p["cap"] == float(root["trap_energy_cap"])
    assert p["margin"] == float(root["trap_margin"])
    original = _data(write_view(swing_atlas, tmp_path / "original.html"))["points"][0]
    assert p["cap"] == 0.5 * original["cap"] and p["barrier"]["g"] != original["barrier"]["g"]
    stored.close()


def test_a_format_3_file_is_refused_with_one_line(swing_atlas, tmp_path, capsys):
    """atlas view refuses a file of format 3 (no stored certificate) with one line saying how
    to upgrade it, and writes no page; atlas info and atlas plot still read it."""
    path = rewritten(swing_atlas, tmp_path / "old.h5", as_format_3)
    assert main(["view", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "written in format 3" in err
    assert "does not store the certificate" in err and "(`atlas run CONFIG`)" in err
    assert not path.with_suffix(".html").exists()
    assert main(["info", str(path)]) == 0 and "alpha" in capsys.readouterr().out
    assert main(["plot", str(path)]) == 0 and path.with_suffix(".png").exists()


def _uniform_cells(ds, code, k=None):
    """Grid indices (j, i) whose 3 × 3 neighbourhood all has status ``code`` (and well k)."""
    status, att = ds["status"].values, ds["attractor"].values
    good = status == code if k is None else (np.isin(status, (0, 3)) & (att == k))
    inner = np.zeros_like(good)
    inner[1:-1, 1:-1] = True
    for dj in (-1, 0, 1):
        for di in (-1, 0, 1):
            inner &= np.roll(good, (dj, di), axis=(0, 1))
    return np.argwhere(inner)


@pytest.mark.slow
@needs_browser
def test_torque_page_clicks_agree_with_the_file(swing, browser):
    """Clicks on a torque page: a point the file labels running is certified running in the
    browser (and shown as the file's), a point in a well's basin ends in the file's well; the
    page's orbits from grid points inside uniform patches get the file's labels, and the
    state at the certificate equals atlas.commands.orbit_integrate.integrate's (the same RK4
    map and tests)."""
    from atlas.commands.orbit import running_barrier_for
    from atlas.commands.orbit_integrate import integrate

    path, page = swing
    ds = atlas.open(path).to_dataset(inherit=False)
    th, v = ds["theta0"].values, ds["theta_dot0"].values
    _open(browser, page)
    assert "θ* + 2πk" in browser.evaluate("document.getElementById('legend').textContent")
    running = _uniform_cells(ds, 4)
    well = _uniform_cells(ds, None, k=0)
    assert len(running) and len(well)
    for (j, i), expect in ((running[len(running) // 2], "running"),
                           (well[len(well) // 2], "trapped")):
        xy = browser.evaluate(f"atlasView.clientXY({float(th[i])!r}, {float(v[j])!r})")
        browser.click(xy["x"], xy["y"])
        r = _readout(browser)
        assert r["orbitStatus"] == expect, (th[i], v[j], r)
        if expect == "running":
            assert r["gridStatus"] == "running" and r["orbitDirection"] == "1"
            assert r["orbitK"] == "" and r["gridK"] == ""
            assert browser.evaluate("document.querySelector('#readout .agree').textContent") \
                == "running, as the stored label"
        else:
            k = int(ds["attractor"].values[j, i])
            assert int(r["orbitK"]) == k == int(r["gridK"])
    # the page's integrator from exact grid points of uniform patches: the file's labels
    rng = np.random.default_rng(4)
    cells = np.concatenate([running[rng.choice(len(running), 20, replace=False)],
                            _uniform_cells(ds, None, k=0)[:10]])
    pairs = json.dumps([[float(th[i]), float(v[j])] for j, i in cells])
    got = browser.evaluate(f"{pairs}.map(([a, b]) => atlasView.orbit(a, b))")
    status = ds["status"].values[cells[:, 0], cells[:, 1]]
    names = {0: "trapped", 3: "trapped", 4: "running"}
    assert [g["status"] for g in got] == [names[int(s)] for s in status]
    assert [g["k"] for g in got if g["status"] == "trapped"] == \
        ds["attractor"].values[cells[:, 0], cells[:, 1]][status != 4].tolist()
    np.testing.assert_allclose([g["t_trap"] for g in got],
                               ds["t_trap"].values[cells[:, 0], cells[:, 1]], atol=0.16 + 1e-9)
    barrier, _ = running_barrier_for(0.05, 1.0, 0.5, 0.01)
    for g in got[::3]:
        ref = integrate(g["theta0"], g["theta_dot0"], running=barrier, **SWING)
        assert ref.t_trap == pytest.approx(g["t_trap"]) and ref.k == g["k"]
        i = ref.trap_index
        assert abs(ref.theta[i] - g["theta_trap"]) + abs(ref.theta_dot[i] - g["theta_dot_trap"]) \
            < 1e-9
    assert browser.dialogs == [] and browser.errors == []
