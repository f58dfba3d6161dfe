/* Workers page: /workers every 2 s. */
(function () {
  "use strict";
  SP.header("workers");
  SP.q("#main").insertAdjacentHTML("beforeend", `<table id="workers"><thead><tr><th class="l">worker</th><th class="l">host</th>
    <th>pid</th><th>slots</th><th class="l">alive</th><th>current runs</th><th>runs done</th><th class="l">last seen</th></tr></thead><tbody></tbody></table>`);
  async function refresh() {
    const r = await SP.api("/workers");
    if (r.ok) {
      SP.q("#status").textContent = `${r.data.length} workers, ${r.data.filter((w) => w.alive).length} alive`;
      SP.q("#workers tbody").innerHTML = r.data.map((w) => `<tr data-worker="${SP.esc(w.id)}"><td class="l">${SP.esc(w.id)}</td>
        <td class="l">${SP.esc(w.host)}</td><td>${w.pid}</td><td>${w.slots}</td><td class="l">${w.alive ? "yes" : "no"}</td>
        <td title="${SP.esc(w.current_runs.join(" "))}">${w.current_runs.length}</td><td>${w.runs_done}</td>
        <td class="l">${SP.time(w.last_seen)}</td></tr>`).join("");
      document.body.dataset.loaded = "1";
    }
    setTimeout(refresh, 2000);
  }
  refresh();
})();
