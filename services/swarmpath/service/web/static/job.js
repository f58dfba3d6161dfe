/* Job page: status, downloads, and the job's aggregates (/ui/jobs/{id}/data): a benchmark's
   pivot table, convergence curves and box plots; a map job's maps with every path, success
   rates and box plots. Refreshed every 2 s while the job runs (304 when nothing changed). */
(function () {
  "use strict";
  SP.header("jobs");
  const id = decodeURIComponent(location.pathname.split("/")[3]);
  const main = SP.q("#main");
  SP.q("h1").textContent = "Job " + id;
  main.insertAdjacentHTML("beforeend", `<p id="summary"></p><p class="downloads" id="downloads"></p>
    <div id="content"></div><p class="legend" id="notes"></p><dl class="legend" id="legend"></dl>`);
  let etag = null, colors = {}, status = null, loading = false;
  let race = null; /* a raced job's GET /jobs/{id}/race, fetched with each new data */

  function color(name, list) {
    if (!(name in colors)) colors[name] = SP.color(list.indexOf(name));
    return colors[name];
  }
  function downloads(kind) {
    const j = "/jobs/" + encodeURIComponent(id);
    SP.q("#downloads").innerHTML = `Downloads:
      <a href="${j}/mcap" id="dl-mcap">MCAP</a>
      <a href="${j}/summary?format=csv" id="dl-summary-csv">summary CSV</a>
      <a href="${j}/summary" id="dl-summary-json">summary JSON</a>
      <a href="${j}/runs?format=csv" id="dl-runs-csv">runs CSV</a>
      <a href="${j}/runs?format=parquet" id="dl-runs-parquet">runs Parquet</a>
      <a href="${j}/runs?format=jsonl" id="dl-runs-json">runs JSON lines</a>`;
  }

  function renderStatus(s) {
    status = s;
    const done = s.runs_done + s.runs_failed;
    const active = s.state === "queued" || s.state === "running" || s.state === "waiting";
    const pins = Object.entries(s.pins || {}).filter(([, p]) => p.source !== "built-in");
    SP.q("#status").innerHTML = `<span class="state state-${s.state}" id="job-state">${s.state}</span>
      ${s.kind} job, ${done} / ${s.runs_total} runs finished (${s.runs_failed} crashed),
      created ${SP.time(s.created)}${s.finished ? ", ended " + SP.time(s.finished) : ""}
      ${active ? '<button class="cancel" id="cancel">cancel</button>' : ""}
      ${s.waiting ? `<p class="waiting" id="job-waiting">waiting: ${SP.esc(s.waiting)}</p>` : ""}
      ${pins.length ? `<p class="pins" id="job-pins">plugins: ${pins.map(([k, p]) =>
        `${SP.esc(k)} (${SP.esc(p.origin)}, ${SP.esc(p.digest.slice(0, 12))})`).join(", ")}</p>` : ""}`;
    const b = SP.q("#cancel");
    if (b) b.onclick = async () => { const r = await SP.cancelJob(id); if (r.ok) renderStatus(r.data); };
  }

  /* A12 and the Bayesian P(better/equivalent/worse) under a marker; the shift in the title. */
  function effect(per, name) {
    const e = per && per[name];
    if (!e) return "";
    const p = (v) => (v === null || v === undefined ? "-" : v.toFixed(2));
    /* a raced job: no shift interval (it assumes a fixed number of runs) */
    const title = !race && e.shift !== undefined ? `Hodges-Lehmann shift ${SP.num(e.shift, 3)} [${SP.num(e.shift_low, 3)}, ${SP.num(e.shift_high, 3)}]` : "";
    return `<div class="effect" title="${title}">A12 ${p(e.a12)}` + (e.p_better !== undefined
      ? ` &middot; P ${p(e.p_better)}/${p(e.p_equivalent)}/${p(e.p_worse)}` : "") + `</div>`;
  }

  function pivot(data) {
    const st = data.statistics || { markers: {}, counts: {}, friedman: {} };
    const algs = data.algorithms;
    const raced = race && st.reference ? raceMarkers(race, st.reference) : null;
    let html = `<h2>Best fitness: mean (std) over runs</h2><table id="pivot"><thead><tr><th class="l">function</th><th>dim</th>`
      + algs.map((a) => `<th>${SP.esc(a)}</th>`).join("") + `</tr></thead><tbody>`;
    for (const g of data.groups) {
      html += `<tr data-group="${g.function}/${g.dim}"><td class="l">${g.function}</td><td>${g.dim}</td>`;
      for (const a of algs) {
        const c = g.algorithms[a], d = c && c.describe;
        const m = ((race ? raced.markers : st.markers)[g.function + "/" + g.dim] || {})[a];
        const run = c && c.best_run !== null && c.best_run !== undefined ? c.cell * data.runs_per_cell + c.best_run : null;
        const value = d ? SP.num(d.avg, 3) + " (" + SP.sig(d.std, 2) + ")" : "-";
        html += `<td class="${g.best.includes(a) ? "best" : ""}">${run === null ? value
          : `<a class="run-link" title="open the best run" href="/ui/jobs/${encodeURIComponent(id)}/runs/${run}">${value}</a>`}`
          + `${m ? `<span class="marker">${m}</span>` : ""}${effect((st.effects || {})[g.function + "/" + g.dim], a)}</td>`;
      }
      html += "</tr>";
    }
    html += "</tbody><tfoot>";
    if (st.reference) {
      html += `<tr><th class="l" colspan="2">+/=/- vs ${SP.esc(st.reference)}</th>` + algs.map((a) => {
        const c = (raced ? raced.counts : st.counts)[a];
        return `<td>${c ? `${c["+"]}/${c["="]}/${c["-"]}` : "ref."}</td>`;
      }).join("") + "</tr>";
      for (const dim in st.friedman) {
        const f = st.friedman[dim];
        html += `<tr><th class="l" colspan="2">mean rank (dim ${dim})</th>` + algs.map((a) =>
          `<td>${SP.num(f.mean_ranks[a], 2)}</td>`).join("") + "</tr>";
      }
    }
    html += "</tfoot></table>";
    if (raced) html += `<p class="legend">Bold: lowest mean. Markers: the race's decisions against ${SP.esc(st.reference)} (below): + better, - worse, = not decided different (equivalent, or still open). A12: Vargha-Delaney effect size, the probability that a run beats a run of ${SP.esc(st.reference)}. P: posterior probabilities of better / practically equivalent / worse (Bayesian bootstrap of the mean, rope ${SP.esc(st.rope || "")} of the larger distance to the optimum). Mean rank: Friedman ranks of the means over the functions (1 = best).</p>`;
    else if (st.reference) html += `<p class="legend">Bold: lowest mean. Markers: Wilcoxon rank-sum test of each algorithm's best fitness against ${SP.esc(st.reference)} (Holm-adjusted over the table, alpha ${st.alpha}): + significantly better, = no significant difference, - significantly worse. A12: Vargha-Delaney effect size, the probability that a run beats a run of ${SP.esc(st.reference)} (0.5: no effect; hover for the Hodges-Lehmann shift and its 95 % interval). P: posterior probabilities of better / practically equivalent / worse (Bayesian bootstrap of the mean, rope ${SP.esc(st.rope || "")} of the larger distance to the optimum). Mean rank: Friedman ranks of the means over the functions (1 = best).</p>`;
    return html;
  }

  /* Time per run beside the table: wall and CPU seconds (medians over the finished runs; "-"
     where no run has one: CPU times of runs stored before they were measured are missing). */
  function times(data) {
    const algs = data.algorithms;
    const t = (v) => (v === null || v === undefined ? "-" : SP.sig(v, 3));
    let html = `<h2>Time per run (s): wall / CPU, median</h2><table id="times"><thead><tr><th class="l">function</th><th>dim</th>`
      + algs.map((a) => `<th>${SP.esc(a)}</th>`).join("") + `</tr></thead><tbody>`;
    for (const g of data.groups) {
      html += `<tr data-group="${g.function}/${g.dim}"><td class="l">${g.function}</td><td>${g.dim}</td>`
        + algs.map((a) => {
          const c = g.algorithms[a];
          return c && c.runs ? `<td data-algorithm="${SP.esc(a)}"><span class="wall">${t(c.seconds)}</span> / <span class="cpu">${t(c.cpu_seconds)}</span></td>` : "<td>-</td>";
        }).join("") + "</tr>";
    }
    return html + `</tbody></table><p class="legend">Wall: the run's share of the elapsed time of the batch that computed it (grows with the worker's load). CPU: its share of the CPU time of the thread that computed it (does not). Batches of stacked runs share both evenly.</p>`;
  }

  /* A race's markers against the reference per "function/dim" and their +/=/- counts. */
  function raceMarkers(r, ref) {
    const markers = {}, counts = {};
    for (const b of r.blocks) {
      const key = b.block.function + "/" + b.block.dim;
      for (const d of b.duels) {
        let name = null, m = d.marker;
        if (d.b === ref) name = d.a;
        else if (d.a === ref) { name = d.b; m = { "+": "-", "-": "+", "=": "=" }[m]; }
        if (name === null) continue;
        (markers[key] = markers[key] || {})[name] = m;
        const c = (counts[name] = counts[name] || { "+": 0, "=": 0, "-": 0 });
        c[m] += 1;
      }
    }
    return { markers: markers, counts: counts };
  }

  /* The race (docs/statistics.md, Racing): a summary line, per function and dimension each
     cell's runs, state and stopping round, and each pair's verdict, round and interval. */
  function raceTables(r, algs) {
    const s = r.settings;
    const cells = r.blocks.flatMap((b) => b.cells);
    const used = cells.reduce((n, c) => n + c.runs, 0), full = s.max_runs * cells.length;
    const stopped = cells.filter((c) => !c.racing).length, decided = cells.filter((c) => c.reason === "decided").length;
    /* the planned looks, recycling and futility (documents of older jobs lack some of them) */
    const looks = s.looks === "every-round" ? `, looks every round (${SP.esc(String(s.spending))})` : (Array.isArray(s.looks) && s.looks.length ? `, looks at ${s.looks.join(",")} (${SP.esc(String(s.spending))})` : "");
    const design = looks + (s.recycle ? ", shares recycled in blocks" : "") + (s.futility ? `, futility below ${s.futility}` : "");
    let html = `<h2>Race</h2><p id="race-line">alpha ${s.alpha} over ${r.comparisons} comparisons (Bonferroni), min_runs ${s.min_runs}, batch ${s.batch}, margin ${s.margin}, closing look ${SP.esc(String(s.final_test))}${design}, at most ${s.max_runs} runs a cell: ${stopped}/${cells.length} cells stopped (${decided} decided), <b>${used} runs of ${full}</b> (${(full / Math.max(used, 1)).toFixed(1)}x fewer)</p>`;
    html += `<table id="race-cells"><thead><tr><th class="l">function</th><th>dim</th>` + algs.map((a) => `<th>${SP.esc(a)}</th>`).join("") + `<th>rounds</th></tr></thead><tbody>`;
    for (const b of r.blocks) {
      const by = {}; for (const c of b.cells) by[c.algorithm] = c;
      html += `<tr data-block="${SP.esc(b.block.function)}/${b.block.dim}"><td class="l">${SP.esc(b.block.function)}</td><td>${b.block.dim}</td>` + algs.map((a) => {
        const c = by[a];
        if (!c) return "<td>-</td>";
        const state = c.racing ? "racing" : `${c.reason} r${c.stopped_round}`;
        return `<td data-algorithm="${SP.esc(a)}" title="${c.finished_runs} runs finished">${c.runs} &middot; ${SP.esc(state)}</td>`;
      }).join("") + `<td>${b.rounds}${b.finished ? "" : "+"}</td></tr>`;
    }
    html += `</tbody></table><table id="race-pairs"><thead><tr><th class="l">function</th><th>dim</th><th class="l">pair</th><th class="l">verdict</th><th>round</th><th>pairs</th><th>P(a's run beats b's) [interval]</th></tr></thead><tbody>`;
    for (const b of r.blocks) for (const d of b.duels) {
      const verdict = (d.decision === "different" ? `${d.better} better` : d.decision) + (d.final ? " (closing look)" : "") + (d.look ? ` (look at ${d.look} runs)` : "") + (d.power !== null && d.power !== undefined ? `, predictive power ${d.power.toFixed(3)}` : "");
      const theta = d.theta === null ? "" : `${d.theta.toFixed(3)} [${SP.num(d.low, 3)}, ${SP.num(d.high, 3)}]`;
      html += `<tr data-pair="${SP.esc(b.block.function)}/${b.block.dim}/${SP.esc(d.a)}/${SP.esc(d.b)}"><td class="l">${SP.esc(b.block.function)}</td><td>${b.block.dim}</td>
        <td class="l">${SP.esc(d.a)} vs ${SP.esc(d.b)}</td><td class="l verdict-${d.decision}">${SP.esc(verdict)} <span class="marker">${d.marker}</span></td>
        <td>${d.round === null ? (b.finished ? "-" : "open") : "r" + d.round}</td><td>${d.pairs}</td><td>${theta}</td></tr>`;
    }
    html += `</tbody></table><p class="legend">Cells: the runs the race gave each (at most ${s.max_runs}), and whether it still races or why it stopped (decided: every comparison it is part of is decided; max_runs: it reached the job's runs undecided) in round rK (min_runs + K x batch runs). Pairs: each comparison's verdict (different: the better one named; equivalent: within the margin of 1/2; futile: stopped at a look because the chance that the closing look calls it, its predictive power, was below the job's futility threshold, not a verdict; open: not decided), the round that decided it, the paired runs it used, and the share of paired runs (run r against run r) a won, ties half, with its anytime-valid confidence-sequence interval at alpha over the job's comparisons (docs/statistics.md, Racing). A comparison still open at ${s.max_runs} runs is decided there by the closing look, if the job has one (rank-sum: the two-sample rank test of the ${s.max_runs} runs, Holm over the comparisons not declared different, at the share of alpha the sequence leaves; sign: the sign test of the paired runs). The markers in the table above are these decisions, not tests repeated after each round (their p-values are not valid after stopping early).</p>`;
    return html;
  }

  function renderBenchmark(data) {
    const algs = data.algorithms;
    const content = SP.q("#content");
    content.innerHTML = pivot(data) + times(data) + (race ? raceTables(race, algs) : "") + `<h2>Convergence and best fitness per function and dimension</h2><div id="charts"></div>`;
    const charts = SP.q("#charts");
    for (const g of data.groups) {
      const row = document.createElement("div");
      row.className = "grid";
      row.dataset.group = g.function + "/" + g.dim;
      row.innerHTML = `<div class="card chart conv"></div><div class="card chart box"></div><div class="card chart ecdf"></div>`;
      charts.appendChild(row);
      const series = algs.filter((a) => g.algorithms[a] && g.algorithms[a].runs).map((a) => {
        const b = g.algorithms[a].band;
        return { name: a, color: color(a, algs), x: g.iterations, y: b.median, lo: b.q1, hi: b.q3 };
      });
      SP.lineChart(row.children[0], { title: `${g.function}, dim ${g.dim}: median and IQR`,
        xlabel: "iteration", ylabel: "best-so-far f(x) - f*", logy: true, logx: false, series: series });
      const boxes = algs.map((a) => ({ name: a, color: color(a, algs), stats: g.algorithms[a] && g.algorithms[a].box }));
      const positive = boxes.every((b) => !b.stats || b.stats.min > 0);
      SP.boxChart(row.children[1], { title: `${g.function}, dim ${g.dim}: best fitness`, ylabel: "best fitness", logy: positive, boxes: boxes });
      const ecdf = g.ecdf || { algorithms: {}, points: [] };
      SP.lineChart(row.children[2], { title: `${g.function}, dim ${g.dim}: runtime ECDF`, xlabel: "iteration",
        ylabel: "share of (run, target) pairs", logx: true, logy: false,
        series: algs.filter((a) => ecdf.algorithms[a]).map((a) => ({ name: `${a} (AUC ${ecdf.algorithms[a].auc.toFixed(2)})`,
          color: color(a, algs), x: ecdf.points, y: ecdf.algorithms[a].ecdf })) });
    }
  }

  /* MovingAI buckets (swarmpath.evidence.buckets, as swarmpath plan --scen prints them): a
     table and the difficulty curve, success and median gap against the bucket per planner. */
  function difficultyTable(buckets, planners) {
    const pct = (v, d) => (v === null || v === undefined || typeof v !== "number" ? "" : SP.num(100 * v, d));
    let html = `<h2>Difficulty: per MovingAI bucket</h2><div class="grid" id="difficulty">
      <div class="card chart difficulty-success"></div><div class="card chart difficulty-gap"></div></div>
      <table id="buckets"><thead><tr><th>bucket</th><th class="l">planner</th><th>pairs</th><th>success</th>
      <th>success %</th><th>gap % (median)</th><th>gap % (mean)</th></tr></thead><tbody>`;
    const rows = buckets.slice().sort((a, b) => a.bucket - b.bucket || planners.indexOf(a.planner) - planners.indexOf(b.planner));
    for (const b of rows) {
      html += `<tr data-bucket="${b.bucket}" data-planner="${SP.esc(b.planner)}"><td>${b.bucket}</td><td class="l">${SP.esc(b.planner)}</td><td>${b.pairs}</td>
        <td>${b.successes}/${b.runs}</td><td>${pct(b.success_rate, 1)}</td><td>${pct(b.gap_median, 2)}</td><td>${pct(b.gap_mean, 2)}</td></tr>`;
    }
    return html + `</tbody></table><p class="legend">A MovingAI .scen groups its start/goal pairs into buckets by the octile length of their optimal path (bucket b: lengths in [4b, 4b + 4) cells; Sturtevant 2012), so higher buckets are longer and usually harder. Success over every run of the bucket's pairs; gap over the successful runs with an exact optimum, pooled over the pairs.</p>`;
  }
  function difficultyCharts(buckets, planners) {
    const series = (key) => planners.filter((p) => buckets.some((b) => b.planner === p)).map((p) => {
      const mine = buckets.filter((b) => b.planner === p).sort((a, b) => a.bucket - b.bucket);
      return { name: p, color: color(p, planners), x: mine.map((b) => b.bucket),
        y: mine.map((b) => (typeof b[key] === "number" ? 100 * b[key] : null)) };
    });
    SP.lineChart(SP.q("#difficulty .difficulty-success"), { title: "success per bucket", xlabel: "MovingAI bucket",
      ylabel: "success %", series: series("success_rate") });
    SP.lineChart(SP.q("#difficulty .difficulty-gap"), { title: "median gap per bucket (successful runs)", xlabel: "MovingAI bucket",
      ylabel: "gap %", series: series("gap_median") });
  }

  async function renderMap(data) {
    const planners = data.planners;
    const st = data.statistics || { markers: {} };
    const content = SP.q("#content");
    let html = `<h2>Success rate</h2><table id="success"><thead><tr><th class="l">map</th>` +
      planners.map((p) => `<th>${SP.esc(p)}</th>`).join("") + `</tr></thead><tbody>`;
    for (const g of data.groups) {
      html += `<tr><td class="l">${SP.esc(g.map)}</td>` + planners.map((p) => {
        const c = g.planners[p]; const m = (st.markers[g.map] || {})[p];
        if (!c || !c.runs) return "<td>-</td>";
        const f = Object.entries(c.failures).map(([k, n]) => `${n} ${k}`).join(", ");
        return `<td title="${f}">${(100 * c.success_rate).toFixed(0)}% (${c.succeeded}/${c.runs})${m ? `<span class="marker">${m}</span>` : ""}</td>`;
      }).join("") + "</tr>";
    }
    html += `</tbody></table>`;
    if (st.reference) html += `<p class="legend">Markers: Fisher's exact test of each planner's success rate against ${SP.esc(st.reference)} (Holm-adjusted, alpha ${st.alpha}): + significantly higher, = no significant difference, - significantly lower.</p>`;
    html += `<h2>Per planner and map</h2><table id="cells"><thead><tr><th class="l">map</th><th class="l">planner</th>
      <th>runs</th><th>failed</th><th>success_rate</th><th>collisions</th><th>length (median)</th><th>gap % (median)</th>
      <th>planning s (median)</th><th>CPU s (median)</th><th class="l">why runs did not reach the goal</th></tr></thead><tbody>`;
    for (const g of data.groups) for (const p of planners) {
      const c = g.planners[p]; if (!c) continue;
      const med = (b) => (b ? SP.num(b.median, 3) : "");
      const mark = (what) => { const m = ((st[what + "_markers"] || {})[g.map] || {})[p]; return (m ? `<span class="marker">${m}</span>` : "") + effect((st[what + "_effects"] || {})[g.map], p); };
      html += `<tr><td class="l">${SP.esc(g.map)}</td><td class="l">${SP.esc(p)}</td><td>${c.runs}</td><td>${c.crashed}</td>
        <td>${c.success_rate === null ? "" : SP.num(c.success_rate, 3)}</td><td>${c.collisions}</td><td>${med(c.box.length)}${mark("length")}</td>
        <td${c.box.gap || !c.optimum_reason ? "" : ` class="l note" title="no exact optimum: ${SP.esc(c.optimum_reason)}"`}>${c.box.gap ? SP.num(100 * c.box.gap.median, 2) + mark("gap") : (c.optimum_reason ? `no optimum: ${SP.esc(c.optimum_reason)}` : "")}</td><td>${med(c.box.seconds)}${mark("seconds")}</td><td>${med(c.box.cpu_seconds)}</td>
        <td class="l">${Object.entries(c.failures).map(([k, n]) => `${n} ${k}`).join(", ")}</td></tr>`;
    }
    html += `</tbody></table>`;
    /* the field's path metrics (docs/metrics.md), medians over the successful runs */
    const quality = [["min_clearance", "clearance min (m)", 3, 1, "min"], ["clearance_mean", "clearance mean (m)", 3, 1], ["curvature_max", "curvature max (1/m)", 2, 1],
      ["curvature_mean", "curvature mean (1/m)", 3, 1], ["cusps", "cusps", 1, 1], ["danger_share", "in danger (%)", 1, 100],
      ["travel_time", "travel time (s)", 1, 1], ["velocity_smoothness", "velocity smoothness (m/s²)", 3, 1],
      ["angular_smoothness", "angular smoothness (rad/s²)", 2, 1], ["jerk", "jerk (m/s³)", 2, 1],
      ["costmap_cost_mean", "cost mean (nav2)", 1, 1], ["costmap_cost_max", "cost max (nav2)", 1, 1]];
    html += `<h2>Path quality</h2><table id="quality"><thead><tr><th class="l">map</th><th class="l">planner</th>` +
      quality.map(([, label]) => `<th>${label}</th>`).join("") + `</tr></thead><tbody>`;
    for (const g of data.groups) for (const p of planners) {
      const c = g.planners[p]; if (!c) continue;
      html += `<tr><td class="l">${SP.esc(g.map)}</td><td class="l">${SP.esc(p)}</td>` + quality.map(([key, , digits, scale, stat]) => {
        const b = c.box[key]; return `<td>${b ? SP.num(scale * b[stat || "median"], digits) : ""}</td>`;
      }).join("") + "</tr>";
    }
    html += `</tbody></table><p class="legend">Clearance min: the least over all runs (failed ones too; as the summary and swarmpath plan). The rest: medians over the runs that reached the goal. Clearance: body gap (clearance minus robot radius) sampled every 5 cm; curvature: circles through points 0.3 m apart (Bench-MR); cusps: turns over 60°; in danger: share of the travel time within 0.1 m of an obstacle (MRPB); smoothness: mean |change| per second of the speed (MRPB) and of the turn rate; jerk: mean |da/dt|; cost: nav2's inflated costmap along the path (nav2 maps only).</p>`;
    const warned = data.groups.map((g) => [g.map, Object.values(g.planners).find((c) => c && c.warnings && c.warnings.length)]).filter(([, c]) => c);
    if (warned.length) html += `<ul id="map-warnings" class="legend">` + warned.map(([map, c]) => c.warnings.map(([f, m]) => `<li>warning: ${SP.esc(map)}: ${SP.esc(f)}: ${SP.esc(m)}</li>`).join("")).join("") + `</ul>`;
    if (st.reference) {
      const measures = ["success", "length", "gap", "seconds"].filter((w) => st[w === "success" ? "counts" : w + "_counts"]);
      const ranked = Object.keys(st.friedman || {});
      const label = { success: "success", length: "length", gap: "gap", seconds: "planning s" };
      html += `<h2>Planners against ${SP.esc(st.reference)}</h2><table id="map-ranks"><thead><tr><th class="l">planner</th>`
        + measures.map((w) => `<th>${label[w]} +/=/-</th>`).join("")
        + ranked.map((w) => `<th>${label[w]} mean rank</th>`).join("") + `</tr></thead><tbody>`;
      for (const p of planners) {
        html += `<tr data-planner="${SP.esc(p)}"><td class="l">${SP.esc(p)}</td>` + measures.map((w) => {
          const c = st[w === "success" ? "counts" : w + "_counts"][p];
          return `<td>${c ? `${c["+"]}/${c["="]}/${c["-"]}` : "ref."}</td>`;
        }).join("") + ranked.map((w) => `<td>${SP.num(st.friedman[w].mean_ranks[p], 2)}</td>`).join("") + "</tr>";
      }
      html += `</tbody></table><p class="legend">+/=/-: maps where the planner is significantly better / not significantly different / worse than ${SP.esc(st.reference)}. Mean rank: Friedman ranks of the planners' mean length (successful runs) and mean planning time over the maps (1 = best; a map where a planner has no value is left out).</p>`;
    }
    const buckets = data.buckets || [];
    if (buckets.length) html += difficultyTable(buckets, planners);
    html += `<div id="maps"></div>`;
    content.innerHTML = html;
    if (buckets.length) difficultyCharts(buckets, planners);
    const maps = SP.q("#maps");
    for (const g of data.groups) {
      const sec = document.createElement("section");
      sec.dataset.map = g.map;
      sec.innerHTML = `<h2>${SP.esc(g.map)}</h2><div class="grid"><div class="card mapchart"></div>
        <div><div class="card chart box-length"></div><div class="card chart box-gap"></div><div class="card chart box-seconds"></div></div></div>`;
      maps.appendChild(sec);
      const paths = [];
      let tEnd = 0;
      for (const p of planners) {
        const c = g.planners[p]; if (!c) continue;
        for (const r of c.paths) {
          paths.push({ name: p, color: color(p, planners), points: r.path, run: r.run, success: r.success, failure: r.failure, reason: r.reason, collisions: r.collisions,
            href: `/ui/jobs/${encodeURIComponent(id)}/runs/${c.cell * data.runs_per_cell + r.run}` });
          if (r.path.length) tEnd = Math.max(tEnd, r.path[r.path.length - 1][2]);
        }
      }
      const r = await SP.api(`/ui/jobs/${encodeURIComponent(id)}/scene?cell=${g.cell}&t_end=${tEnd}`);
      if (r.ok) {
        SP.mapChart(sec.querySelector(".mapchart"), r.data, paths);
        const leg = document.createElement("p"); leg.className = "legend";
        leg.innerHTML = planners.map((p) => `<span data-planner="${SP.esc(p)}">&#9632; ${SP.esc(p)}</span>`).join(" ")
          + " &nbsp; dashed: failed run; &#10005; where a run touched an obstacle; &#9633; end of a stalled (purple) or timed-out (orange) run"
          + (r.data.dynamic ? "; orange lines: moving obstacles' tracks (run 0's world)" : "")
          + "; under the map: its frame and corners (hover start and goal for their positions in it)";
        for (const span of leg.querySelectorAll("span[data-planner]")) span.style.color = color(span.dataset.planner, planners);  /* CSSOM: no inline style under the CSP */
        sec.querySelector(".mapchart").appendChild(leg);
      }
      for (const [what, label] of [["length", "path length (m), successful runs"], ["gap", "gap to the optimum (%), successful runs"], ["seconds", "planning time (s)"]]) {
        SP.boxChart(sec.querySelector(".box-" + what), { title: label, empty: what === "gap" ? "no gap: no optimum with moving obstacles, or no successful run" : "no successful run", ylabel: what === "seconds" ? "s" : what === "gap" ? "gap %" : "m", width: 420, height: 200,
          boxes: planners.map((p) => ({ name: p, color: color(p, planners), stats: g.planners[p] && (what === "gap" ? SP.scaled(g.planners[p].box.gap, 100) : g.planners[p].box[what]) })) });
      }
    }
  }

  /* While the job runs: its status every 2 s, its charts every DATA_EVERY-th time (the data is
     tens to hundreds of KiB; many open pages must not slow the workers down), and once more
     when it ends. */
  const DATA_EVERY = 3;
  let tick = 0;
  async function refresh() {
    const s = await SP.api("/jobs/" + encodeURIComponent(id));
    if (!s.ok) { SP.q("#status").textContent = `job ${id}: ${s.status} ${JSON.stringify(s.data && s.data.detail)}`; return; }
    const live = (st) => st === "queued" || st === "running" || st === "waiting";
    const ended = status && live(status.state) && !live(s.data.state);
    renderStatus(s.data);
    if (!SP.q("#downloads").innerHTML) downloads(s.data.kind);
    const due = tick++ % DATA_EVERY === 0 || ended || etag === null || loading;
    const headers = etag ? { "If-None-Match": etag } : {};
    const r = due ? await SP.api(`/ui/jobs/${encodeURIComponent(id)}/data`, { headers: headers }) : { status: 304 };
    if (r.status === 200) {
      etag = r.headers.get("etag");
      if (r.data.racing) {
        const rr = await SP.api(`/jobs/${encodeURIComponent(id)}/race`);
        race = rr.ok ? rr.data : null;
      }
      if (r.data.kind === "benchmark") renderBenchmark(r.data); else await renderMap(r.data);
      SP.q("#legend").innerHTML = (r.data.legend || []).map(([c, t]) => `<dt>${SP.esc(c)}</dt><dd>${SP.esc(t)}</dd>`).join("");
      SP.q("#notes").textContent = r.data.kind === "benchmark"
        ? "Curves: median best-so-far error f(x) - f* over the successful runs, band from the 25th to the 75th percentile, log scale; box plots: quartiles, whiskers at 1.5 IQR, outliers as circles; runtime ECDF: share of (run, target) pairs whose error reached the target by that iteration, over IOHanalyzer's default targets (10 log-spaced between the smallest and largest error of the function and dimension), AUC its area over the iterations divided by the last. Crashed runs (an exception in the optimizer) have no value."
        : "Paths: up to 200 runs per planner and map. Success: the run reached the goal without touching an obstacle. Crashed runs (an exception) are counted in 'runs' but have no path. Gap: length / optimum - 1 (the exact shortest path), only on static maps: with moving obstacles there is no optimum. Collisions count colliding steps.";
      document.body.dataset.version = r.data.version;
      loading = !!r.data.loading;
      if (loading) SP.q("#notes").textContent = "Still reading this job's stored runs (after a coordinator restart): the charts fill in as they are read.";
    }
    if (loading || (status && ["queued", "running", "waiting"].includes(status.state))) setTimeout(refresh, 2000);
    else document.body.dataset.loaded = "1";
  }
  refresh();
})();
