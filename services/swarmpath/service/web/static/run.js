/* Run page: a benchmark run's convergence curve and best position; a map run's path over the
   map with a time slider (robot, moving obstacles and goal at that time), metrics and failure. */
(function () {
  "use strict";
  SP.header("jobs");
  const parts = location.pathname.split("/");
  const id = decodeURIComponent(parts[3]), runId = parseInt(parts[5], 10);
  const main = SP.q("#main");
  SP.q("h1").innerHTML = `Run ${runId} of job <a href="/ui/jobs/${encodeURIComponent(id)}">${SP.esc(id)}</a>`;
  main.insertAdjacentHTML("beforeend", `<div class="grid"><div class="card run-plot" id="plot"></div>
    <div><table id="metrics"><tbody></tbody></table><p class="err" id="failure"></p><div id="position"></div></div></div>`);

  function metrics(run) {
    const skip = new Set(["curve", "best_position", "path"]);
    SP.q("#metrics tbody").innerHTML = Object.entries(run).filter(([k]) => !skip.has(k)).map(([k, v]) =>
      `<tr><th class="l">${SP.esc(k)}</th><td class="l">${SP.esc(typeof v === "number" ? SP.num(v, 6) : v)}</td></tr>`).join("");
  }

  function failure(run) {  // as the job page's aggregates name it (series.failure_kind)
    if (run.success !== false) return null;
    if (run.failure_class) return run.failure_class;
    const reason = String(run.reason || "");
    if (run.collisions > 0 || reason.startsWith("collided")) return "collision";
    if (reason.includes("gave up") || reason.includes("stall")) return "stall";
    return reason.includes("limit") ? "timeout" : "other";
  }

  async function load() {
    const r = await SP.api(`/jobs/${encodeURIComponent(id)}/runs/${runId}`);
    if (!r.ok) { SP.q("#status").textContent = `${r.status}: ${JSON.stringify(r.data && r.data.detail)}`; return; }
    const run = r.data;
    SP.q("#status").textContent = `${run.cell}, run ${run.run}: ${run.state}`;
    metrics(run);
    const why = run.failure_class ? `${run.failure_class} (${run.reason}${run.failure_detail ? ": " + run.failure_detail : ""})` : run.reason;
    const reason = run.failure || (run.success === false ? why : "");
    SP.q("#failure").textContent = reason ? "Failure: " + reason : "";
    if (run.curve) {
      const x = run.curve.map((_, i) => i + 1);
      const y = run.curve.map(Number);
      SP.lineChart(SP.q("#plot"), { title: `${run.algorithm} on ${run.function}, dim ${run.dim}`, xlabel: "iteration",
        ylabel: "best-so-far f(x)", logy: y.every((v) => v > 0), series: [{ name: run.algorithm, color: SP.color(0), x: x, y: y }] });
      if (run.best_position) SP.q("#position").innerHTML = `<h2>Best position</h2><table id="best-position"><tbody>` +
        run.best_position.map((v, i) => `<tr><th>x${i + 1}</th><td>${SP.num(v, 6)}</td></tr>`).join("") + "</tbody></table>";
    } else if (run.path) {
      const path = run.path;
      const tEnd = path.length ? path[path.length - 1][2] : 0;
      const s = await SP.api(`/ui/jobs/${encodeURIComponent(id)}/scene?run=${runId}&t_end=${tEnd}`);
      if (!s.ok) return;
      const scene = s.data;
      const draw = (t) => {
        let i = 0; while (i < path.length - 1 && path[i + 1][2] <= t) i++;
        SP.mapChart(SP.q("#plot"), scene, [{ name: run.planner, color: SP.color(0), points: path, run: run.run,
          success: run.success !== false, failure: failure(run), reason: run.reason, collisions: scene.collisions }],
          { time: t, robot: path.length ? path[i] : null });
        SP.q("#time-label").textContent = `t = ${t.toFixed(2)} s`;
      };
      const ctl = document.createElement("p");
      ctl.innerHTML = `<input type="range" id="time" min="0" max="${tEnd}" step="${Math.max(tEnd / 500, 0.001)}" value="${tEnd}"> <span id="time-label"></span>`;
      SP.q("#plot").after(ctl);
      SP.q("#time").oninput = (e) => draw(parseFloat(e.target.value));
      draw(tEnd);
    }
    document.body.dataset.loaded = "1";
  }
  load();
})();
