/* Jobs list: live over Server-Sent Events (/events), polling /ui/jobs when they fail. */
(function () {
  "use strict";
  SP.header("jobs");
  const main = SP.q("#main");
  const states = ["all", "queued", "waiting", "running", "done", "failed", "cancelled"];
  const params = new URLSearchParams(location.search);
  let filter = params.get("state") || "all";
  main.insertAdjacentHTML("beforeend", `<p><label>State <select id="filter">${states.map((s) =>
    `<option${s === filter ? " selected" : ""}>${s}</option>`).join("")}</select></label>
    <span class="muted" id="live"></span></p>
    <table id="jobs"><thead><tr><th class="l">job</th><th class="l">kind</th><th class="l">contents</th><th class="l">state</th>
    <th class="l">progress</th><th>runs</th><th>failed</th><th>runs/s</th><th>ETA</th><th class="l">created</th><th></th></tr></thead>
    <tbody></tbody></table><p class="err" id="error"></p>`);
  let last = null;

  function render(snapshot) {
    last = snapshot;
    const rows = snapshot.jobs.filter((j) => filter === "all" || j.state === filter);
    SP.q("#status").textContent = `${rows.length} of ${snapshot.jobs.length} jobs`;
    SP.q("#live").textContent = "updated " + SP.time(snapshot.time);
    SP.q("#jobs tbody").innerHTML = rows.map((j) => {
      const done = j.runs_done + j.runs_failed;
      const active = j.state === "queued" || j.state === "running" || j.state === "waiting";
      const why = j.waiting ? ` title="${SP.esc(j.waiting)}"` : "";
      return `<tr data-job="${SP.esc(j.id)}" data-state="${j.state}">
        <td class="l"><a href="/ui/jobs/${encodeURIComponent(j.id)}">${SP.esc(j.id)}</a></td>
        <td class="l">${j.kind}</td><td class="l contents">${SP.esc(j.contents || "")}</td><td class="l"><span class="state state-${j.state}"${why}>${j.state}</span>${j.waiting ? `<div class="waiting">${SP.esc(j.waiting)}</div>` : ""}</td>
        <td class="l"><span class="bar"><span data-progress="${(100 * j.progress).toFixed(1)}"></span></span>
          ${(100 * j.progress).toFixed(1)}%</td>
        <td>${done} / ${j.runs_total}</td><td>${j.runs_failed}</td>
        <td class="rate">${j.state === "running" ? SP.num(j.rate, 1) : ""}</td>
        <td class="eta">${active ? SP.duration(j.eta) : ""}</td><td class="l">${SP.time(j.created)}</td>
        <td>${active ? `<button class="cancel" data-job="${SP.esc(j.id)}">cancel</button>` : ""}</td></tr>`;
    }).join("");
    /* widths through the CSSOM: the dashboard's CSP allows no inline style attribute */
    for (const bar of SP.q("#jobs tbody").querySelectorAll("[data-progress]")) bar.style.width = bar.dataset.progress + "%";
  }

  SP.q("#filter").onchange = (e) => {
    filter = e.target.value;
    history.replaceState(null, "", filter === "all" ? "/" : "/?state=" + filter);
    if (last) render(last);
  };
  SP.q("#jobs").onclick = async (e) => {
    const b = e.target.closest("button.cancel");
    if (!b) return;
    b.disabled = true;
    const r = await SP.cancelJob(b.dataset.job);
    SP.q("#error").textContent = r.ok ? "" : `cancel failed (${r.status}): ${JSON.stringify(r.data && r.data.detail)}`;
    b.disabled = false;
  };

  function poll() {
    SP.api("/ui/jobs").then((r) => r.ok && render(r.data)).finally(() => setTimeout(poll, 2000));
  }
  if (window.EventSource) {
    const es = new EventSource("/events");
    es.addEventListener("jobs", (e) => render(JSON.parse(e.data)));
    es.onerror = () => { if (es.readyState === EventSource.CLOSED) poll(); };
  } else {
    poll();
  }
})();
