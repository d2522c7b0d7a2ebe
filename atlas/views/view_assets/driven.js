// atlas view, the driven pendulum's page: a click on a basin map follows the orbit from that
// initial state on the stroboscopic map P, in the browser.
//
// The equation θ̈ + 2αθ̇ + ω0² sin θ = τ + A cos(Ωt + φ), from t = 0, by classical RK4 with
// dt = T/N (T = 2π/Ω, N the file's steps per period): the step of atlas/kernels/driven.py
// (make_driven_step), the drive read at t, t + dt/2 and t + dt of each step from a table of
// τ + A cos(Ω t_j + φ) at the 2N + 1 half-step times t_j = j·dt/2 of one period
// (forcing_table), the same table in every period. After each period the return to P is
// labelled by the rule of label_driven: the nearest target (an attractor's point on P,
// θ wrapped to [−π, π), θ difference wrapped) within its attractor's capture radius is a
// hit; that attractor's confirm hits in a row decide the label (one where its capture ball
// was seen to map into itself, else 8); none by t_max: undecided.
// Every number comes from the file (atlas/views/page_driven.py): nothing is rebuilt here.
(() => {
  'use strict';
  const TWO_PI = 2.0 * Math.PI;
  const INV_TWO_PI = 1.0 / TWO_PI;
  const CURVE_MAX = 200000; // the most vertices of the faint path kept per orbit
  const DRAWN_RETURNS = 4000; // the most returns drawn as dots
  const points = JSON.parse(document.getElementById('atlas-data').dataset.json);

  // ---- the map P, as atlas/kernels/driven.py ---------------------------------------------
  function forcing(d) {
    const n = d.steps_per_period;
    const dt = TWO_PI / d.frequency / n;
    const half = 0.5 * dt;
    const table = new Float64Array(2 * n + 1);
    for (let j = 0; j <= 2 * n; j++) {
      table[j] = d.torque + d.amplitude * Math.cos(d.frequency * (j * half) + d.phase);
    }
    return { table, dt };
  }

  function step(th, v, alpha, omega0, dt, f0, f1, f2) {
    const w2 = omega0 * omega0;
    const a2 = 2.0 * alpha;
    const h2 = 0.5 * dt;
    const k1t = v;
    const k1v = f0 - w2 * Math.sin(th) - a2 * v;
    const k2t = v + h2 * k1v;
    const k2v = f1 - w2 * Math.sin(th + h2 * k1t) - a2 * k2t;
    const k3t = v + h2 * k2v;
    const k3v = f1 - w2 * Math.sin(th + h2 * k2t) - a2 * k3t;
    const k4t = v + dt * k3v;
    const k4v = f2 - w2 * Math.sin(th + dt * k3t) - a2 * k4t;
    const h6 = dt / 6.0;
    return [th + h6 * (k1t + 2.0 * (k2t + k3t) + k4t),
      v + h6 * (k1v + 2.0 * (k2v + k3v) + k4v)];
  }

  function wrapPi(th) {
    return th - TWO_PI * Math.floor((th + Math.PI) * INV_TWO_PI);
  }

  // the attractor of the nearest target within its capture radius, else -1 (nearest_attractor)
  function nearest(th, v, d) {
    const t = d.targets;
    const wrapped = wrapPi(th);
    let best = Infinity;
    let hit = -1;
    for (let k = 0; k < t.theta.length; k++) {
      let dd = wrapped - t.theta[k];
      dd -= TWO_PI * Math.floor((dd + Math.PI) * INV_TWO_PI);
      const e = v - t.theta_dot[k];
      const dist2 = dd * dd + e * e;
      const r = d.radius[t.attractor[k]];
      if (dist2 <= r * r && dist2 < best) {
        best = dist2;
        hit = t.attractor[k];
      }
    }
    return hit;
  }

  // the orbit from (θ0, θ̇0) at t = 0: its returns to P (θ unwrapped), its path, its label
  function follow(d, theta0, thetaDot0) {
    if (!d.forcing) d.forcing = forcing(d);
    const { table, dt } = d.forcing;
    const n = d.steps_per_period;
    const period = TWO_PI / d.frequency;
    const curve = [theta0, thetaDot0];
    const returns = [];
    let th = theta0;
    let v = thetaDot0;
    let run = -1;
    let length = 0;
    const out = { theta0, theta_dot0: thetaDot0, returns, curve, attractor: null,
      status: null, periods: 0, decided: false };
    if (!(Number.isFinite(th) && Number.isFinite(v))) {
      out.status = 'nonfinite';
      return out;
    }
    for (let p = 1; ; p++) {
      for (let j = 0; j < 2 * n; j += 2) {
        [th, v] = step(th, v, d.alpha, d.omega0, dt, table[j], table[j + 1], table[j + 2]);
        if (curve.length < 2 * CURVE_MAX) curve.push(th, v);
      }
      out.periods = p;
      if (!(Number.isFinite(th) && Number.isFinite(v))) {
        out.status = 'nonfinite';
        return out;
      }
      returns.push([th, v]);
      const hit = nearest(th, v, d);
      if (hit < 0) length = 0;
      else if (hit === run) length += 1;
      else length = 1;
      run = hit;
      if (hit >= 0 && length >= d.confirm[hit]) {
        out.attractor = hit;
        out.decided = true;
        out.status = d.status_names[String(d.attractor_status[hit])] || 'decided';
        out.t = p * period;
        return out;
      }
      if (p >= d.max_periods) {
        out.status = 'unresolved';
        return out;
      }
    }
  }

  // ---- the picture ------------------------------------------------------------------------
  function axis(values) {
    const [first, last, n] = values;
    const h = n > 1 ? (last - first) / (n - 1) : 1.0;
    return { first, last, n, h, lo: first - h / 2, hi: last + h / 2 };
  }

  function decode(blob, Type) {
    const bytes = Uint8Array.from(atob(blob), (c) => c.charCodeAt(0));
    return new Type(bytes.buffer);
  }

  const sections = [...document.querySelectorAll('section[data-point]')];
  const state = sections.map((section) => {
    const d = points[Number(section.dataset.point)];
    const x = axis(d.grid.theta0);
    const y = axis(d.grid.theta_dot0);
    return {
      d, x, y, section,
      img: section.querySelector('.stage img'),
      canvas: section.querySelector('.stage canvas'),
      readout: section.querySelector('.orbit-readout'),
      stored: decode(d.stored_attractor, Int16Array),
      storedStatus: decode(d.stored_status, Int8Array),
      orbit: null,
    };
  });

  function toCss(s, th, v) {
    const b = s.canvas.getBoundingClientRect();
    return [(th - s.x.lo) / (s.x.hi - s.x.lo) * b.width,
      (s.y.hi - v) / (s.y.hi - s.y.lo) * b.height];
  }

  // θ drawn in the window: a whole number of turns away where the window holds a turn,
  // else wrapped to [−π, π) (and clipped by the canvas)
  function shown(s, th) {
    const width = s.x.hi - s.x.lo;
    if (width >= TWO_PI) return s.x.lo + (((th - s.x.lo) % TWO_PI) + TWO_PI) % TWO_PI;
    return wrapPi(th);
  }

  function dot(ctx, x, y, r, fill, edge, width) {
    ctx.beginPath();
    ctx.arc(x, y, r, 0, TWO_PI);
    ctx.fillStyle = fill;
    ctx.fill();
    ctx.lineWidth = width;
    ctx.strokeStyle = edge;
    ctx.stroke();
  }

  function diamond(ctx, x, y, r) {
    ctx.beginPath();
    ctx.moveTo(x, y - r);
    ctx.lineTo(x + r, y);
    ctx.lineTo(x, y + r);
    ctx.lineTo(x - r, y);
    ctx.closePath();
    ctx.fillStyle = '#ffffff';
    ctx.fill();
    ctx.lineWidth = 2;
    ctx.strokeStyle = '#000000';
    ctx.stroke();
  }

  function draw(s) {
    const b = s.img.getBoundingClientRect();
    const ratio = window.devicePixelRatio || 1;
    s.canvas.width = Math.round(b.width * ratio);
    s.canvas.height = Math.round(b.height * ratio);
    const ctx = s.canvas.getContext('2d');
    ctx.setTransform(ratio, 0, 0, ratio, 0, 0);
    ctx.clearRect(0, 0, b.width, b.height);
    // the attractors' points on P (periodic ones: a chaotic cloud would cover its basin)
    const t = s.d.targets;
    const marks = [];
    for (let k = 0; k < t.theta.length; k++) {
      if (s.d.kinds[t.attractor[k]] !== 'periodic') continue;
      const [x, y] = toCss(s, shown(s, t.theta[k]), t.theta_dot[k]);
      diamond(ctx, x, y, 8);
      marks.push([`#${t.attractor[k]}`, x + 11, y]);
    }
    const o = s.orbit;
    if (o) drawOrbit(s, ctx, o);
    // the attractors' names last, over the orbit
    ctx.font = 'bold 15px "DejaVu Sans", system-ui, sans-serif';
    ctx.textBaseline = 'middle';
    for (const [name, x, y] of marks) {
      ctx.lineWidth = 4;
      ctx.strokeStyle = '#ffffff';
      ctx.strokeText(name, x, y);
      ctx.fillStyle = '#000000';
      ctx.fillText(name, x, y);
    }
  }

  function drawOrbit(s, ctx, o) {
    // the path between the returns: thin and faint, broken where θ is wrapped
    ctx.lineWidth = 1;
    ctx.strokeStyle = 'rgba(0, 0, 0, 0.25)';
    ctx.beginPath();
    let previous = null;
    for (let i = 0; i < o.curve.length; i += 2) {
      const th = shown(s, o.curve[i]);
      const [x, y] = toCss(s, th, o.curve[i + 1]);
      if (previous === null || Math.abs(th - previous) > Math.PI) ctx.moveTo(x, y);
      else ctx.lineTo(x, y);
      previous = th;
    }
    ctx.stroke();
    // the start, then the returns to P: black dots ringed in white
    const [x0, y0] = toCss(s, shown(s, o.theta0), o.theta_dot0);
    dot(ctx, x0, y0, 8, '#ffffff', '#000000', 3);
    const first = Math.max(0, o.returns.length - DRAWN_RETURNS);
    for (let i = first; i < o.returns.length; i++) {
      const [x, y] = toCss(s, shown(s, o.returns[i][0]), o.returns[i][1]);
      dot(ctx, x, y, 5, '#000000', '#ffffff', 2);
    }
  }

  function returnsText(confirm) {
    return confirm === 1 ? 'a return' : `${confirm} returns in a row`;
  }

  function fmt(value, digits = 4) {
    return Number(value).toFixed(digits);
  }

  function storedText(s, th, v) {
    const i = Math.min(s.x.n - 1, Math.max(0, Math.round((th - s.x.first) / s.x.h)));
    const j = Math.min(s.y.n - 1, Math.max(0, Math.round((v - s.y.first) / s.y.h)));
    const k = s.stored[j * s.x.n + i];
    const code = s.storedStatus[j * s.x.n + i];
    const status = s.d.status_names[String(code)] || `status ${code}`;
    const name = k >= 0 && k < s.d.names.length ? s.d.names[k] : 'no label';
    const at = `θ0 = ${fmt(s.x.first + i * s.x.h)} rad, θ̇0 = ${fmt(s.y.first + j * s.y.h)} rad/s`;
    return { k: k >= 0 ? k : null, text: `${name} (${status})`, at };
  }

  function line(parent, tag, text, cls) {
    const e = document.createElement(tag);
    e.textContent = text;
    if (cls) e.className = cls;
    parent.appendChild(e);
    return e;
  }

  function report(s) {
    const o = s.orbit;
    const d = s.d;
    const r = s.readout;
    r.replaceChildren();
    line(r, 'p', `Orbit from θ0 = ${fmt(o.theta0)} rad, θ̇0 = ${fmt(o.theta_dot0)} rad/s at t = 0 `
      + `(white circle; RK4, dt = T/${d.steps_per_period}): its ${o.returns.length} returns to P `
      + 'are the black dots, its path between them the grey line, the attractors\' points on P '
      + 'the white diamonds.');
    const label = line(r, 'p', '', 'orbit-label');
    if (o.decided) {
      label.textContent = `It reaches ${d.names[o.attractor]} (${o.status}) after ${o.periods} `
        + `drive periods, t = ${o.t.toFixed(1)} s: ${returnsText(d.confirm[o.attractor])} `
        + `within its capture radius ${d.radius[o.attractor].toPrecision(3)}.`;
    } else if (o.status === 'nonfinite') {
      label.textContent = `A NaN or inf state was met after ${o.periods} drive periods.`;
    } else {
      label.textContent = `Undecided after ${o.periods} periods (t_max = ${d.t_max} s).`;
    }
    const stored = storedText(s, o.theta0, o.theta_dot0);
    const differs = (stored.k === null ? null : stored.k) !== o.attractor;
    line(r, 'p', `The file stores at the nearest grid point (${stored.at}): ${stored.text}.`
      + (differs ? ' That is another initial state: near a fractal boundary the two labels '
        + 'can differ.' : ''), 'orbit-stored');
    Object.assign(r.dataset, {
      ready: '1', attractor: o.attractor === null ? '' : String(o.attractor),
      status: o.status, periods: String(o.periods), decided: o.decided ? '1' : '0',
      stored: stored.k === null ? '' : String(stored.k),
    });
  }

  function run(index, theta0, thetaDot0) {
    const s = state[index];
    s.orbit = follow(s.d, theta0, thetaDot0);
    draw(s);
    report(s);
    api.last = s.orbit;
    return { attractor: s.orbit.attractor, status: s.orbit.status, periods: s.orbit.periods,
      decided: s.orbit.decided, returns: s.orbit.returns };
  }

  state.forEach((s, index) => {
    s.canvas.addEventListener('click', (event) => {
      const b = s.canvas.getBoundingClientRect();
      const th = s.x.lo + (event.clientX - b.left) / b.width * (s.x.hi - s.x.lo);
      const v = s.y.hi - (event.clientY - b.top) / b.height * (s.y.hi - s.y.lo);
      run(index, th, v);
    });
    draw(s);
  });
  window.addEventListener('resize', () => state.forEach(draw));

  const api = {
    ready: true,
    last: null,
    follow: run,
    // the viewport point (CSS pixels) of (θ, θ̇) on the map of the index-th parameter point
    clientXY(index, th, v) {
      const s = state[index];
      const b = s.canvas.getBoundingClientRect();
      const [x, y] = toCss(s, th, v);
      return { x: b.left + x, y: b.top + y };
    },
  };
  window.atlasDriven = api;
})();
