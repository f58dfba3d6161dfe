/* Submit page: a form built from /catalog (names, parameters and their defaults) and the job
   specs' defaults (/ui/config), posting to /jobs; each validation error is shown at its field. */
(function () {
  "use strict";
  SP.header("submit");
  const main = SP.q("#main");

  function checks(name, items, describe) {
    return `<div class="choices" data-field="${name}">` + items.map((it) =>
      `<label title="${SP.esc(describe(it))}"><input type="checkbox" name="${name}" value="${SP.esc(it.name)}"> ${SP.esc(it.name)}</label>`).join("")
      + `</div><div class="err" data-error="${name}"></div>`;
  }
  function number(name, value, label) {
    return `<label>${label} <input type="text" name="${name}" value="${SP.esc(value)}"></label><div class="err" data-error="${name}"></div>`;
  }
  function paramInputs(kind, item) {
    return `<fieldset class="params" data-member="${SP.esc(item.name)}" data-kind="${kind}" hidden><legend>${SP.esc(item.name)} parameters</legend>` +
      Object.entries(item.params).map(([k, v]) => {
        const choices = item.choices[k];
        const input = choices
          ? `<select data-param="${k}" data-default="${SP.esc(v)}">${choices.map((c) => `<option${String(c) === String(v) ? " selected" : ""}>${SP.esc(c)}</option>`).join("")}</select>`
          : `<input type="text" data-param="${k}" data-default="${SP.esc(v)}" value="${SP.esc(v)}">`;
        return `<label>${SP.esc(k)} ${input}</label><div class="err" data-error="params.${SP.esc(item.name)}.${k}"></div>`;
      }).join("") + `<div class="err" data-error="params.${SP.esc(item.name)}"></div></fieldset>`;
  }

  function build(cat, cfg) {
    const b = cfg.defaults.benchmark, m = cfg.defaults.map;
    main.insertAdjacentHTML("beforeend", `<form class="submit" id="submit-form" novalidate>
      <label><input type="radio" name="kind" value="benchmark" checked> benchmark job</label>
      <label><input type="radio" name="kind" value="map"> map job</label>
      <fieldset id="benchmark-fields"><legend>Benchmark</legend>
        <b>algorithms</b>${checks("algorithms", cat.optimizers, (o) => o.summary)}
        <b>functions</b>${checks("functions", cat.functions, (f) => f.description)}
        ${number("dims", b.dims.join(", "), "dims (comma-separated)")}
        ${number("runs", b.runs, "runs per cell")}${number("agents", b.agents, "agents")}
        ${number("iterations", b.iterations, "iterations")}${number("seed", b.seed, "seed")}
        <label>transform <select name="transform">${cfg.transforms.map((t) =>
          `<option value="${SP.esc(t)}"${t === b.transform ? " selected" : ""}>${SP.esc(t)}</option>`).join("")}</select></label><div class="err" data-error="transform"></div>
        ${number("reference", "", "reference algorithm for the statistics (empty: the last one)")}
        ${cat.optimizers.map((o) => paramInputs("benchmark", o)).join("")}
      </fieldset>
      <fieldset id="map-fields" hidden><legend>Map</legend>
        <b>planners</b>${checks("planners", cat.planners, (p) => p.description)}
        <b>maps</b>${checks("maps", cat.maps, (x) => x.description)}
        ${number("map_runs", m.runs, "runs per cell")}${number("map_seed", m.seed, "seed")}
        ${number("map_reference", "", "reference planner for the statistics (empty: the last one)")}
        ${number("optimum_budget", "", "time budget of each map's exact optimum, s (empty: 30)")}
        ${cat.planners.map((p) => paramInputs("map", p)).join("")}
      </fieldset>
      <div class="err" data-error="_general" id="general-error"></div>
      <button type="submit" id="submit-button">Submit</button> <span id="result"></span></form>`);
    const form = SP.q("#submit-form");
    const kind = () => form.querySelector("input[name=kind]:checked").value;
    form.addEventListener("change", (e) => {
      SP.q("#benchmark-fields").hidden = kind() !== "benchmark";
      SP.q("#map-fields").hidden = kind() !== "map";
      if (e.target.name === "algorithms" || e.target.name === "planners") {
        const fs = form.querySelector(`fieldset.params[data-member="${CSS.escape(e.target.value)}"][data-kind="${kind()}"]`);
        if (fs) fs.hidden = !e.target.checked;
      }
    });
    form.onsubmit = (e) => { e.preventDefault(); send(form, kind()); };
    SP.q("#status").textContent = "";
    document.body.dataset.loaded = "1";
  }

  const value = (form, name) => form.querySelector(`[name="${name}"]`).value.trim();
  const asNumber = (s) => (s !== "" && isFinite(Number(s)) ? Number(s) : s);
  const checked = (form, name) => [...form.querySelectorAll(`input[name="${name}"]:checked`)].map((i) => i.value);

  function params(form, kind, members) {
    const out = {};
    for (const name of members) {
      const fs = form.querySelector(`fieldset.params[data-member="${CSS.escape(name)}"][data-kind="${kind}"]`);
      if (!fs) continue;
      for (const input of fs.querySelectorAll("[data-param]")) {
        if (input.value === input.dataset.default) continue;
        (out[name] = out[name] || {})[input.dataset.param] = asNumber(input.value);
      }
    }
    return out;
  }

  function spec(form, kind) {
    if (kind === "benchmark") {
      const algorithms = checked(form, "algorithms");
      return { kind: "benchmark", algorithms: algorithms, functions: checked(form, "functions"),
        dims: value(form, "dims").split(",").map((s) => asNumber(s.trim())).filter((s) => s !== ""),
        runs: asNumber(value(form, "runs")), agents: asNumber(value(form, "agents")),
        iterations: asNumber(value(form, "iterations")), seed: asNumber(value(form, "seed")),
        transform: form.querySelector("[name=transform]").value, params: params(form, "benchmark", algorithms),
        ...(value(form, "reference") ? { reference: value(form, "reference") } : {}) };
    }
    const planners = checked(form, "planners");
    return { kind: "map", planners: planners, maps: checked(form, "maps"), runs: asNumber(value(form, "map_runs")),
      seed: asNumber(value(form, "map_seed")), params: params(form, "map", planners),
      ...(value(form, "map_reference") ? { reference: value(form, "map_reference") } : {}),
      ...(value(form, "optimum_budget") ? { optimum_budget: asNumber(value(form, "optimum_budget")) } : {}) };
  }

  /* The form field of an error's loc: ["body", kind?, field, ...]. */
  function fieldOf(loc, kind) {
    let rest = loc.slice(loc[0] === "body" ? 1 : 0);
    if (rest[0] === kind || rest[0] === "benchmark" || rest[0] === "map") rest = rest.slice(1);
    if (!rest.length) return "_general";
    let f = String(rest[0]);
    if (kind === "map" && (f === "runs" || f === "seed" || f === "reference")) f = "map_" + f;
    if (f === "params" && rest.length >= 3) return `params.${rest[1]}.${rest[2]}`;
    if (f === "params" && rest.length === 2) return `params.${rest[1]}`;
    return f;
  }

  async function send(form, kind) {
    for (const e of form.querySelectorAll(".err")) e.textContent = "";
    SP.q("#result").textContent = "submitting...";
    const r = await SP.api("/jobs", { method: "POST", json: spec(form, kind) });
    if (r.ok) {
      SP.q("#result").innerHTML = `submitted: <a id="new-job" href="/ui/jobs/${encodeURIComponent(r.data.id)}">${SP.esc(r.data.id)}</a> (${r.data.runs_total} runs)`;
      return;
    }
    SP.q("#result").textContent = `rejected (${r.status})`;
    const detail = r.data && r.data.detail;
    const errors = Array.isArray(detail) ? detail : [{ loc: [], msg: typeof detail === "string" ? detail : JSON.stringify(detail) }];
    for (const e of errors) {
      let box = form.querySelector(`[data-error="${CSS.escape(fieldOf(e.loc || [], kind))}"]`);
      if (!box) box = SP.q("#general-error");
      box.textContent += (box.textContent ? "; " : "") + e.msg;
    }
  }

  Promise.all([SP.api("/catalog"), SP.api("/ui/config")]).then(([c, g]) => {
    if (c.ok && g.ok) build(c.data, g.data); else SP.q("#status").textContent = "could not load /catalog";
  });
})();
