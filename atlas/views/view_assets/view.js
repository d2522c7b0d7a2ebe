"use strict";
// atlas view: the basin map, its key, a hover readout, orbits clicked or typed. Every string
// from the file goes through textContent; the data come from the JSON block above, parsed,
// never evaluated.
(function () {
  const D = JSON.parse(document.getElementById("atlas-data").textContent);
  const $ = (id) => document.getElementById(id);
  const TWO_PI = 2 * Math.PI, INV_TWO_PI = 1 / TWO_PI;
  const [TH0, TH1, NT] = D.theta0, [V0, V1, NV] = D.theta_dot0;
  const HT = (TH1 - TH0) / (NT - 1), HV = (V1 - V0) / (NV - 1);
  // The drawn window: the image spans the grid cells' edges (grid point i at the centre of
  // pixel column i). Its period: the whole turns (2π each) that fit in its θ width; an orbit
  // is drawn shifted by multiples of it wherever it leaves the window (0: narrower than one
  // turn, drawn as it is and clipped).
  const A = TH0 - HT / 2, B = TH1 + HT / 2, VA = V0 - HV / 2, VB = V1 + HV / 2;
  const PERIOD = TWO_PI * Math.floor((B - A) * INV_TWO_PI + 1e-9);
  const M = { left: 64, right: 14, top: 12, bottom: 46 };
  let W = 700, H = 420, CW = 0, CH = 0;
  const NAMES = D.status_names;
  const dpr = window.devicePixelRatio || 1;
  //: After a trap the orbit is followed until E_k is below SETTLE times the saddle's energy;
  //: after the running certificate at least MIN_TURNS turns, and until two successive turns
  //: cross θ_cert (mod 2π) at speeds within SETTLE of each other (the cycle reached), as
  //: atlas.commands.orbit_integrate.integrate.
  const SETTLE = 1e-3, MIN_TURNS = 2;

  const xOf = (th) => M.left + (th - A) / (B - A) * W;
  const yOf = (v) => M.top + H - (v - VA) / (VB - VA) * H;
  const thOf = (x) => A + (x - M.left) / W * (B - A);
  const vOf = (y) => VA + (M.top + H - y) / H * (VB - VA);
  const clamp = (x, lo, hi) => Math.min(hi, Math.max(lo, x));
  const minus = (s) => s.replace(/-/g, "−");
  const signed = (k) => (k > 0 ? "+" : "") + minus(String(k));
  const fix = (x, n) => minus(x.toFixed(n));
  const sci = (x) => (x === 0 ? "0" : minus(x.toPrecision(3)));
  // decimals that resolve a grid step h (at least 2, at most 12)
  const decimals = (h) => clamp(Math.ceil(-Math.log10(Math.abs(h))) + 1, 2, 12);
  const DT_DEC = decimals(HT), DV_DEC = decimals(HV);
  // (θ, θ̇) with units, to the grid's resolution (hover) or finer (at least 4 decimals)
  const coords = (th, v, dot, fine = true) => "θ" + (dot ? "0" : "") + " = " +
    fix(th, fine ? Math.max(4, DT_DEC) : DT_DEC) + " rad, θ̇" + (dot ? "0" : "") + " = " +
    fix(v, fine ? Math.max(4, DV_DEC) : DV_DEC) + " rad/s";
  const inside = (th, v) => th >= A && th <= B && v >= VA && v <= VB;

  // Every colour comes from atlas.views.style through the data (the PNGs' own): a well's
  // colour is looked up in the palette's tables as well_colour does (a function of k alone,
  // repeating every `cycle` wells on each side); the time and distance layers interpolate
  // the PNGs' colour maps, given as equally spaced tables ("rrggbb" after "rrggbb").
  const hexRgb = (c) => [1, 3, 5].map((i) => parseInt(c.slice(i, i + 2), 16));
  function wellColour(k) {
    const p = D.palette;
    return k === 0 ? p.zero : (k > 0 ? p.positive : p.negative)[(Math.abs(k) - 1) % p.cycle];
  }
  const SCALES = {};
  for (const [name, table] of Object.entries(D.colormaps)) {
    SCALES[name] = Array.from({ length: table.length / 6 },
                              (_, i) => hexRgb("#" + table.slice(6 * i, 6 * i + 6)));
  }
  function scaleColour(name, f) {
    const t = SCALES[name], x = clamp(f, 0, 1) * (t.length - 1);
    const i = Math.min(t.length - 2, Math.floor(x)), u = x - i;
    return t[i].map((c, n) => Math.round(c + u * (t[i + 1][n] - c)));
  }

  // θ drawn in the window: θ itself where it is inside, else shifted by a multiple of PERIOD
  // into it (the map's pictures repeat every 2π in θ, one well further per turn).
  function wrap(th) {
    if (PERIOD === 0 || (th >= A && th <= B)) return th;
    return th > B ? th - PERIOD * Math.ceil((th - B) / PERIOD)
      : th + PERIOD * Math.ceil((A - th) / PERIOD);
  }

  function setup(canvas, w, h) {
    canvas.style.width = w + "px"; canvas.style.height = h + "px";
    canvas.width = Math.round(w * dpr); canvas.height = Math.round(h * dpr);
    const ctx = canvas.getContext("2d");
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    return ctx;
  }
  let mapCtx = null, ovCtx = null;
  // The map fills the figure's width; its height is 0.6 of that, less where the window is
  // short, so that the map, the hover line and the key (as built) fit on one screen.
  function layout() {
    const fig = $("figure"), width = Math.max(220, fig.clientWidth);
    M.left = width < 560 ? 50 : 64;
    W = Math.max(150, Math.floor(width - M.left - M.right));
    const top = fig.getBoundingClientRect().top + window.scrollY;
    const below = $("hover").offsetHeight + $("key").offsetHeight + 16;
    const room = window.innerHeight - top - M.top - M.bottom - below;
    H = Math.round(Math.max(Math.min(0.6 * W, room), Math.min(0.6 * W, 180)));
    CW = M.left + W + M.right; CH = M.top + H + M.bottom;
    $("stage").style.width = CW + "px"; $("stage").style.height = CH + "px";
    mapCtx = setup($("map"), CW, CH); ovCtx = setup($("overlay"), CW, CH);
  }
  const penCtx = setup($("pendulum"), 220, 220);

  async function inflate(b64) {
    const bin = atob(b64), bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
    return new Response(stream).arrayBuffer();
  }
  // The basin image starts decoding at once: an image being fetched delays the load event,
  // so the map is drawn (its onload) before the page's load event.
  function startImage(p) {
    if (!p.img) {
      p.img = new Image();
      p.img.onload = () => { if (P === p) drawMap(); };
      p.img.src = p.png;
    }
  }
  async function loadGrid(p) {
    const [k, s, t, d] = await Promise.all(
      [p.attractor, p.status, p.t_trap, p.distance].map(inflate));
    p.grid = { k: new Int16Array(k), status: new Int8Array(s), trap: new Uint32Array(t),
               dist: new Uint16Array(d) };
    // the running barrier's lower curve: float64, exactly the numbers the sweep verified
    if (p.barrier) p.barrierG = new Float64Array(await inflate(p.barrier.g));
    return p;
  }

  // The stored values at the grid point nearest (th, v).
  function gridAt(p, th, v) {
    const i = clamp(Math.round((th - TH0) / HT), 0, NT - 1);
    const j = clamp(Math.round((v - V0) / HV), 0, NV - 1);
    const n = j * NT + i, q = p.grid.dist[n], t = p.grid.trap[n];
    const status = p.grid.status[n];
    return { i, j, theta: TH0 + i * HT, theta_dot: V0 + j * HV, status: NAMES[status],
             k: status === 0 || status === 3 ? p.grid.k[n] : null,
             t_trap: t === 0xFFFFFFFF ? null : t * D.check_every * D.dt,
             distance: q === 65535 ? null : q === 0 ? 0 : 2 ** (q / D.dist_steps - D.dist_offset) };
  }

  // The running certificate's lower curve at u (frame of positive rotation), interpolated as
  // the kernels' running test does (atlas.kernels.rk4.make_running_test).
  function lowerCurve(b, g, u) {
    const m = g.length - 1;
    let x = u - b.theta0;
    x = x - TWO_PI * Math.floor(x * INV_TWO_PI);
    const t = x * (m * INV_TWO_PI), i = Math.min(Math.max(Math.floor(t), 0), m - 1);
    return g[i] + (t - i) * (g[i + 1] - g[i]);
  }

  // One orbit of θ̈ = −ω0² sin θ − 2αθ̇ + τ: atlas's RK4 step (the file's method: "rk4", or
  // "rk4-trigfree" with cos θ, sin θ carried as state and re-synchronised from θ at every
  // trap test, atlas.kernels.trigfree), the (tilted) energy trap and then the running
  // certificate, tested every check_every steps in the kernels' order and arithmetic
  // (atlas.kernels.rk4). After the certificate the orbit is followed on for the picture
  // (SETTLE, MIN_TURNS above), at most to t_max.
  function integrate(theta0, thetaDot0, p) {
    const a = p.alpha, w = p.omega0, tq = p.torque || 0, dt = D.dt, ce = D.check_every;
    const w2 = w * w, a2 = 2 * a, h2 = 0.5 * dt, h6 = dt / 6;
    const cap = p.cap === null ? -Infinity : p.cap, shift = p.shift, vers = p.vers;
    const b = p.barrier, g = p.barrierG, sign = b ? b.direction : 1;
    const nChecks = Math.max(1, Math.ceil(D.t_max / (dt * ce) - 1e-9));
    let th = theta0, v = thetaDot0;
    const path = [th, v];
    const rk4 = () => {  // with τ = 0, τ − x is −x exactly: the untilted step
      const k1t = v, k1v = tq - w2 * Math.sin(th) - a2 * v;
      const k2t = v + h2 * k1v, k2v = tq - w2 * Math.sin(th + h2 * k1t) - a2 * k2t;
      const k3t = v + h2 * k2v, k3v = tq - w2 * Math.sin(th + h2 * k2t) - a2 * k3t;
      const k4t = v + dt * k3v, k4v = tq - w2 * Math.sin(th + dt * k3t) - a2 * k4t;
      th += h6 * (k1t + 2 * (k2t + k3t) + k4t);
      v += h6 * (k1v + 2 * (k2v + k3v) + k4v);
      path.push(th, v);
    };
    let c = 0, s = 0;
    const trigfree = () => {  // RK4 on (θ, θ̇, c, s): c' = −s θ̇, s' = c θ̇
      const k1v = tq - w2 * s - a2 * v, k1c = -s * v, k1s = c * v;
      const v2 = v + h2 * k1v, c2 = c + h2 * k1c, s2 = s + h2 * k1s;
      const k2v = tq - w2 * s2 - a2 * v2, k2c = -s2 * v2, k2s = c2 * v2;
      const v3 = v + h2 * k2v, c3 = c + h2 * k2c, s3 = s + h2 * k2s;
      const k3v = tq - w2 * s3 - a2 * v3, k3c = -s3 * v3, k3s = c3 * v3;
      const v4 = v + dt * k3v, c4 = c + dt * k3c, s4 = s + dt * k3s;
      const k4v = tq - w2 * s4 - a2 * v4, k4c = -s4 * v4, k4s = c4 * v4;
      th += h6 * (v + 2 * (v2 + v3) + v4);
      v += h6 * (k1v + 2 * (k2v + k3v) + k4v);
      c += h6 * (k1c + 2 * (k2c + k3c) + k4c);
      s += h6 * (k1s + 2 * (k2s + k3s) + k4s);
      path.push(th, v);
    };
    const steps = () => {  // check_every steps from a trap test
      if (D.method === "rk4-trigfree") {
        c = Math.cos(th); s = Math.sin(th);
        for (let i = 0; i < ce; i++) trigfree();
      } else {
        for (let i = 0; i < ce; i++) rk4();
      }
    };
    const energy = () => {
      if (D.method === "rk4-trigfree") {  // as the re-synchronisation: 1 − cos θ of the whole θ
        const h = Math.sin(0.5 * th), vt = 2 * (h * h);
        if (tq === 0) return [Math.floor(th * INV_TWO_PI + 0.5), 0.5 * v * v + w2 * vt];
        const k = Math.floor((th + shift) * INV_TWO_PI + 0.5), phi = th - TWO_PI * k;
        return [k, 0.5 * v * v + w2 * (vt - vers) - tq * (phi - shift)];
      }
      if (tq === 0) {
        const k = Math.floor(th * INV_TWO_PI + 0.5), s = Math.sin(0.5 * (th - TWO_PI * k));
        return [k, 0.5 * v * v + 2 * w2 * s * s];
      }
      const k = Math.floor((th + shift) * INV_TWO_PI + 0.5), phi = th - TWO_PI * k;
      const s = Math.sin(0.5 * phi);
      return [k, 0.5 * v * v + w2 * (2 * (s * s) - vers) - tq * (phi - shift)];
    };
    const running = () => {
      if (!b) return false;
      const u = sign * v;
      return u <= b.top && u >= lowerCurve(b, g, sign * th);
    };
    const r = { theta0, theta_dot0: thetaDot0, status: "unresolved", k: null, t_trap: null,
                energy: null, cap: p.cap, margin: p.margin, theta_trap: null,
                theta_dot_trap: null, direction: 0, turns: 0, settled: false };
    for (let j = 0; j <= nChecks; j++) {
      if (!Number.isFinite(th) || !Number.isFinite(v)) { r.status = "nonfinite"; break; }
      const [k, e] = energy();
      if (e < cap) {
        Object.assign(r, { status: "trapped", k, t_trap: j * ce * dt, energy: e,
                           theta_trap: th, theta_dot_trap: v });
        break;
      }
      if (running()) {
        Object.assign(r, { status: "running", t_trap: j * ce * dt, theta_trap: th,
                           theta_dot_trap: v, direction: b.direction,
                           lower: sign * lowerCurve(b, g, sign * th) });
        break;
      }
      if (j === nChecks) break;
      steps();
    }
    r.trap_index = path.length / 2 - 1;
    const limit = nChecks * ce;
    if (r.status === "trapped") {
      const level = SETTLE * (tq === 0 ? 2 * w2 : p.saddle_energy);
      while (path.length / 2 - 1 < limit && energy()[1] > level) steps();
      r.settled = energy()[1] <= level;
    } else if (r.status === "running") {
      // the return speeds at θ_cert + 2πn (linear between steps): the cycle is reached when
      // two successive ones agree to SETTLE
      const start = th;
      let last = null;
      while (path.length / 2 - 1 < limit && !(r.turns >= MIN_TURNS && r.settled)) {
        const from = path.length / 2 - 1;
        steps();
        for (let i = from + 1; i <= path.length / 2 - 1; i++) {
          const x0 = sign * (path[2 * i - 2] - start), x1 = sign * (path[2 * i] - start);
          while (x0 < TWO_PI * (r.turns + 1) && x1 >= TWO_PI * (r.turns + 1)) {
            const f = (TWO_PI * (r.turns + 1) - x0) / (x1 - x0);
            const u = path[2 * i - 1] + f * (path[2 * i + 1] - path[2 * i - 1]);
            r.settled = last !== null && Math.abs(u - last) < SETTLE * Math.abs(u);
            last = u; r.turns++;
          }
        }
      }
    }
    r.theta_end = th; r.theta_dot_end = v;
    r.path = Float64Array.from(path);
    return r;
  }

  // ---- drawing ------------------------------------------------------------------------
  let P = null, index = 0, orbits = [], anim = null, layer = "basins";
  // what the last drawMap drew of the orbits (CSS px, and θ before and after the wrap)
  let drawn = null;

  // nπ/d as a tick label: "0", "π", "−2π", "π/2", "−3π/4"
  function piLabel(n, d = 1) {
    if (n === 0) return "0";
    let x = Math.abs(n), y = d;
    while (y) [x, y] = [y, x % y];  // x: gcd(|n|, d)
    const a = Math.abs(n) / x, b = d / x;
    return (n < 0 ? "−" : "") + (a === 1 ? "" : a) + "π" + (b === 1 ? "" : "/" + b);
  }
  // An orbit's phase curve, θ wrapped into the window (the line breaks where it jumps).
  function drawPath(c, r, n, latest) {
    const path = r.path;
    const lines = latest ? [["#fff", 3.5], ["#000", 1.6]] : [["#fff", 2.6], ["#000", 1]];
    for (const [style, width] of lines) {
      c.strokeStyle = style; c.lineWidth = width; c.beginPath();
      let turn = null;
      for (let i = 0; i < path.length; i += 2) {
        const th = wrap(path[i]), x = xOf(th), y = yOf(path[i + 1]);
        const now = PERIOD ? Math.round((th - path[i]) / PERIOD) : 0;
        if (now !== turn) { c.moveTo(x, y); turn = now; } else c.lineTo(x, y);
        drawn.xmin = Math.min(drawn.xmin, x); drawn.xmax = Math.max(drawn.xmax, x);
        drawn.thmin = Math.min(drawn.thmin, path[i]); drawn.thmax = Math.max(drawn.thmax, path[i]);
        if (now) drawn.shifted = true;
      }
      c.stroke();
    }
    const x0 = xOf(wrap(path[0])), y0 = yOf(path[1]);
    const m = D.markers.start, side = m.size * 4 / 3 * (latest ? 1 : 0.8);  // pt → px
    c.fillStyle = m.fill; c.strokeStyle = m.edge; c.lineWidth = m.width * 4 / 3;
    c.beginPath(); c.rect(x0 - side / 2, y0 - side / 2, side, side); c.fill(); c.stroke();
    if (orbits.length > 1) {
      c.font = "bold 12px 'DejaVu Sans', system-ui, sans-serif";
      c.textAlign = "left"; c.textBaseline = "bottom";
      c.lineWidth = 3; c.strokeStyle = "#fff"; c.strokeText(String(n), x0 + 5, y0 - 3);
      c.fillStyle = "#000"; c.fillText(String(n), x0 + 5, y0 - 3);
    }
    if (r.status === "trapped" || r.status === "running") {
      const x = xOf(wrap(r.theta_trap)), y = yOf(r.theta_dot_trap);
      c.strokeStyle = "#000"; c.lineWidth = latest ? 2 : 1.5;
      c.beginPath(); c.moveTo(x - 4, y - 4); c.lineTo(x + 4, y + 4);
      c.moveTo(x - 4, y + 4); c.lineTo(x + 4, y - 4); c.stroke();
    }
  }

  // The time and distance layers: one pixel per grid point, in the PNGs' colour maps and on
  // their log scales, over the stored values above the floor (0; for the distance, d_cert
  // where measured): t_trap = 0 (certified at once) at the dark end, as in the PNG; the "no label"
  // white where nothing is stored (no label certified; no distance); the PNG's d_cert colour
  // where a state is closer than d_cert to a boundary.
  function layerImage(p, name) {
    p.layers = p.layers || {};
    if (p.layers[name]) return p.layers[name];
    const n = NT * NV, values = new Float64Array(n);
    const floor = name === "distance" && p.d_cert !== null ? p.d_cert : 0;
    for (let m = 0; m < n; m++) {
      if (name === "t_trap") {
        const t = p.grid.trap[m];
        values[m] = t === 0xFFFFFFFF ? NaN : t * D.check_every * D.dt;
      } else {
        const q = p.grid.dist[m];
        values[m] = q === 65535 ? NaN : q === 0 ? 0 : 2 ** (q / D.dist_steps - D.dist_offset);
      }
    }
    const finite = Array.from(values).filter((v) => v > floor).map(Math.log10)
      .sort((x, y) => x - y);
    // the PNGs' limits (atlas.views.maps): t_trap from its least to its greatest value, the
    // distance from its 1st to its 99th percentile; a decade at least
    const q = (f) => finite[Math.min(finite.length - 1, Math.floor(f * finite.length))];
    const [a, b] = name === "t_trap" ? [0, 1] : [0.01, 0.99];
    const lo = finite.length ? q(a) : -3, hi = Math.max(finite.length ? q(b) : 0, lo + 1);
    const canvas = document.createElement("canvas");
    canvas.width = NT; canvas.height = NV;
    const ctx = canvas.getContext("2d"), img = ctx.createImageData(NT, NV);
    const blank = hexRgb(D.no_label_color), nearRgb = hexRgb(D.near_boundary_color);
    let blanks = false, near = false;
    for (let j = 0; j < NV; j++) {
      for (let i = 0; i < NT; i++) {
        const val = values[j * NT + i], o = 4 * ((NV - 1 - j) * NT + i);
        let rgb;
        if (Number.isNaN(val)) { rgb = blank; blanks = true; }
        else if (floor > 0 && val <= floor) { rgb = nearRgb; near = true; }
        else rgb = scaleColour(name, (Math.log10(val) - lo) / (hi - lo));
        img.data[o] = rgb[0]; img.data[o + 1] = rgb[1]; img.data[o + 2] = rgb[2]; img.data[o + 3] = 255;
      }
    }
    ctx.putImageData(img, 0, 0);
    p.layers[name] = { canvas, lo, hi, blanks, near };
    return p.layers[name];
  }

  function drawMap() {
    const c = mapCtx;
    c.clearRect(0, 0, CW, CH);
    c.imageSmoothingEnabled = false;
    const shown = layer === "basins" || !P.grid ? "basins" : layer;
    if (shown === "basins") {
      if (P.img && P.img.complete && P.img.naturalWidth) {
        c.drawImage(P.img, M.left, M.top, W, H);
        $("map").dataset.drawn = "basins";
      }
    } else {
      c.drawImage(layerImage(P, shown).canvas, M.left, M.top, W, H);
      $("map").dataset.drawn = shown;
    }
    drawAxes(c);  // the frame under the markers that sit on it
    c.save();
    c.beginPath(); c.rect(M.left, M.top, W, H); c.clip();
    // the boundaries: full strength over the basins, faint over the time and distance layers
    const line = shown === "basins" ? D.separatrix : D.separatrix_faint;
    c.globalAlpha = line.alpha; c.strokeStyle = line.color;
    c.lineWidth = shown === "basins" ? 1 : 0.8;
    for (const [ts, vs] of P.curves) {
      c.beginPath(); c.moveTo(xOf(ts[0]), yOf(vs[0]));
      for (let i = 1; i < ts.length; i++) c.lineTo(xOf(ts[i]), yOf(vs[i]));
      c.stroke();
    }
    c.globalAlpha = 1;
    if (shown === "basins" && P.band_labels.length) {  // many wells: each band named
      c.font = "bold 12px 'DejaVu Sans', system-ui, sans-serif";
      c.textAlign = "center"; c.textBaseline = "middle"; c.lineWidth = 3;
      for (const [k, th, v] of P.band_labels) {
        c.strokeStyle = "#fff"; c.strokeText(signed(k), xOf(th), yOf(v));
        c.fillStyle = "#000"; c.fillText(signed(k), xOf(th), yOf(v));
      }
    }
    if (P.cycle) {  // the running limit cycle, dashed, repeated 2π-periodically
      const ts = P.cycle.theta, vs = P.cycle.theta_dot;
      const lo = Math.min(ts[0], ts[ts.length - 1]), hi = Math.max(ts[0], ts[ts.length - 1]);
      c.strokeStyle = "#000"; c.lineWidth = 1.6; c.setLineDash([7, 4]);
      for (let n = Math.floor((TH0 - hi) / TWO_PI); n <= Math.ceil((TH1 - lo) / TWO_PI); n++) {
        c.beginPath(); c.moveTo(xOf(ts[0] + n * TWO_PI), yOf(vs[0]));
        for (let i = 1; i < ts.length; i++) c.lineTo(xOf(ts[i] + n * TWO_PI), yOf(vs[i]));
        c.stroke();
      }
      c.setLineDash([]);
    }
    c.restore(); drawMarkers(c);  // under the orbits, over the frame
    c.save(); c.beginPath(); c.rect(M.left, M.top, W, H); c.clip();
    drawn = { xmin: Infinity, xmax: -Infinity, thmin: Infinity, thmax: -Infinity,
              shifted: false, left: M.left, right: M.left + W, A, B, period: PERIOD };
    orbits.forEach((r, n) => drawPath(c, r, n + 1, n === orbits.length - 1));
    // an orbit that settles whole turns away from where it is drawn: its well named there
    c.font = "bold 12px 'DejaVu Sans', system-ui, sans-serif";
    c.textAlign = "left"; c.textBaseline = "top"; c.lineWidth = 3;
    for (const r of orbits) {
      const end = r.path[r.path.length - 2];
      if (r.status !== "trapped" || wrap(end) === end) continue;
      const x = xOf(wrap(end)) + 8, y = yOf(r.path[r.path.length - 1]) + 8;
      const turns = Math.abs(Math.round((end - wrap(end)) / TWO_PI));
      const text = "well " + signed(r.k) + ", drawn " + turns + " turn" + (turns > 1 ? "s" : "") +
        " away";
      c.strokeStyle = "#fff"; c.strokeText(text, x, y);
      c.fillStyle = "#000"; c.fillText(text, x, y);
    }
    c.restore();
  }
  // The critical points as every figure marks them (D.markers: atlas.views.style's), not
  // clipped to the plot, so that a saddle on the window's edge (±3π) shows whole; only those
  // in the window (to rounding), as critical_point_markers: none in a zoom off θ̇ = 0.
  function drawMarkers(c) {
    const et = 1e-9 * (TH1 - TH0), ev = 1e-9 * (V1 - V0);
    if (V0 - ev > 0 || V1 + ev < 0) return;
    for (const [which, list] of [["attractor", P.attractors], ["saddle", P.saddles]]) {
      const m = D.markers[which], px = 4 / 3;  // 1 pt = 4/3 CSS px
      c.fillStyle = m.fill; c.strokeStyle = m.edge; c.lineWidth = m.width * px;
      for (const t of list.filter((x) => x >= TH0 - et && x <= TH1 + et)) {
        c.beginPath(); c.arc(xOf(t), yOf(0), m.size * px / 2, 0, TWO_PI); c.fill(); c.stroke();
      }
    }
  }
  function drawAxes(c) {
    c.strokeStyle = "#333"; c.fillStyle = "#222"; c.lineWidth = 1;
    c.strokeRect(M.left, M.top, W, H);
    c.font = "12px 'DejaVu Sans', system-ui, sans-serif"; c.textAlign = "center"; c.textBaseline = "top";
    const xTick = (t, x) => {
      c.beginPath(); c.moveTo(x, M.top + H); c.lineTo(x, M.top + H + 5); c.stroke();
      c.fillText(t, x, M.top + H + 7);
    };
    // θ ticks at multiples of π, of π/2 or of π/4: the coarsest giving at least 4 ticks
    const d = [1, 2, 4].find((f) => Math.floor(TH1 * f / Math.PI + 1e-9) -
      Math.ceil(TH0 * f / Math.PI - 1e-9) >= 3) || 4;
    const n0 = Math.ceil(TH0 * d / Math.PI - 1e-9), n1 = Math.floor(TH1 * d / Math.PI + 1e-9);
    let xName = "θ0 [rad]";
    if (n1 > n0) {
      const every = Math.max(1, Math.ceil((n1 - n0 + 1) / Math.max(2, Math.floor(W / 55))));
      for (let n = n0; n <= n1; n++) if (n % every === 0) xTick(piLabel(n, d), xOf(n * Math.PI / d));
    } else {
      xName = plainTicks(TH0, TH1, W / 80, xOf, xTick, "θ0", "rad");
    }
    c.textAlign = "right"; c.textBaseline = "middle";
    const yName = plainTicks(V0, V1, H / 45, yOf, (t, y) => {
      c.beginPath(); c.moveTo(M.left - 5, y); c.lineTo(M.left, y); c.stroke();
      c.fillText(t, M.left - 7, y);
    }, "θ̇0", "rad/s");
    c.textAlign = "center"; c.textBaseline = "bottom";
    c.fillText(xName, M.left + W / 2, CH - 4);
    c.save(); c.translate(14, M.top + H / 2); c.rotate(-Math.PI / 2);
    c.textBaseline = "middle"; c.fillText(yName, 0, 0); c.restore();
  }
  // Plain ticks of [lo, hi]; in a window too narrow for plain ticks to tell apart (a zoom)
  // the offsets from a reference near its centre, in units with an SI prefix, as
  // atlas.views.style.window_ticks: "θ̇0 − 2.4149382176 [µrad/s]", ticks −0.4 … 0.4.
  // Returns the axis's name with its unit.
  function plainTicks(lo, hi, count, pos, draw, name, unit) {
    const width = hi - lo, centre = 0.5 * (lo + hi);
    const power = clamp(3 * Math.floor(Math.log10(width) / 3), -15, 0);
    let ref = 0, refText = "", scale = 1, prefix = "";
    if (power < 0 || Math.abs(centre) > 100 * width) {
      if (Math.abs(centre) > 10 * width) {
        for (let n = 1; n <= 17; n++) {
          refText = centre.toPrecision(n);
          if (Math.abs(Number(refText) - centre) <= width * 1e-4) break;
        }
        ref = Number(refText); refText = String(ref);
      }
      scale = 10 ** power;
      prefix = { 0: "", "-3": "m", "-6": "µ", "-9": "n", "-12": "p", "-15": "f" }[power];
    }
    const a = (lo - ref) / scale, b = (hi - ref) / scale, span = b - a;
    const raw = span / Math.max(2, count), mag = 10 ** Math.floor(Math.log10(raw));
    const step = [1, 2, 2.5, 5, 10].map((f) => f * mag).find((s) => s >= raw);
    for (let n = Math.ceil(a / step - 1e-9); n * step <= b + 1e-9 * span; n++) {
      const t = n * step;  // whole multiples: 0 is 0, not the sum of steps
      draw(minus(String(Number(t.toPrecision(12)))), pos(ref + t * scale));
    }
    const shown = !ref ? name : ref > 0 ? name + " − " + refText : name + " + " + minus(refText).slice(1);
    return shown + " [" + prefix + unit + "]";
  }

  const bobColor = (r) => (r && r.status === "running" ? D.running_color
    : r && r.k !== null ? wellColour(r.k) : D.no_label_color);
  function drawPendulum(th, orbit) {
    const c = penCtx, cx = 110, cy = 100, r = 78;
    c.clearRect(0, 0, 220, 220);
    c.strokeStyle = "#ccc"; c.lineWidth = 1;
    c.beginPath(); c.arc(cx, cy, r, 0, TWO_PI); c.stroke();
    const x = cx + r * Math.sin(th), y = cy + r * Math.cos(th);
    c.strokeStyle = "#333"; c.lineWidth = 3;
    c.beginPath(); c.moveTo(cx, cy); c.lineTo(x, y); c.stroke();
    c.fillStyle = bobColor(orbit);
    c.beginPath(); c.arc(x, y, 11, 0, TWO_PI); c.fill();
    c.strokeStyle = "#000"; c.lineWidth = 1; c.stroke();
    c.fillStyle = "#000"; c.beginPath(); c.arc(cx, cy, 3, 0, TWO_PI); c.fill();
    c.font = "12px 'DejaVu Sans', system-ui, sans-serif"; c.textAlign = "center"; c.textBaseline = "top";
    c.fillText("turns: " + signed(Math.floor(th / TWO_PI + 0.5)), cx, 200);
  }

  function frame(now) {
    if (!anim) return;
    const r = anim.r, n = r.path.length / 2;
    const t = (now - anim.start) / 1000 * anim.speed;
    const i = Math.min(n - 1, Math.floor(t / D.dt));
    const th = r.path[2 * i], v = r.path[2 * i + 1];
    drawPendulum(th, r);
    ovCtx.clearRect(0, 0, CW, CH);
    ovCtx.save(); ovCtx.beginPath(); ovCtx.rect(M.left, M.top, W, H); ovCtx.clip();
    ovCtx.fillStyle = bobColor(r); ovCtx.strokeStyle = "#000";
    ovCtx.beginPath(); ovCtx.arc(xOf(wrap(th)), yOf(v), 6, 0, TWO_PI); ovCtx.fill(); ovCtx.stroke();
    ovCtx.restore();
    $("clock").textContent = "t = " + (i * D.dt).toFixed(2) + " s of " +
      ((n - 1) * D.dt).toFixed(1) + " s" + (anim.speed > 1 ? " (" + anim.speed.toFixed(1) +
      "× real time)" : "");
    if (i < n - 1) requestAnimationFrame(frame); else anim = null;
  }
  function animate(r) {
    const total = (r.path.length / 2 - 1) * D.dt;
    anim = { r, start: performance.now(), speed: Math.max(1, total / 12) };
    requestAnimationFrame(frame);
  }

  // ---- the key -------------------------------------------------------------------------
  function item(parent, swatch, text) {
    const span = document.createElement("span"), mark = document.createElement("i");
    span.className = "item"; mark.className = "swatch " + swatch.kind;
    if (swatch.color) mark.style.setProperty("--c", swatch.color);
    span.append(mark, document.createTextNode(text));
    parent.appendChild(span);
    return span;
  }
  function buildKey() {
    const key = $("key"), tilted = (P.torque || 0) !== 0;
    key.replaceChildren();
    const colours = document.createElement("div");
    colours.className = "colours";
    const title = document.createElement("b");
    if (layer === "basins" || !P.grid) {
      title.textContent = "Colour: the well k (rest state (" + (tilted ? "θ* + " : "") +
        "2πk, 0)) the orbit from each point reaches";
      colours.appendChild(title);
      P.key.wells.forEach((k) => {
        const s = item(colours, { kind: "fill", color: wellColour(k) }, "k = " + signed(k));
        s.dataset.k = String(k);
      });
      if (P.key.running) item(colours, { kind: "fill", color: D.running_color }, "running");
      if (P.key.unlabelled) item(colours, { kind: "fill", color: D.no_label_color }, "no certified label");
    } else {
      const L = layerImage(P, layer);
      title.textContent = layer === "t_trap" ? "Colour: the time to trap t_trap [s]" +
        (P.barrier ? " (or to the running certificate)" : "") + ", log scale"
        : "Colour: the distance to the nearest basin boundary (θ and θ̇ in rad and rad/s as " +
          "one unit), log scale over its 1st to 99th percentile";
      colours.appendChild(title);
      const bar = document.createElement("canvas"), bw = 220;
      bar.width = bw; bar.height = 12; bar.className = "bar";
      const bc = bar.getContext("2d");
      for (let x = 0; x < bw; x++) {
        const [r, g, b] = scaleColour(layer, x / (bw - 1));
        bc.fillStyle = "rgb(" + r + "," + g + "," + b + ")"; bc.fillRect(x, 0, 1, 12);
      }
      const lo = document.createElement("span"), hi = document.createElement("span");
      lo.textContent = "≤ " + sci(10 ** L.lo) + " "; hi.textContent = " ≥ " + sci(10 ** L.hi) +
        (layer === "t_trap" ? " s" : "");
      colours.append(lo, bar, hi);
      if (layer === "t_trap") {
        colours.append(document.createTextNode(" (t = 0, certified at once: the dark end) "));
      }
      if (L.blanks) {
        item(colours, { kind: "fill", color: D.no_label_color }, layer === "t_trap"
          ? "no label certified by t_max" : "no distance stored");
      }
      if (L.near) {
        item(colours, { kind: "fill", color: D.near_boundary_color }, "closer than d_cert = " +
          sci(P.d_cert) + " (labels certified for the RK4 map only)");
      }
    }
    key.appendChild(colours);
    const marks = document.createElement("div");
    marks.className = "marks";
    if (P.curves.length) {
      item(marks, { kind: "line", color: layer === "basins" ? D.separatrix.color : "#999" },
           "separatrices (basin boundaries)" + (layer === "basins" ? "" : ", faint"));
    }
    if (P.saddles.length) item(marks, { kind: "ring", color: D.markers.saddle.edge }, "saddles");
    if (P.attractors.length) {
      item(marks, { kind: "dot", color: D.markers.attractor.fill }, "attractors (rest states)");
    }
    if (P.cycle) item(marks, { kind: "dash", color: "#000" }, "running limit cycle");
    item(marks, { kind: "line", color: "#000" }, "orbit");
    item(marks, { kind: "square", color: D.markers.start.edge }, "its start");
    item(marks, { kind: "cross", color: "#000" }, "certified" + (P.barrier
      ? " (energy trap or running barrier)" : " (energy trap)"));
    key.appendChild(marks);
  }

  // ---- readout -------------------------------------------------------------------------
  const STATUS_WORDS = {
    trapped: "trapped, certified for the exact equation",
    near_boundary: "trapped, certified for the RK4 map only (closer than d_cert to a boundary)",
    running: "running, certified to converge to the running limit cycle",
    running_near_boundary: "running, certified for the RK4 map only (closer than d_cert to a boundary)",
    unresolved: "unresolved: not trapped by t_max",
    nonfinite: "non-finite: the orbit left the floating-point numbers",
  };
  const wellText = (k) => {
    const tilted = (P.torque || 0) !== 0;
    return "well k = " + signed(k) + ": rest at (" + (tilted
      ? (k === 0 ? "θ*" : "θ* " + (k < 0 ? "−" : "+") + " " + piLabel(Math.abs(2 * k))) +
        " = " + fix(P.shift + TWO_PI * k, 4) : piLabel(2 * k)) + ", 0)";
  };
  const runText = (d) => "running: converges to the limit cycle (direction " + signed(d) + ")";
  const distText = (d) => d === null ? "not stored" : sci(d) +
    " (Euclidean in (θ, θ̇), rad and rad/s as one unit)";

  // E_k against the trap's level, both to the same significant digits, as many as it takes
  // for the printed numbers to show the inequality, and the gap.
  function energyText(e, cap, capName) {
    let n = 3;
    while (n < 17 && !(Number(e.toPrecision(n)) < Number(cap.toPrecision(n)))) n++;
    return "E_k = " + minus(e.toPrecision(n)) + " < " + capName + " = " +
      minus(cap.toPrecision(n)) + ": below the level by " + sci(cap - e);
  }

  function table(sections) {
    const t = document.createElement("table");
    for (const [title, rows] of sections) {
      const tr = t.insertRow(), th = document.createElement("th");
      th.colSpan = 2; th.textContent = title; tr.appendChild(th);
      for (const [key, value, cls] of rows) {
        const row = t.insertRow();
        row.insertCell().textContent = key;
        const cell = row.insertCell(); cell.textContent = value;
        if (cls) cell.className = cls;
      }
    }
    return t;
  }
  function orbitSummary(r) {
    return r.status === "trapped" ? "well " + signed(r.k) : r.status === "running"
      ? "running (" + signed(r.direction) + ")" : r.status;
  }
  function readout() {
    const box = $("readout");
    const r = orbits[orbits.length - 1];
    if (!r) {
      box.replaceChildren(hint);
      Object.keys(box.dataset).filter((k) => k !== "ready").forEach((k) => delete box.dataset[k]);
      return;
    }
    const th = r.theta0, v = r.theta_dot0, tilted = (P.torque || 0) !== 0;
    const g = inside(th, v) && P.grid ? gridAt(P, th, v) : null;
    const sections = [];
    if (g) {
      let cert = STATUS_WORDS[g.status] || g.status;
      if (P.d_cert !== null && g.status !== "unresolved" && g.status !== "nonfinite") {
        cert += " (d_cert = " + sci(P.d_cert) + ")";
      }
      sections.push(["nearest grid point (stored in the file)", [
        ["grid point", coords(g.theta, g.theta_dot, true)],
        ["stored label", g.k !== null ? wellText(g.k) : g.status.startsWith("running") &&
          P.barrier ? runText(P.barrier.direction) : "none (" + g.status + ")"],
        ["status", cert],
        ["t_trap", g.t_trap === null ? "—" : g.t_trap.toFixed(2) + " s"],
        ["boundary distance", distText(g.distance)],
      ]]);
    }
    const orbit = [["from", coords(th, v, true) + (inside(th, v) ? ""
      : " (outside the map's window: no stored label)")]];
    if (r.status === "trapped") {
      orbit.push(["end state", "trapped in " + wellText(r.k) + " at t = " + r.t_trap.toFixed(2) + " s"],
        ["at the trap", coords(r.theta_trap, r.theta_dot_trap, false)],
        ["energy trap", energyText(r.energy, r.cap, tilted ? "ΔE(1 − m) − rounding"
          : "2ω0²(1 − m)") + "; m = " + sci(r.margin)]);
    } else if (r.status === "running") {
      const b = P.barrier, d = r.direction;
      orbit.push(["end state", runText(d) + ", certified at t = " + r.t_trap.toFixed(2) + " s"],
        ["at the certificate", coords(r.theta_trap, r.theta_dot_trap, false)],
        ["running barrier", (d > 0 ? "g(θ) = " + sci(r.lower) + " ≤ θ̇ ≤ top = " + sci(b.top)
          : "−top = " + sci(-b.top) + " ≤ θ̇ ≤ " + sci(r.lower) + " = −g(−θ)") +
         " [rad/s]: the RK4 map's orbit stays in the band around the limit cycle"],
        ["followed on", r.turns + " turns after the certificate" + (r.settled
          ? ", until two successive turns agree in θ̇ to " + SETTLE * 100 + " %: on the cycle"
          : ", to t_max")]);
    } else {
      orbit.push(["end state", r.status === "nonfinite" ? "left the finite numbers"
        : "not trapped by t_max = " + D.t_max + " s"]);
    }
    orbit.push(["last state drawn", coords(r.theta_end, r.theta_dot_end, false) + " at t = " +
      ((r.path.length / 2 - 1) * D.dt).toFixed(1) + " s"]);
    if (PERIOD && r.path.some((x, i) => i % 2 === 0 && (x < A || x > B))) {
      orbit.push(["drawn", "where θ leaves the window the curve is drawn shifted by whole " +
        "turns (multiples of " + piLabel(Math.round(PERIOD / Math.PI)) + ") back into it" +
        (r.status === "trapped" ? "; it settles at θ = " + fix(P.shift + TWO_PI * r.k, 4) +
         ", drawn at " + fix(wrap(P.shift + TWO_PI * r.k), 4) : "")]);
    } else if (!PERIOD) {
      orbit.push(["drawn", "the window is narrower than one turn: the curve is clipped to it"]);
    }
    if (g && g.k !== null && r.k !== null) {
      orbit.push(g.k === r.k ? ["agreement", "same well as the stored label", "agree"]
        : ["agreement", "a different well from the nearest grid point's: the point is near a basin boundary", "differ"]);
    } else if (g && g.status.startsWith("running") && r.status === "running") {
      orbit.push(["agreement", "running, as the stored label", "agree"]);
    } else if (g && g.status.startsWith("running") !== (r.status === "running") &&
               (g.k !== null || g.status.startsWith("running")) && r.status !== "unresolved") {
      orbit.push(["agreement", "a different label from the nearest grid point's: the point is near a basin boundary", "differ"]);
    }
    sections.push(["orbit " + orbits.length + " (integrated in your browser)", orbit]);
    if (orbits.length > 1) {
      sections.push(["orbits on the map (numbered at their start)", orbits.map((o, n) =>
        [String(n + 1), "from (" + fix(o.theta0, 3) + ", " + fix(o.theta_dot0, 3) + "): " +
         orbitSummary(o)])]);
    }
    box.replaceChildren(table(sections));
    for (const k of Object.keys(box.dataset)) if (k !== "ready" && k !== "clicks") delete box.dataset[k];
    Object.assign(box.dataset, {
      theta0: th, thetaDot0: v, point: index, orbits: orbits.length,
      orbitStatus: r.status, orbitK: r.k === null ? "" : r.k, orbitDirection: r.direction,
      orbitTTrap: r.t_trap === null ? "" : r.t_trap,
    });
    if (g) {
      Object.assign(box.dataset, {
        gridStatus: g.status, gridK: g.k === null ? "" : g.k,
        gridTTrap: g.t_trap === null ? "" : g.t_trap,
        gridDistance: g.distance === null ? "" : g.distance,
      });
    }
  }
  const hint = $("readout").firstElementChild;

  function show(th, v) {
    const r = integrate(th, v, P);
    orbits.push(r);
    $("clear").disabled = false;
    drawMap(); animate(r); readout();
    const box = $("readout");
    box.dataset.clicks = Number(box.dataset.clicks || 0) + 1;
    return r;
  }
  function clear() {
    orbits = []; anim = null;
    $("clear").disabled = true;
    ovCtx.clearRect(0, 0, CW, CH); $("clock").textContent = "";
    drawPendulum(0, null); drawMap(); readout();
  }

  // ---- hover ---------------------------------------------------------------------------
  const HOVER_HINT = $("hover").textContent;
  function hover(x, y) {
    const box = $("hover");
    if (!(x >= M.left && x <= M.left + W && y >= M.top && y <= M.top + H) || !P.grid) {
      box.textContent = HOVER_HINT; delete box.dataset.theta0; return;
    }
    const th = thOf(x), v = vOf(y), g = gridAt(P, th, v);
    box.textContent = [coords(th, v, true, false), g.k !== null ? "k = " + signed(g.k) : null,
      STATUS_WORDS[g.status] || g.status,
      "t_trap " + (g.t_trap === null ? "—" : g.t_trap.toFixed(2) + " s"),
      "boundary distance " + (g.distance === null ? "—" : sci(g.distance))
    ].filter(Boolean).join(" · ");
    Object.assign(box.dataset, { theta0: th, thetaDot0: v, status: g.status,
                                 k: g.k === null ? "" : g.k });
  }

  // ---- the parameter point --------------------------------------------------------------
  function legendText() {
    const tilted = D.points.some((p) => p.torque);
    return (tilted ? "θ̈ = −ω0² sin θ − 2αθ̇ + τ; rest states (θ* + 2πk, 0) with " +
      "θ* = arcsin(τ/ω0²), saddles (π − θ* + 2πk, 0)." : "θ̈ = −ω0² sin θ − 2αθ̇; rest " +
      "states (2πk, 0), saddles ((2j+1)π, 0).") + " Each point of the map is an initial " +
      "condition (θ0, θ̇0); the key above says what its colour means. Orbits are drawn " +
      (PERIOD ? "modulo " + piLabel(Math.round(PERIOD / Math.PI)) + " into the window (a " +
      "piece that leaves it reappears a whole number of turns away)." : "clipped to the window.");
  }
  function select(i) {
    index = clamp(i | 0, 0, D.points.length - 1);
    P = D.points[index];
    startImage(P);
    $("point").value = String(index);
    const params = "α = " + P.alpha + " s⁻¹, ω0 = " + P.omega0 + " rad/s" +
      (P.torque ? ", τ = " + P.torque + " rad/s²" : "");
    $("point-label").textContent = params + " (" + (index + 1) + " of " + D.points.length + ")";
    $("subtitle").textContent = params + ", dt = " + D.dt + " s, t_max = " + D.t_max +
      " s; grid " + NT + " × " + NV + "; file " + D.file;
    buildKey(); layout(); drawMap();
    const p = P;
    p.loading = p.loading || loadGrid(p);
    return p.loading.then(() => {
      if (P !== p) return;
      orbits = orbits.map((o) => integrate(o.theta0, o.theta_dot0, P));
      buildKey(); layout(); drawMap(); readout();
    });
  }
  function setLayer(name) {
    layer = name;
    for (const input of document.querySelectorAll("input[name=layer]")) input.checked = input.value === name;
    if (P.grid) { buildKey(); layout(); drawMap(); }
  }

  // π expressions as the config's: 1.5, -pi/2, 3pi, 2*pi, π/4
  function parseValue(text) {
    const t = text.trim().replace(/[−–]/g, "-").replace(/π/g, "pi").replace(/\s+/g, "");
    const m = /^([+-]?)(\d*\.?\d*(?:e[+-]?\d+)?)(\*?pi)?(?:\/(\d*\.?\d+))?$/i.exec(t);
    if (!m || (!m[2] && !m[3]) || (m[2] && !/\d/.test(m[2])) || (m[2] === "" && m[3] && m[3][0] === "*")) return NaN;
    let x = m[2] ? Number(m[2]) : 1;
    if (m[3]) x *= Math.PI;
    if (m[4]) x /= Number(m[4]);
    return m[1] === "-" ? -x : x;
  }

  $("name").textContent = D.name;
  document.title = D.name + " · atlas view";
  $("provenance").textContent = [D.title, D.created && "created " + D.created,
    D.atlas_version && "atlas " + D.atlas_version].filter(Boolean).join("; ");
  if (D.points.length > 1) {
    $("controls").hidden = false;
    $("point").max = String(D.points.length - 1);
    $("point").addEventListener("input", (e) => select(Number(e.target.value)));
  }
  $("legend").textContent = legendText();
  const local = (e) => {
    const b = $("overlay").getBoundingClientRect();
    return [e.clientX - b.left, e.clientY - b.top];
  };
  $("overlay").addEventListener("click", (e) => {
    const [x, y] = local(e);
    if (x >= M.left && x <= M.left + W && y >= M.top && y <= M.top + H) show(thOf(x), vOf(y));
  });
  $("overlay").addEventListener("mousemove", (e) => hover(...local(e)));
  $("overlay").addEventListener("mouseleave", () => hover(-1, -1));
  $("goto").addEventListener("submit", (e) => {
    e.preventDefault();
    const th = parseValue($("in-theta0").value), v = parseValue($("in-theta-dot0").value);
    const bad = !Number.isFinite(th) ? "θ0" : !Number.isFinite(v) ? "θ̇0" : null;
    $("goto-error").textContent = bad ? bad + ": not a number (try 1.2, −3.1, pi/2, −3pi)" : "";
    if (!bad) show(th, v);
  });
  $("clear").addEventListener("click", clear);
  for (const input of document.querySelectorAll("input[name=layer]")) {
    input.addEventListener("change", () => setLayer(input.value));
  }
  let pending = false;
  window.addEventListener("resize", () => {
    if (pending) return;
    pending = true;
    requestAnimationFrame(() => { pending = false; layout(); drawMap(); });
  });
  drawPendulum(0, null);

  const ready = select(0).then(() => { $("readout").dataset.ready = "1"; });
  // For scripts and tests: the same computations the page draws.
  window.atlasView = {
    ready, select, show, clear, setLayer, parseValue, energyText, wellColour, scaleColour,
    orbit: (th, v, i) => { const { path, ...r } = integrate(th, v, D.points[i ?? index]); return r; },
    grid: (th, v) => gridAt(P, th, v),
    drawn: () => Object.assign({}, drawn),
    clientXY: (th, v) => {
      const b = $("overlay").getBoundingClientRect();
      return { x: b.left + xOf(th), y: b.top + yOf(v) };
    },
    points: D.points.length,
  };
})();
