"use strict";
// atlas view: the basin map, click an orbit. Every string from the file goes through
// textContent; the data come from the JSON block above, parsed, never evaluated.
(function () {
  const D = JSON.parse(document.getElementById("atlas-data").textContent);
  const $ = (id) => document.getElementById(id);
  const TWO_PI = 2 * Math.PI, INV_TWO_PI = 1 / TWO_PI;
  const RUNNING_COLOR = "#d1d1d1";
  const [TH0, TH1, NT] = D.theta0, [V0, V1, NV] = D.theta_dot0;
  const HT = (TH1 - TH0) / (NT - 1), HV = (V1 - V0) / (NV - 1);
  const M = { left: 64, right: 14, top: 12, bottom: 46 }, W = 700, H = 420;
  const CW = M.left + W + M.right, CH = M.top + H + M.bottom;
  const NAMES = D.status_names;
  const dpr = window.devicePixelRatio || 1;

  function setup(canvas, w, h) {
    canvas.style.width = w + "px"; canvas.style.height = h + "px";
    canvas.width = Math.round(w * dpr); canvas.height = Math.round(h * dpr);
    const ctx = canvas.getContext("2d");
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    return ctx;
  }
  $("stage").style.width = CW + "px"; $("stage").style.height = CH + "px";
  const mapCtx = setup($("map"), CW, CH), ovCtx = setup($("overlay"), CW, CH);
  const penCtx = setup($("pendulum"), 220, 220);

  // The image spans the grid cells' edges: grid point i sits at the centre of pixel column i.
  const xOf = (th) => M.left + (th - TH0 + HT / 2) / (TH1 - TH0 + HT) * W;
  const yOf = (v) => M.top + H - (v - V0 + HV / 2) / (V1 - V0 + HV) * H;
  const thOf = (x) => TH0 - HT / 2 + (x - M.left) / W * (TH1 - TH0 + HT);
  const vOf = (y) => V0 - HV / 2 + (M.top + H - y) / H * (V1 - V0 + HV);
  const clamp = (x, lo, hi) => Math.min(hi, Math.max(lo, x));
  const signed = (k) => (k > 0 ? "+" : "") + k;
  const fix = (x, n) => x.toFixed(n).replace("-", "−");
  const sci = (x) => (x === 0 ? "0" : x.toPrecision(3).replace("-", "−"));
  const color = (k) => D.colors[((k % 10) + 10) % 10];

  async function inflate(b64) {
    const bin = atob(b64), bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
    return new Response(stream).arrayBuffer();
  }
  function image(src) {
    return new Promise((resolve, reject) => {
      const im = new Image(); im.onload = () => resolve(im); im.onerror = reject; im.src = src;
    });
  }
  async function load(p) {
    if (!p.grid) {
      const [k, s, t, d] = await Promise.all(
        [p.attractor, p.status, p.t_trap, p.distance].map(inflate));
      p.img = await image(p.png);
      p.grid = { k: new Int16Array(k), status: new Int8Array(s), trap: new Uint32Array(t),
                 dist: new Uint16Array(d) };
      // the running barrier's lower curve: float64, exactly the numbers the sweep verified
      if (p.barrier) p.barrierG = new Float64Array(await inflate(p.barrier.g));
    }
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
  // (atlas.kernels.rk4). After the trap the orbit is followed on (for the picture) until it
  // has nearly settled; after the running certificate for two more turns.
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
                theta_dot_trap: null, direction: 0 };
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
    if (r.status === "trapped") {
      const level = 1e-3 * (tq === 0 ? 2 * w2 : p.saddle_energy);
      while (path.length / 2 - 1 < nChecks * ce && energy()[1] > level) {
        steps();
      }
    } else if (r.status === "running") {
      const start = th;
      while (path.length / 2 - 1 < nChecks * ce && Math.abs(th - start) < 2 * TWO_PI) {
        steps();
      }
    }
    r.theta_end = th; r.theta_dot_end = v;
    r.path = Float64Array.from(path);
    return r;
  }

  // ---- drawing ------------------------------------------------------------------------
  let P = null, index = 0, current = null, anim = null;

  function piLabel(n) {
    if (n === 0) return "0";
    return (n < 0 ? "−" : "") + (Math.abs(n) === 1 ? "" : Math.abs(n)) + "π";
  }
  function drawPath(c, r) {
    const path = r.path;
    for (const [style, width] of [["#fff", 3.5], ["#000", 1.5]]) {
      c.strokeStyle = style; c.lineWidth = width; c.beginPath();
      c.moveTo(xOf(path[0]), yOf(path[1]));
      for (let i = 2; i < path.length; i += 2) c.lineTo(xOf(path[i]), yOf(path[i + 1]));
      c.stroke();
    }
    c.fillStyle = "#fff"; c.strokeStyle = "#000"; c.lineWidth = 1.5;
    c.beginPath(); c.arc(xOf(path[0]), yOf(path[1]), 4.5, 0, TWO_PI); c.fill(); c.stroke();
    if (r.status === "trapped" || r.status === "running") {
      const x = xOf(r.theta_trap), y = yOf(r.theta_dot_trap);
      c.beginPath(); c.moveTo(x - 4, y - 4); c.lineTo(x + 4, y + 4);
      c.moveTo(x - 4, y + 4); c.lineTo(x + 4, y - 4); c.stroke();
    }
  }
  function drawMap() {
    const c = mapCtx;
    c.clearRect(0, 0, CW, CH);
    c.imageSmoothingEnabled = false;
    c.drawImage(P.img, M.left, M.top, W, H);
    c.save();
    c.beginPath(); c.rect(M.left, M.top, W, H); c.clip();
    c.strokeStyle = "red"; c.lineWidth = 1.3;
    for (const [ts, vs] of P.curves) {
      c.beginPath(); c.moveTo(xOf(ts[0]), yOf(vs[0]));
      for (let i = 1; i < ts.length; i++) c.lineTo(xOf(ts[i]), yOf(vs[i]));
      c.stroke();
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
    c.fillStyle = "#000";
    for (const t of P.attractors) { c.beginPath(); c.arc(xOf(t), yOf(0), 3.5, 0, TWO_PI); c.fill(); }
    c.strokeStyle = "red"; c.lineWidth = 1.8;
    for (const t of P.saddles) { c.beginPath(); c.arc(xOf(t), yOf(0), 5, 0, TWO_PI); c.stroke(); }
    if (current) drawPath(c, current);
    c.restore();
    // axes
    c.strokeStyle = "#333"; c.fillStyle = "#222"; c.lineWidth = 1;
    c.strokeRect(M.left, M.top, W, H);
    c.font = "12px 'DejaVu Sans', system-ui, sans-serif"; c.textAlign = "center"; c.textBaseline = "top";
    const n0 = Math.ceil(TH0 / Math.PI - 1e-9), n1 = Math.floor(TH1 / Math.PI + 1e-9);
    const every = Math.max(1, Math.ceil((n1 - n0 + 1) / 13));
    for (let n = n0; n <= n1; n++) {
      if (n % every) continue;
      const x = xOf(n * Math.PI);
      c.beginPath(); c.moveTo(x, M.top + H); c.lineTo(x, M.top + H + 5); c.stroke();
      c.fillText(piLabel(n), x, M.top + H + 7);
    }
    const span = V1 - V0, raw = span / 8, mag = 10 ** Math.floor(Math.log10(raw));
    const stepV = [1, 2, 5, 10].map((f) => f * mag).find((s) => s >= raw);
    c.textAlign = "right"; c.textBaseline = "middle";
    for (let v = Math.ceil(V0 / stepV) * stepV; v <= V1 + 1e-9 * span; v += stepV) {
      const y = yOf(v);
      c.beginPath(); c.moveTo(M.left - 5, y); c.lineTo(M.left, y); c.stroke();
      c.fillText(String(Number(v.toPrecision(6))).replace("-", "−"), M.left - 7, y);
    }
    c.textAlign = "center"; c.textBaseline = "bottom";
    c.fillText("θ0 [rad]", M.left + W / 2, CH - 4);
    c.save(); c.translate(16, M.top + H / 2); c.rotate(-Math.PI / 2);
    c.textBaseline = "middle"; c.fillText("θ̇0 = dθ/dt at t = 0 [rad/s]", 0, 0); c.restore();
  }

  const bobColor = (r) => (r && r.status === "running" ? RUNNING_COLOR
    : r && r.k !== null ? color(r.k) : "#999");
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
    ovCtx.beginPath(); ovCtx.arc(xOf(th), yOf(v), 6, 0, TWO_PI); ovCtx.fill(); ovCtx.stroke();
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

  // ---- readout -------------------------------------------------------------------------
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
  function show(th, v) {
    const r = integrate(th, v, P), g = gridAt(P, th, v);
    current = r;
    drawMap(); animate(r);
    const tilted = (P.torque || 0) !== 0;
    const wellText = (k) => "well k = " + signed(k) + ": rest at (" + (tilted
      ? (k === 0 ? "θ*" : "θ* " + (k < 0 ? "−" : "+") + " " + piLabel(Math.abs(2 * k))) +
        " = " + fix(P.shift + TWO_PI * k, 4) : piLabel(2 * k)) + ", 0)";
    const runText = (d) => "running: converges to the limit cycle (direction " + signed(d) + ")";
    let cert = "—";
    if (g.status === "trapped") cert = "certified for the exact equation (distance > d_cert" +
      (P.d_cert === null ? ")" : " = " + sci(P.d_cert) + ")");
    else if (g.status === "near_boundary") cert = "certified for the RK4 map only (closer " +
      "than d_cert" + (P.d_cert === null ? " or d_cert not measured)" : " = " + sci(P.d_cert) + ")");
    else if (g.status === "running") cert = "certified for the exact equation (running " +
      "barrier, distance > d_cert" + (P.d_cert === null ? ")" : " = " + sci(P.d_cert) + ")");
    else if (g.status === "running_near_boundary") cert = "certified for the RK4 map only " +
      "(running barrier; closer than d_cert or d_cert not measured)";
    const grid = [
      ["grid point", "θ0 = " + fix(g.theta, 4) + ", θ̇0 = " + fix(g.theta_dot, 4)],
      ["stored label", g.k !== null ? wellText(g.k) : g.status.startsWith("running") &&
        P.barrier ? runText(P.barrier.direction) : "none (" + g.status + ")"],
      ["status", g.status], ["certificate", cert],
      ["t_trap", g.t_trap === null ? "—" : g.t_trap.toFixed(2) + " s"],
      ["boundary distance", g.distance === null ? "—" : "≈ " + sci(g.distance)],
    ];
    const orbit = [["from", "θ0 = " + fix(th, 4) + ", θ̇0 = " + fix(v, 4)]];
    if (r.status === "trapped") {
      orbit.push(["end state", "trapped in " + wellText(r.k) + " at t = " + r.t_trap.toFixed(2) + " s"],
        ["at the trap", "θ = " + fix(r.theta_trap, 4) + ", θ̇ = " + fix(r.theta_dot_trap, 4)],
        ["energy trap", "E_k = " + sci(r.energy) + (tilted ? " < ΔE(1 − m) − rounding = "
          : " < 2ω0²(1 − m) = ") + r.cap.toPrecision(10) + ", m = " + sci(r.margin)]);
    } else if (r.status === "running") {
      const b = P.barrier, d = r.direction;
      orbit.push(["end state", runText(d) + ", certified at t = " + r.t_trap.toFixed(2) + " s"],
        ["at the certificate", "θ = " + fix(r.theta_trap, 4) + ", θ̇ = " + fix(r.theta_dot_trap, 4)],
        ["running barrier", (d > 0 ? "g(θ) = " + sci(r.lower) + " ≤ θ̇ ≤ top = " + sci(b.top)
          : "−top = " + sci(-b.top) + " ≤ θ̇ ≤ " + sci(r.lower) + " = −g(−θ)") +
         ": the RK4 map's orbit stays in the band around the limit cycle"]);
    } else {
      orbit.push(["end state", r.status === "nonfinite" ? "left the finite numbers"
        : "not trapped by t_max = " + D.t_max + " s"]);
    }
    orbit.push(["last state drawn", "θ = " + fix(r.theta_end, 4) + ", θ̇ = " + fix(r.theta_dot_end, 4)]);
    if (g.k !== null && r.k !== null) {
      orbit.push(g.k === r.k ? ["agreement", "same well as the stored label", "agree"]
        : ["agreement", "a different well from the nearest grid point's: the click is near a basin boundary", "differ"]);
    } else if (g.status.startsWith("running") && r.status === "running") {
      orbit.push(["agreement", "running, as the stored label", "agree"]);
    } else if (g.status.startsWith("running") !== (r.status === "running") &&
               (g.k !== null || g.status.startsWith("running")) && r.status !== "unresolved") {
      orbit.push(["agreement", "a different label from the nearest grid point's: the click is near a basin boundary", "differ"]);
    }
    const box = $("readout");
    box.replaceChildren(table([["nearest grid point (stored in the file)", grid],
                               ["this orbit (integrated in your browser)", orbit]]));
    Object.assign(box.dataset, {
      theta0: th, thetaDot0: v, point: index,
      orbitStatus: r.status, orbitK: r.k === null ? "" : r.k, orbitDirection: r.direction,
      orbitTTrap: r.t_trap === null ? "" : r.t_trap,
      gridStatus: g.status, gridK: g.k === null ? "" : g.k,
      gridTTrap: g.t_trap === null ? "" : g.t_trap,
      gridDistance: g.distance === null ? "" : g.distance,
      clicks: Number(box.dataset.clicks || 0) + 1,
    });
    return r;
  }

  async function select(i) {
    index = clamp(i | 0, 0, D.points.length - 1);
    P = await load(D.points[index]);
    $("point").value = String(index);
    const params = "α = " + P.alpha + " s⁻¹, ω0 = " + P.omega0 + " rad/s" +
      (P.torque ? ", τ = " + P.torque + " rad/s²" : "");
    $("point-label").textContent = params + " (" + (index + 1) + " of " + D.points.length + ")";
    $("subtitle").textContent = params + ", dt = " + D.dt + " s, t_max = " + D.t_max +
      " s; grid " + NT + " × " + NV + "; file " + D.file;
    if (current) show(current.theta0, current.theta_dot0); else drawMap();
  }

  $("name").textContent = D.name;
  if (D.points.some((p) => p.torque)) {
    $("legend").textContent = "θ̈ = −ω0² sin θ − 2αθ̇ + τ. Colour: the well k (rest state " +
      "(θ* + 2πk, 0), θ* = arcsin(τ/ω0²)) each initial condition reaches; grey: running " +
      "(certified to converge to the running limit cycle, dashed); white: no certified " +
      "label. Red: the separatrices (basin boundaries); open circles: saddles " +
      "(π − θ* + 2πk, 0); dots: attractors.";
  }
  document.title = D.name + " · atlas view";
  $("provenance").textContent = [D.title, D.created && "created " + D.created,
    D.atlas_version && "atlas " + D.atlas_version].filter(Boolean).join("; ");
  if (D.points.length > 1) {
    $("controls").hidden = false;
    $("point").max = String(D.points.length - 1);
    $("point").addEventListener("input", (e) => select(Number(e.target.value)));
  }
  $("overlay").addEventListener("click", (e) => {
    const b = $("overlay").getBoundingClientRect(), x = e.clientX - b.left, y = e.clientY - b.top;
    if (x >= M.left && x <= M.left + W && y >= M.top && y <= M.top + H) show(thOf(x), vOf(y));
  });
  drawPendulum(0, null);

  const ready = select(0).then(() => { $("readout").dataset.ready = "1"; });
  // For scripts and tests: the same computations the page draws.
  window.atlasView = {
    ready, select, show,
    orbit: (th, v, i) => { const { path, ...r } = integrate(th, v, D.points[i ?? index]); return r; },
    grid: (th, v) => gridAt(P, th, v),
    clientXY: (th, v) => {
      const b = $("overlay").getBoundingClientRect();
      return { x: b.left + xOf(th), y: b.top + yOf(v) };
    },
    points: D.points.length,
  };
})();
