/* Submit page: a form built from /catalog (names, parameters and their defaults), the job
   specs' defaults (/ui/config) and the uploaded maps (/maps), posting to /jobs; each validation
   error is shown at its field. A map can be uploaded here too (POST /maps, a MovingAI .map with
   its .scen) and is then chosen; a map with a .scen gets a pairs picker (pairs.js). */
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

  /* the uploaded maps by id (the pairs pickers read their .scen counts) and the pairs limit */
  const known = {};
  let pairLimit = 500;
  function uploaded(maps) {
    return `<div class="choices" data-field="uploaded" id="uploaded-maps">` + maps.map(uploadedChoice).join("")
      + `</div><div id="pair-pickers">` + maps.filter((m) => m.scen).map((m) => SP.pairs.fields(m, pairLimit)).join("") + `</div>`;
  }
  function uploadedChoice(m) {
    known[m.id] = m;
    const size = m.size ? ` ${SP.num(m.size[0], 3)} x ${SP.num(m.size[1], 3)} m` : "";
    const scen = m.scen ? `, ${m.scen.pairs} .scen pairs` : "";
    return `<label title="${SP.esc(m.id)}: ${SP.esc(m.format)},${SP.esc(size)}, ${m.obstacles} obstacles${scen}"><input type="checkbox" name="uploaded" value="${SP.esc(m.id)}"> ${SP.esc(m.name)} <span class="muted">(uploaded${m.scen ? ", .scen" : ""})</span></label>`;
  }
  const picker = (id) => SP.q(`#pair-pickers fieldset.pairs[data-map="${CSS.escape(id)}"]`);
  function showPicker(id, on) {
    const fs = picker(id);
    if (!fs) return;
    fs.hidden = !on;
    if (on) SP.pairs.refresh(fs, known[id], pairLimit);
  }
  function uploadFields() {
    return `<fieldset id="upload"><legend>Upload a map</legend>
      <label>format <select name="up_format"><option value="nav2">nav2 (map YAML + its image)</option><option value="movingai">MovingAI .map</option></select></label>
      <label>name <input type="text" name="up_name" placeholder="the file's name"></label>
      <span class="up-nav2"><label>YAML <input type="file" name="up_yaml" accept=".yaml,.yml"></label>
      <label>image <input type="file" name="up_image" accept=".pgm,.png,.bmp"></label></span>
      <span class="up-movingai" hidden><label>.map <input type="file" name="up_map" accept=".map"></label>
      <label>metres per cell <input type="text" name="up_resolution" value="1"></label>
      <label>.scen (optional: its start/goal pairs) <input type="file" name="up_scen" accept=".scen"></label></span>
      <button type="button" id="upload-button">Upload</button> <span id="upload-result"></span>
      ${["name", "yaml", "image", "map", "resolution", "scen"].map((f) => `<div class="err" data-error="up.${f}"></div>`).join("")}
      <div class="err" data-error="upload"></div></fieldset>`;
  }

  /* base64 of a file's bytes (in slices: String.fromCharCode takes a bounded argument list) */
  async function base64(file) {
    const bytes = new Uint8Array(await file.arrayBuffer());
    let text = "";
    for (let i = 0; i < bytes.length; i += 0x8000) text += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
    return btoa(text);
  }

  async function upload(form) {
    const box = form.querySelector('[data-error="upload"]'), result = SP.q("#upload-result");
    for (const e of SP.q("#upload").querySelectorAll(".err")) e.textContent = "";
    result.textContent = "uploading...";
    const fmt = form.querySelector("[name=up_format]").value;
    const file = (n) => form.querySelector(`[name=${n}]`).files[0];
    const main = fmt === "nav2" ? file("up_yaml") : file("up_map");
    if (!main || (fmt === "nav2" && !file("up_image"))) {
      result.textContent = "";
      box.textContent = fmt === "nav2" ? "choose the map's YAML and its image" : "choose a .map file";
      return;
    }
    const name = value(form, "up_name") || main.name.replace(/\.[^.]*$/, "").replace(/[^A-Za-z0-9_.-]/g, "-");
    const body = fmt === "nav2"
      ? { name: name, format: "nav2", yaml: await main.text(), image: await base64(file("up_image")) }
      : { name: name, format: "movingai", map: await main.text(), resolution: asNumber(value(form, "up_resolution")),
        ...(file("up_scen") ? { scen: await file("up_scen").text() } : {}) };
    const r = await SP.api("/maps", { method: "POST", json: body });
    if (!r.ok) {
      result.textContent = `rejected (${r.status})`;
      const detail = r.data && r.data.detail;
      const errors = Array.isArray(detail) ? detail : [{ loc: [], msg: typeof detail === "string" ? detail : JSON.stringify(detail) }];
      for (const e of errors) {  /* at the upload's field (["body", "scen"]), named there too */
        const field = (e.loc || []).slice(1).join(".");
        const at = form.querySelector(`[data-error="up.${CSS.escape(field.split(".")[0])}"]`) || box;
        at.textContent += (at.textContent ? "; " : "") + (field ? `${field}: ` : "") + e.msg;
      }
      return;
    }
    SP.q("#uploaded-maps").insertAdjacentHTML("beforeend", uploadedChoice(r.data));
    SP.q("#uploaded-maps").lastElementChild.querySelector("input").checked = true;
    if (r.data.scen) SP.q("#pair-pickers").insertAdjacentHTML("beforeend", SP.pairs.fields(r.data, pairLimit));
    showPicker(r.data.id, true);
    const pairsNote = r.data.scen ? `, ${r.data.scen.pairs} .scen pairs in buckets ${SP.pairs.spans(Object.keys(r.data.scen.buckets).map(Number))}` : "";
    result.innerHTML = `uploaded <span id="uploaded-id">${SP.esc(r.data.id)}</span> (${SP.esc(r.data.name)}${pairsNote}), chosen below the presets`;
  }

  function build(cat, cfg, maps) {
    const b = cfg.defaults.benchmark, m = cfg.defaults.map;
    pairLimit = (cfg.limits || {}).scen_pairs_per_map || pairLimit;
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
        <b>uploaded maps</b>${uploaded(maps)}
        ${uploadFields()}
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
      const fmt = form.querySelector("[name=up_format]").value;
      form.querySelector(".up-nav2").hidden = fmt !== "nav2";
      form.querySelector(".up-movingai").hidden = fmt !== "movingai";
      if (e.target.name === "uploaded") showPicker(e.target.value, e.target.checked);
      const pairsOf = e.target.closest("fieldset.pairs");
      if (pairsOf) SP.pairs.refresh(pairsOf, known[pairsOf.dataset.map], pairLimit);
      if (e.target.name === "algorithms" || e.target.name === "planners") {
        const fs = form.querySelector(`fieldset.params[data-member="${CSS.escape(e.target.value)}"][data-kind="${kind()}"]`);
        if (fs) fs.hidden = !e.target.checked;
      }
    });
    form.addEventListener("input", (e) => {
      const fs = e.target.closest("fieldset.pairs");
      if (fs) SP.pairs.refresh(fs, known[fs.dataset.map], pairLimit);
    });
    form.onsubmit = (e) => { e.preventDefault(); send(form, kind()); };
    SP.q("#upload-button").onclick = () => upload(form);
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
    const maps = [...checked(form, "maps"), ...checked(form, "uploaded").map((id) => uploadedEntry(form, id))];
    return { kind: "map", planners: planners, maps: maps, runs: asNumber(value(form, "map_runs")),
      seed: asNumber(value(form, "map_seed")), params: params(form, "map", planners),
      ...(value(form, "map_reference") ? { reference: value(form, "map_reference") } : {}),
      ...(value(form, "optimum_budget") ? { optimum_budget: asNumber(value(form, "optimum_budget")) } : {}) };
  }

  /* An uploaded map's entry: {"map": id}, with the pairs its picker names (a picker that names
     none sensible throws {field, msg}: the form is not sent). */
  function uploadedEntry(form, id) {
    const fs = picker(id);
    if (!fs) return { map: id };
    const c = SP.pairs.choice(fs, known[id], pairLimit);
    if (c.error) throw { field: `pairs.${id}`, msg: c.error };
    return c.scen ? { map: id, scen: c.scen } : { map: id };
  }

  /* The form field of an error's loc: ["body", kind?, field, ...]; an error of an uploaded map
     with a pairs picker (["body", "maps", i, "scen", ...]) goes to its picker, the rest of the
     loc named in the message. */
  function fieldOf(loc, kind, sent) {
    let rest = loc.slice(loc[0] === "body" ? 1 : 0);
    if (rest[0] === kind || rest[0] === "benchmark" || rest[0] === "map") rest = rest.slice(1);
    if (!rest.length) return ["_general", ""];
    const entry = rest[0] === "maps" && sent && sent.maps ? sent.maps[rest[1]] : undefined;
    if (entry && entry.map && picker(entry.map)) return [`pairs.${entry.map}`, rest.slice(2).join(".")];
    return [fieldName(rest, kind), ""];
  }
  function fieldName(rest, kind) {
    let f = String(rest[0]);
    if (kind === "map" && (f === "runs" || f === "seed" || f === "reference")) f = "map_" + f;
    if (f === "params" && rest.length >= 3) return `params.${rest[1]}.${rest[2]}`;
    if (f === "params" && rest.length === 2) return `params.${rest[1]}`;
    return f;
  }

  async function send(form, kind) {
    for (const e of form.querySelectorAll(".err")) e.textContent = "";
    let sent;
    try {
      sent = spec(form, kind);
    } catch (e) {
      if (!e || !e.field) throw e;
      SP.q("#result").textContent = "not sent";
      form.querySelector(`[data-error="${CSS.escape(e.field)}"]`).textContent = e.msg;
      return;
    }
    SP.q("#result").textContent = "submitting...";
    const r = await SP.api("/jobs", { method: "POST", json: sent });
    if (r.ok) {
      SP.q("#result").innerHTML = `submitted: <a id="new-job" href="/ui/jobs/${encodeURIComponent(r.data.id)}">${SP.esc(r.data.id)}</a> (${r.data.runs_total} runs)`;
      return;
    }
    SP.q("#result").textContent = `rejected (${r.status})`;
    const detail = r.data && r.data.detail;
    const errors = Array.isArray(detail) ? detail : [{ loc: [], msg: typeof detail === "string" ? detail : JSON.stringify(detail) }];
    for (const e of errors) {
      const [field, within] = fieldOf(e.loc || [], kind, sent);
      let box = form.querySelector(`[data-error="${CSS.escape(field)}"]`);
      if (!box) box = SP.q("#general-error");
      box.textContent += (box.textContent ? "; " : "") + (within ? `${within}: ` : "") + e.msg;
    }
  }

  Promise.all([SP.api("/catalog"), SP.api("/ui/config"), SP.api("/maps?limit=1000")]).then(([c, g, m]) => {
    if (c.ok && g.ok) build(c.data, g.data, m.ok ? m.data : []); else SP.q("#status").textContent = "could not load /catalog";
  });
})();
