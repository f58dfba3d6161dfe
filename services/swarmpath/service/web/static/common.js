/* swarmpath dashboard: helpers shared by the pages (requests, token, formatting, header). */
(function () {
  "use strict";
  const SP = (window.SP = window.SP || {});
  const TOKEN_KEY = "swarmpath-token";

  SP.token = () => localStorage.getItem(TOKEN_KEY) || "";
  SP.setToken = (t) => (t ? localStorage.setItem(TOKEN_KEY, t) : localStorage.removeItem(TOKEN_KEY));

  /* fetch JSON; mutating requests carry the bearer token when one is stored. */
  SP.api = async function (path, opts) {
    opts = Object.assign({ method: "GET", headers: {} }, opts || {});
    if (opts.method !== "GET" && SP.token()) opts.headers.Authorization = "Bearer " + SP.token();
    if (opts.json !== undefined) {
      opts.headers["Content-Type"] = "application/json";
      opts.body = JSON.stringify(opts.json);
    }
    const res = await fetch(path, opts);
    let data = null;
    if (res.status !== 304) {
      const type = res.headers.get("content-type") || "";
      data = type.includes("json") ? await res.json() : await res.text();
    }
    if (res.status === 401) SP.askToken("This coordinator requires a token (SWARMPATH_TOKEN).");
    return { ok: res.ok, status: res.status, data: data, headers: res.headers };
  };

  SP.askToken = function (message) {
    const box = document.getElementById("token-box");
    if (!box) return;
    box.hidden = false;
    document.getElementById("token-message").textContent = message || "";
    document.getElementById("token-input").focus();
  };

  SP.header = function (active) {
    const h = document.createElement("header");
    h.innerHTML = `<a class="brand" href="/">swarmpath</a>
      <nav><a href="/" data-page="jobs">Jobs</a><a href="/ui/workers" data-page="workers">Workers</a>
      <a href="/ui/submit" data-page="submit">Submit</a></nav>
      <span class="token-link"><a href="#" id="token-toggle">token</a></span>
      <form id="token-box" hidden><span id="token-message"></span>
        <input id="token-input" type="password" placeholder="bearer token" autocomplete="off">
        <button type="submit">Save</button></form>`;
    document.body.prepend(h);
    for (const a of h.querySelectorAll("nav a")) if (a.dataset.page === active) a.classList.add("active");
    h.querySelector("#token-toggle").onclick = (e) => { e.preventDefault(); SP.askToken(SP.token() ? "A token is stored." : ""); };
    h.querySelector("#token-box").onsubmit = (e) => {
      e.preventDefault();
      SP.setToken(h.querySelector("#token-input").value.trim());
      h.querySelector("#token-box").hidden = true;
    };
    fetch("/ui/config").then((r) => r.json()).then((c) => {
      if (c.token_required && !SP.token()) SP.askToken("This coordinator requires a token (SWARMPATH_TOKEN) to submit or cancel.");
    }).catch(() => {});
    SP.watchHealth(h);
  };

  /* A banner while the coordinator's store cannot write (disk full: no leases, no new jobs),
     checked every 10 s, gone once it can again. */
  SP.watchHealth = function (header) {
    const alert = document.createElement("div");
    alert.id = "health-alert";
    alert.className = "alert";
    alert.hidden = true;
    header.after(alert);
    const check = () => fetch("/healthz").then((r) => r.json()).then((h) => {
      const problem = h.store && !h.store.writable ? h.store.problem : null;
      alert.hidden = !problem;
      alert.textContent = problem ? "The coordinator cannot store results (no work is handed out, new jobs are refused): " + problem : "";
    }).catch(() => {});
    check();
    setInterval(check, 10000);
  };

  SP.duration = function (s) {
    if (s === null || s === undefined || !isFinite(s)) return "";
    s = Math.round(s);
    if (s < 60) return s + " s";
    if (s < 3600) return Math.floor(s / 60) + " min " + (s % 60) + " s";
    return Math.floor(s / 3600) + " h " + Math.floor((s % 3600) / 60) + " min";
  };
  SP.time = (t) => (t ? new Date(t * 1000).toISOString().replace("T", " ").slice(0, 19) + "Z" : "");
  SP.num = function (v, digits) {
    if (v === null || v === undefined) return "";
    if (typeof v === "string") return v;
    if (!isFinite(v)) return String(v);
    const a = Math.abs(v);
    if (a !== 0 && (a >= 1e5 || a < 1e-3)) return v.toExponential(digits === undefined ? 2 : digits);
    return String(+v.toFixed(digits === undefined ? 4 : digits));
  };
  /* n significant digits (a small std is 0.0041, not 0): plain for 1e-3 <= |v| < 1e5. */
  SP.sig = function (v, n) {
    if (v === null || v === undefined) return "";
    if (typeof v === "string") return v;
    if (!isFinite(v)) return String(v);
    if (v === 0) return "0";
    const a = Math.abs(v);
    n = n === undefined ? 3 : n;
    if (a >= 1e5 || a < 1e-3) return v.toExponential(n - 1);
    return String(Number(v.toPrecision(n)));
  };
  /* A box plot's statistics times k (a gap fraction shown in percent). */
  SP.scaled = function (stats, k) {
    if (!stats) return stats;
    const out = Object.assign({}, stats);
    for (const key of ["lo", "hi", "q1", "q3", "median", "mean", "min", "max"]) if (typeof out[key] === "number") out[key] = k * out[key];
    if (Array.isArray(out.outliers)) out.outliers = out.outliers.map((v) => k * v);
    return out;
  };
  SP.esc = (s) => String(s === null || s === undefined ? "" : s).replace(/[&<>"']/g,
    (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" })[c]);
  SP.q = (sel, root) => (root || document).querySelector(sel);
  SP.cancelJob = async function (id) {
    const r = await SP.api("/jobs/" + encodeURIComponent(id), { method: "DELETE" });
    return r;
  };
})();
