/* swarmpath dashboard: small SVG charts (line charts with bands, box plots, maps).
   Written for this project; no third-party code. Every chart is an <svg> whose parts carry
   classes the browser tests count: sp-series (one <g> per series), sp-band, sp-box,
   sp-axis-label, sp-obstacle, sp-track, sp-path, sp-failure. */
(function () {
  "use strict";
  const NS = "http://www.w3.org/2000/svg";
  const SP = (window.SP = window.SP || {});
  SP.palette = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2",
    "#17becf", "#bcbd22", "#7f7f7f", "#393b79", "#ad494a"];
  SP.color = (i) => SP.palette[i % SP.palette.length];

  function el(name, attrs, parent) {
    const e = document.createElementNS(NS, name);
    for (const k in attrs || {}) e.setAttribute(k, attrs[k]);
    if (parent) parent.appendChild(e);
    return e;
  }
  function text(parent, x, y, s, attrs) {
    const t = el("text", Object.assign({ x: x, y: y }, attrs || {}), parent);
    t.textContent = s;
    return t;
  }
  SP.el = el;

  function fmt(v) {
    if (!isFinite(v)) return String(v);
    const a = Math.abs(v);
    if (a === 0) return "0";
    if (a >= 1e4 || a < 1e-3) return v.toExponential(0).replace("e+", "e");
    return String(+v.toPrecision(3));
  }
  SP.fmt = fmt;

  function niceTicks(lo, hi, n) {
    if (!(hi > lo)) { hi = lo + 1; }
    const raw = (hi - lo) / n;
    const mag = Math.pow(10, Math.floor(Math.log10(raw)));
    const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => s >= raw) || raw;
    const out = [];
    for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push(+v.toPrecision(12));
    return out;
  }
  function logTicks(lo, hi) {
    const a = Math.floor(Math.log10(lo)), b = Math.ceil(Math.log10(hi));
    const every = Math.max(1, Math.ceil((b - a) / 8));
    const steps = b - a <= 2 ? [1, 2, 5] : [1];  // few decades: 1, 2, 5 per decade
    const out = [];
    for (let e = a; e <= b; e += every) for (const m of steps) out.push(+(m * Math.pow(10, e)).toPrecision(3));
    return out;
  }

  /* An axis scale: map(v) -> pixel, with ticks. */
  function scale(lo, hi, p0, p1, log) {
    if (log) {
      lo = Math.max(lo, 1e-300); hi = Math.max(hi, lo * 10);
      const l0 = Math.log10(lo), l1 = Math.log10(hi);
      return { log: true, lo: lo, hi: hi, ticks: logTicks(lo, hi),
        map: (v) => p0 + (Math.log10(Math.max(v, lo)) - l0) / (l1 - l0 || 1) * (p1 - p0) };
    }
    if (hi === lo) { hi = lo + Math.max(1, Math.abs(lo)) * 0.5; lo = lo - (hi - lo); }
    const pad = (hi - lo) * 0.04;
    lo -= pad; hi += pad;
    const ticks = niceTicks(lo, hi, 5);
    const step = +(ticks.length > 1 ? ticks[1] - ticks[0] : Math.abs(hi - lo) || 1).toPrecision(6);
    const digits = Math.max(0, Math.min(10, Math.ceil(-Math.log10(step) - 1e-9)));
    const label = (v) => {  // enough decimals to tell neighbouring ticks apart
      const a = Math.abs(v);
      return a !== 0 && (a >= 1e5 || step < 1e-4) ? fmt(v) : v.toFixed(digits);
    };
    return { log: false, lo: lo, hi: hi, ticks: ticks, label: label,
      map: (v) => p0 + (v - lo) / (hi - lo) * (p1 - p0) };
  }

  function frame(container, opts, W, H) {
    container.innerHTML = "";
    const svg = el("svg", { viewBox: `0 0 ${W} ${H}`, class: "sp-chart", role: "img" }, container);
    if (opts.title) text(svg, W / 2, 16, opts.title, { class: "sp-title", "text-anchor": "middle" });
    return svg;
  }
  function axes(svg, box, xs, ys, opts) {
    const g = el("g", { class: "sp-axes" }, svg);
    el("rect", { x: box.l, y: box.t, width: box.r - box.l, height: box.b - box.t, class: "sp-plotarea" }, g);
    if (xs) for (const v of xs.ticks) {
      const x = xs.map(v);
      if (x < box.l - 0.5 || x > box.r + 0.5) continue;
      el("line", { x1: x, x2: x, y1: box.b, y2: box.b + 4, class: "sp-tick" }, g);
      text(g, x, box.b + 15, (xs.label || fmt)(v), { "text-anchor": "middle", class: "sp-ticklabel" });
    }
    for (const v of ys.ticks) {
      if (ys.log && (v < ys.lo * (1 - 1e-9) || v > ys.hi * (1 + 1e-9))) continue;  // map() clamps
      const y = ys.map(v);
      if (y < box.t - 0.5 || y > box.b + 0.5) continue;
      el("line", { x1: box.l, x2: box.r, y1: y, y2: y, class: "sp-grid" }, g);
      text(g, box.l - 5, y + 4, (ys.label || fmt)(v), { "text-anchor": "end", class: "sp-ticklabel" });
    }
    if (opts.xlabel) text(g, (box.l + box.r) / 2, box.b + 32, opts.xlabel, { "text-anchor": "middle", class: "sp-axis-label sp-xlabel" });
    if (opts.ylabel) text(g, 0, 0, opts.ylabel, { "text-anchor": "middle", class: "sp-axis-label sp-ylabel",
      transform: `translate(12 ${(box.t + box.b) / 2}) rotate(-90)` });
  }
  function legend(svg, items, x, y) {
    const g = el("g", { class: "sp-legend" }, svg);
    items.forEach((it, i) => {
      const yy = y + i * 15;
      el("rect", { x: x, y: yy - 8, width: 12, height: 8, fill: it.color, class: "sp-legend-swatch" }, g);
      text(g, x + 16, yy, it.name, { class: "sp-legend-label" });
    });
  }
  function ok(v) { return typeof v === "number" && isFinite(v); }

  /* Line chart: opts.series = [{name, color, x, y, lo?, hi?}], logx, logy, xlabel, ylabel. */
  SP.lineChart = function (container, opts) {
    const W = opts.width || 460, H = opts.height || 280;
    const svg = frame(container, opts, W, H);
    const box = { l: 58, r: W - 110, t: 26, b: H - 42 };
    let xlo = Infinity, xhi = -Infinity, ylo = Infinity, yhi = -Infinity;
    for (const s of opts.series) {
      s.x.forEach((x, i) => {
        for (const v of [s.y[i], s.lo && s.lo[i], s.hi && s.hi[i]]) {
          if (!ok(v) || (opts.logy && v <= 0)) continue;
          ylo = Math.min(ylo, v); yhi = Math.max(yhi, v);
        }
        xlo = Math.min(xlo, x); xhi = Math.max(xhi, x);
      });
    }
    if (!isFinite(ylo)) { ylo = opts.logy ? 1e-12 : 0; yhi = opts.logy ? 1 : 1; }
    const xs = scale(xlo, xhi, box.l, box.r, !!opts.logx && xlo > 0);
    const ys = scale(ylo, yhi, box.b, box.t, !!opts.logy);
    axes(svg, box, xs, ys, opts);
    const clip = el("g", { class: "sp-data" }, svg);
    const Y = (v) => ys.map(opts.logy ? Math.max(v, ys.lo) : v);
    for (const s of opts.series) {
      const g = el("g", { class: "sp-series", "data-name": s.name }, clip);
      if (s.lo && s.hi) {
        const pts = [];
        s.x.forEach((x, i) => { if (ok(s.lo[i]) && ok(s.hi[i])) pts.push([xs.map(x), Y(s.hi[i])]); });
        for (let i = s.x.length - 1; i >= 0; i--) if (ok(s.lo[i]) && ok(s.hi[i])) pts.push([xs.map(s.x[i]), Y(s.lo[i])]);
        if (pts.length) el("polygon", { points: pts.map((p) => p.join(",")).join(" "), fill: s.color, class: "sp-band" }, g);
      }
      const d = [];
      s.x.forEach((x, i) => { if (ok(s.y[i])) d.push((d.length ? "L" : "M") + xs.map(x).toFixed(1) + "," + Y(s.y[i]).toFixed(1)); });
      el("path", { d: d.join(""), stroke: s.color, class: "sp-line" }, g);
    }
    legend(svg, opts.series, box.r + 10, box.t + 10);
    return svg;
  };

  /* Box plot: opts.boxes = [{name, color, stats: {q1, median, q3, lo, hi, outliers, n}}]. */
  SP.boxChart = function (container, opts) {
    const boxes = opts.boxes.filter((b) => b.stats);
    const W = opts.width || 460, H = opts.height || 280;
    const svg = frame(container, opts, W, H);
    const box = { l: 58, r: W - 12, t: 26, b: H - 42 };
    let lo = Infinity, hi = -Infinity;
    for (const b of boxes) for (const v of [b.stats.lo, b.stats.hi, ...b.stats.outliers]) {
      if (!ok(v) || (opts.logy && v <= 0)) continue;
      lo = Math.min(lo, v); hi = Math.max(hi, v);
    }
    if (!isFinite(lo)) { lo = opts.logy ? 1e-12 : 0; hi = 1; }
    const ys = scale(lo, hi, box.b, box.t, !!opts.logy);
    const Y = (v) => ys.map(opts.logy ? Math.max(v, ys.lo) : v);
    axes(svg, box, null, ys, { ylabel: opts.ylabel, xlabel: opts.xlabel });
    if (!boxes.length) text(svg, (box.l + box.r) / 2, (box.t + box.b) / 2, opts.empty || "no values",
      { "text-anchor": "middle", class: "sp-empty" });
    const step = (box.r - box.l) / Math.max(1, boxes.length), w = Math.min(36, step * 0.6);
    boxes.forEach((b, i) => {
      const cx = box.l + step * (i + 0.5), s = b.stats;
      const g = el("g", { class: "sp-box", "data-name": b.name }, svg);
      el("line", { x1: cx, x2: cx, y1: Y(s.lo), y2: Y(s.q1), class: "sp-whisker" }, g);
      el("line", { x1: cx, x2: cx, y1: Y(s.q3), y2: Y(s.hi), class: "sp-whisker" }, g);
      for (const v of [s.lo, s.hi]) el("line", { x1: cx - w / 4, x2: cx + w / 4, y1: Y(v), y2: Y(v), class: "sp-whisker" }, g);
      el("rect", { x: cx - w / 2, y: Y(s.q3), width: w, height: Math.max(1, Y(s.q1) - Y(s.q3)), fill: b.color, class: "sp-boxrect" }, g);
      el("line", { x1: cx - w / 2, x2: cx + w / 2, y1: Y(s.median), y2: Y(s.median), class: "sp-median" }, g);
      for (const v of s.outliers) if (ok(v)) el("circle", { cx: cx, cy: Y(v), r: 2, class: "sp-outlier", stroke: b.color }, g);
      text(svg, cx, box.b + 15, b.name, { "text-anchor": "middle", class: "sp-ticklabel sp-boxlabel" });
      const n = el("title", {}, g); n.textContent = `${b.name}: median ${fmt(s.median)}, IQR ${fmt(s.q1)}..${fmt(s.q3)}, n=${s.n}`;
    });
    return svg;
  };

  function shape(parent, ob, dx, dy, cls) {
    if (ob.shape === "circle") {
      return el("circle", { cx: ob.center[0] + dx, cy: ob.center[1] + dy, r: ob.radius, class: cls }, parent);
    }
    return el("polygon", { points: ob.points.map((p) => (p[0] + dx) + "," + (p[1] + dy)).join(" "), class: cls }, parent);
  }
  function refPoint(ob) {
    if (ob.shape === "circle") return ob.center;
    const n = ob.points.length;
    return [ob.points.reduce((a, p) => a + p[0], 0) / n, ob.points.reduce((a, p) => a + p[1], 0) / n];
  }
  SP.offsetAt = function (motion, k, t) {
    const tr = motion.offsets[String(k)];
    if (!tr || !motion.times.length) return [0, 0];
    const ts = motion.times;
    if (t <= ts[0]) return tr[0];
    if (t >= ts[ts.length - 1]) return tr[tr.length - 1];
    let i = 1; while (ts[i] < t) i++;
    const f = (t - ts[i - 1]) / (ts[i] - ts[i - 1] || 1);
    return [tr[i - 1][0] + f * (tr[i][0] - tr[i - 1][0]), tr[i - 1][1] + f * (tr[i][1] - tr[i - 1][1])];
  };

  /* Map: scene (size, start, goal, obstacles, motion; frame and origin: the map's own frame,
     e.g. a nav2 map's "map" frame and YAML origin), paths [{color, points, failure, run,
     success, name}], opts.time (draw moving obstacles and the robot at that time). Drawn in
     the scenario frame (0, 0 at the lower-left corner); the line under it names the map's
     frame and gives the corners there, and start and goal say where they are in it. */
  SP.mapChart = function (container, scene, paths, opts) {
    opts = opts || {};
    const [w, h] = scene.size, m = 0.02 * Math.max(w, h), fs = 0.03 * Math.max(w, h);
    const frameName = scene.frame || "scenario", o = scene.origin || [0, 0];
    const at = (x, y) => `(${SP.num(x + o[0], 2)}, ${SP.num(y + o[1], 2)})`;
    container.innerHTML = "";
    const svg = el("svg", { viewBox: `${-m} ${-m} ${w + 2 * m} ${h + 2 * m + 1.6 * fs}`, class: "sp-chart sp-map", role: "img" }, container);
    text(svg, -m, h + m + 1.2 * fs, `${frameName} frame (m): lower left ${at(0, 0)}, upper right ${at(w, h)}`,
      { class: "sp-frame", "font-size": fs, "data-frame": frameName, "data-origin": o.join(",") });
    const world = el("g", { transform: `translate(0 ${h}) scale(1 -1)` }, svg);
    el("rect", { x: 0, y: 0, width: w, height: h, class: "sp-world" }, world);
    const motion = scene.motion || { times: [], offsets: {}, goal: [] };
    scene.obstacles.forEach((ob, k) => {
      let d = [0, 0];
      if (ob.moving && opts.time !== undefined) d = SP.offsetAt(motion, k, opts.time);
      shape(world, ob, d[0], d[1], "sp-obstacle" + (ob.moving ? " sp-moving" : ""));
      const tr = motion.offsets[String(k)];
      if (ob.moving && tr) {
        const c = refPoint(ob);
        el("polyline", { points: tr.map((o) => (c[0] + o[0]) + "," + (c[1] + o[1])).join(" "), class: "sp-track" }, world);
      }
    });
    if (motion.goal && motion.goal.length)
      el("polyline", { points: motion.goal.map((p) => p.join(",")).join(" "), class: "sp-track sp-goal-track" }, world);
    for (const p of paths) {
      const g = el(p.href ? "a" : "g", { class: "sp-path-group", "data-run": p.run, "data-name": p.name || "" }, world);
      if (p.href) g.setAttribute("href", p.href);
      const pl = el("polyline", { points: p.points.map((q) => q[0] + "," + q[1]).join(" "), stroke: p.color,
        class: "sp-path" + (p.success ? "" : " sp-failed") }, g);
      const tt = el("title", {}, pl); tt.textContent = `${p.name || ""} run ${p.run}${p.reason ? ": " + p.reason : ""}`;
      const r = 0.012 * Math.max(w, h);
      for (const c of p.collisions || []) {  // where it touched an obstacle
        const mk = el("path", { d: `M${c[0] - r},${c[1] - r}L${c[0] + r},${c[1] + r}M${c[0] - r},${c[1] + r}L${c[0] + r},${c[1] - r}`,
          class: "sp-failure sp-collision" }, g);
        el("title", {}, mk).textContent = `run ${p.run}: collision at t = ${c[2]} s`;
      }
      if (!p.success && p.failure !== "collision" && p.points.length) {  // where it stopped
        const e = p.points[p.points.length - 1];
        const mk = el("rect", { x: e[0] - r * 0.7, y: e[1] - r * 0.7, width: 1.4 * r, height: 1.4 * r, class: "sp-failure sp-" + (p.failure || "other") }, g);
        el("title", {}, mk).textContent = `run ${p.run}: ${p.failure || "failed"}${p.reason ? " (" + p.reason + ")" : ""}`;
      }
    }
    const start = el("circle", { cx: scene.start[0], cy: scene.start[1], r: 0.015 * Math.max(w, h), class: "sp-start" }, world);
    el("title", {}, start).textContent = `start ${at(scene.start[0], scene.start[1])}, ${frameName} frame`;
    let goal = scene.goal;
    if (opts.time !== undefined && motion.goal && motion.goal.length) {
      const i = Math.min(motion.goal.length - 1, Math.max(0, motion.times.findIndex((t) => t >= opts.time)));
      goal = motion.goal[i];
    }
    const goalMark = el("circle", { cx: goal[0], cy: goal[1], r: 0.02 * Math.max(w, h), class: "sp-goal" }, world);
    el("title", {}, goalMark).textContent = `goal ${at(goal[0], goal[1])}, ${frameName} frame`;
    if (opts.robot) el("circle", { cx: opts.robot[0], cy: opts.robot[1], r: scene.robot_radius, class: "sp-robot" }, world);
    return svg;
  };
})();
