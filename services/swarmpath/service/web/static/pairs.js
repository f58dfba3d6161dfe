/* Submit page: the pairs picker of an uploaded MovingAI map with its .scen. Turns what the user
   picks (every pair, rows as spans "0-9, 20", or N pairs of each listed bucket) into the job
   spec's {"map": id, "scen": {"rows": [...]} or {"buckets": [...], "per_bucket": n}}, the
   form POST /jobs takes (docs/service.md, MovingAI pairs), and counts the pairs it names from
   the map's pairs per bucket (GET /maps). The API checks the choice again; its errors land in
   the picker's error box. */
(function () {
  "use strict";
  const SP = (window.SP = window.SP || {});
  const pairs = (SP.pairs = {});

  /* "0-15, 20" for sorted integers */
  pairs.spans = function (values) {
    const out = [];
    for (let i = 0; i < values.length; i++) {
      let j = i;
      while (j + 1 < values.length && values[j + 1] === values[j] + 1) j++;
      out.push(i === j ? String(values[i]) : `${values[i]}-${values[j]}`);
      i = j;
    }
    return out.join(", ");
  };

  /* The integers of "0-9, 20 30-31" in the order given, at most `limit` + 1 of them (a list
     past the limit is refused whatever its length); {error} names the first bad part. */
  pairs.parseSpans = function (text, what, limit) {
    const parts = String(text).split(/[\s,]+/).filter((s) => s !== "");
    if (!parts.length) return { error: `${what}: give at least one (e.g. 0-9, 20)` };
    const values = [];
    for (const part of parts) {
      const m = /^(\d{1,9})(?:-(\d{1,9}))?$/.exec(part);
      if (!m) return { error: `${what}: '${part}' is not a number or a range a-b` };
      const a = Number(m[1]), b = m[2] === undefined ? a : Number(m[2]);
      if (b < a) return { error: `${what}: ${part} ends before it starts` };
      for (let v = a; v <= b && values.length <= limit; v++) values.push(v);
      if (values.length > limit) return { error: `${what}: more than ${limit} (a map entry takes at most ${limit} pairs)` };
    }
    return { values: values };
  };

  /* The picker's fields for map `m` (GET /maps' entry, m.scen = {pairs, buckets: {b: n}}). */
  pairs.fields = function (m, limit) {
    const buckets = Object.keys(m.scen.buckets).map(Number).sort((a, b) => a - b);
    const last = Math.min(m.scen.pairs, 10) - 1;
    return `<fieldset class="pairs" data-map="${SP.esc(m.id)}" hidden><legend>${SP.esc(m.name)}: .scen pairs (${m.scen.pairs} in buckets ${pairs.spans(buckets)})</legend>
      <label>run on <select data-pairs="mode">
        <option value="buckets" selected>pairs per bucket</option><option value="rows">rows</option>
        <option value="all">every pair</option><option value="none">the map's own start and goal</option></select></label>
      <label class="pairs-buckets">buckets <input type="text" data-pairs="buckets" value="${pairs.spans(buckets)}"></label>
      <label class="pairs-buckets">pairs per bucket <input type="text" data-pairs="per_bucket" value="1"></label>
      <label class="pairs-rows" hidden>rows (0 = the first pair) <input type="text" data-pairs="rows" value="0-${last}"></label>
      <span class="muted" data-pairs="count"></span>
      <div class="err" data-error="pairs.${SP.esc(m.id)}"></div></fieldset>`;
  };

  /* What the picker `fs` names for map `m`: {scen, count} (scen null: the map's own start and
     goal), or {error}. */
  pairs.choice = function (fs, m, limit) {
    const get = (k) => fs.querySelector(`[data-pairs="${k}"]`).value;
    const mode = get("mode");
    if (mode === "none") return { scen: null, count: 1 };
    if (mode === "all") {
      if (m.scen.pairs > limit) return { error: `every pair: the .scen has ${m.scen.pairs}, a map entry takes at most ${limit} (choose rows or buckets)` };
      return { scen: { rows: [...Array(m.scen.pairs).keys()] }, count: m.scen.pairs };
    }
    if (mode === "rows") {
      const r = pairs.parseSpans(get("rows"), "rows", limit);
      if (r.error) return r;
      const beyond = r.values.find((v) => v >= m.scen.pairs);
      if (beyond !== undefined) return { error: `rows: ${beyond} is beyond the ${m.scen.pairs} pairs of the .scen (0 = first)` };
      return { scen: { rows: r.values }, count: r.values.length };
    }
    const b = pairs.parseSpans(get("buckets"), "buckets", limit);
    if (b.error) return b;
    const n = /^\d{1,9}$/.test(get("per_bucket").trim()) ? Number(get("per_bucket").trim()) : NaN;
    if (!(n >= 1)) return { error: "pairs per bucket: a whole number >= 1" };
    const empty = b.values.filter((v) => !m.scen.buckets[v]);
    if (empty.length) return { error: `buckets: the .scen has no pair in bucket ${pairs.spans(empty)}` };
    if (b.values.length * n > limit) return { error: `${b.values.length} buckets x ${n} pairs is over the ${limit} pairs a map entry takes` };
    const count = b.values.reduce((s, v) => s + Math.min(n, m.scen.buckets[v]), 0);
    return { scen: { buckets: b.values, per_bucket: n }, count: count };
  };

  /* Show the fields of the picker's mode and how many pairs (or what is wrong) it names. */
  pairs.refresh = function (fs, m, limit) {
    const mode = fs.querySelector('[data-pairs="mode"]').value;
    for (const el of fs.querySelectorAll(".pairs-buckets")) el.hidden = mode !== "buckets";
    for (const el of fs.querySelectorAll(".pairs-rows")) el.hidden = mode !== "rows";
    const c = pairs.choice(fs, m, limit);
    const box = fs.querySelector(".err");
    box.textContent = c.error || "";
    fs.querySelector('[data-pairs="count"]').textContent = c.error || !c.scen ? "" : `${c.count} pair${c.count === 1 ? "" : "s"}: one map each`;
  };
})();
