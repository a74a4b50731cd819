/* rcsa web view: plain JavaScript, no dependencies, talks to this service's /v1 API.
 *
 * Flow: load RA-1 (GET v1/examples/ra1) and the stored spindles (GET v1/measurements);
 * optionally upload a Fusion library (POST v1/tool-libraries:entries) and pick an entry;
 * Predict (POST v1/tool-point-frf?tool_point=h) draws the FRF in an inline SVG; Lobes
 * (POST v1/stability-lobes with the predicted h inline) draws the lobe diagram. Downloads
 * use v1/exports/*.csv and v1/plots/* (server-rendered PNG/SVG). API errors (problem+json)
 * are shown in the page.
 */
"use strict";

(function () {
  const NS = "http://www.w3.org/2000/svg";
  const API = new URL("../", document.baseURI); // the page lives at <root>/ui/
  const UM_PER_M = 1e6;
  const MM_PER_M = 1e3;

  const state = {
    ra1: null,         // RA-1 assembly document
    entries: [],       // library entries (POST v1/tool-libraries:entries)
    libraryName: "",
    assembly: null,    // the assembly of the shown prediction
    prediction: null,  // the shown prediction result
    label: "",         // what was predicted, for titles and file names
    lobesRequest: null,
    lobes: null,
  };

  const $ = (id) => document.getElementById(id);

  // ------------------------------------------------------------------ API access

  class ApiError extends Error {
    constructor(message, status, problem) {
      super(message);
      this.status = status;
      this.problem = problem;
    }
  }

  function headers(extra) {
    const h = Object.assign({}, extra || {});
    const key = $("api-key").value.trim();
    if (key) h["X-API-Key"] = key;
    return h;
  }

  async function call(path, options) {
    const opts = options || {};
    const init = { method: opts.method || "GET", headers: headers(opts.headers) };
    if (opts.json !== undefined) {
      init.headers["Content-Type"] = "application/json";
      init.body = JSON.stringify(opts.json);
    } else if (opts.form !== undefined) {
      init.body = opts.form;
    }
    let response;
    try {
      response = await fetch(new URL(path, API), init);
    } catch (err) {
      throw new ApiError("the service cannot be reached (" + err.message + ")", 0, null);
    }
    if (!response.ok) {
      let problem = null;
      try {
        problem = await response.json();
      } catch (ignored) {
        problem = null;
      }
      const detail = problem && problem.detail ? problem.detail : response.status + " " + response.statusText;
      throw new ApiError(detail, response.status, problem);
    }
    return response;
  }

  // ------------------------------------------------------------------ messages

  function showError(context, err) {
    const box = $("error");
    $("error-message").textContent = context + ": " + (err && err.message ? err.message : String(err));
    const list = $("error-fields");
    list.replaceChildren();
    const problem = err && err.problem;
    if (problem && Array.isArray(problem.errors)) {
      for (const e of problem.errors) {
        const li = document.createElement("li");
        li.textContent = (e.field ? e.field + ": " : "") + e.detail;
        list.appendChild(li);
      }
    }
    $("error-request").textContent = problem && problem.request_id
      ? "HTTP " + problem.status + " · request id " + problem.request_id : "";
    box.hidden = false;
  }

  function clearError() {
    $("error").hidden = true;
  }

  function setStatus(id, text) {
    $(id).textContent = text;
  }

  // ------------------------------------------------------------------ number input

  function numberFrom(id, label, opts) {
    const o = opts || {};
    const raw = $(id).value.trim();
    if (raw === "") {
      if (o.optional) return null;
      throw new ApiError(label + " is empty: enter a number", 0, null);
    }
    const x = Number(raw);
    if (!Number.isFinite(x)) throw new ApiError(label + " must be a number, got " + raw, 0, null);
    if (o.integer && !Number.isInteger(x)) throw new ApiError(label + " must be a whole number, got " + raw, 0, null);
    return x;
  }

  function fmt(x, digits) {
    if (x === null || x === undefined || !Number.isFinite(x)) return "—";
    return Number(x.toPrecision(digits || 4)).toString();
  }

  // ------------------------------------------------------------------ choices

  async function loadRa1() {
    const r = await call("v1/examples/ra1");
    state.ra1 = await r.json();
  }

  async function loadSpindles() {
    const r = await call("v1/measurements?limit=1000");
    const page = await r.json();
    const select = $("spindle");
    for (const m of page.items) {
      const opt = document.createElement("option");
      opt.value = m.id;
      opt.dataset.plane = m.plane;
      opt.textContent = m.spindle_id + " · " + m.direction + " · " + m.plane.replace("_", " ") + " · " +
        m.kind.replace("_", " ") + " (" + m.id + ", " + fmt(m.frequency_min_hz) + "–" + fmt(m.frequency_max_hz) + " Hz)";
      select.appendChild(opt);
    }
    $("spindle-hint").textContent = page.items.length
      ? page.items.length + " stored measured spindle(s); choosing one makes a hybrid prediction."
      : "No measured spindles stored yet (upload them with the API or the CLI).";
  }

  function entryById(id) {
    return state.entries.find((e) => e.id === id) || null;
  }

  async function uploadLibrary() {
    const input = $("library-file");
    if (!input.files || !input.files.length) return;
    const file = input.files[0];
    clearError();
    setStatus("library-status", "Reading " + file.name + " …");
    const form = new FormData();
    form.append("library", file, file.name);
    try {
      const doc = await (await call("v1/tool-libraries:entries", { method: "POST", form: form })).json();
      state.entries = doc.entries;
      state.libraryName = file.name;
      fillEntries();
      const s = doc.library.summary;
      setStatus("library-status", file.name + ": " + s.ok + " usable, " + s.skipped + " skipped, " +
        s.error + " with errors.");
    } catch (err) {
      setStatus("library-status", "Could not read " + file.name + ".");
      showError("Reading the tool library failed", err);
    }
  }

  function fillEntries() {
    const select = $("entry");
    for (const old of select.querySelectorAll("optgroup")) old.remove();
    const group = document.createElement("optgroup");
    group.label = "Library " + state.libraryName;
    let first = null;
    for (const e of state.entries) {
      const opt = document.createElement("option");
      opt.value = e.id;
      const number = e.number !== null && e.number !== undefined ? "T" + e.number + " · " : "";
      let text = number + (e.description || e.id);
      if (e.status !== "ok") {
        opt.disabled = true;
        text += " — " + e.status + ": " + (e.reason || "");
      } else if (first === null) {
        first = e.id;
      }
      opt.textContent = text;
      group.appendChild(opt);
    }
    select.insertBefore(group, select.querySelector('option[value="custom"]'));
    if (first !== null) {
      select.value = first;
      entryChanged();
    }
  }

  function entryChanged() {
    const value = $("entry").value;
    const info = $("entry-info");
    if (value === "ra1") {
      info.textContent = "RA-1 reference tool: 4 teeth assumed for the lobes.";
      $("teeth").value = 4;
    } else if (value === "custom") {
      info.textContent = "The assembly JSON below is used (its frequency grid is replaced by the band).";
      $("json-details").open = true;
      if (!$("assembly-json").value.trim()) fillJson();
    } else {
      const e = entryById(value);
      if (!e) return;
      const t = e.tool;
      const parts = [e.tool_type || "tool", "Ø" + fmt(t.diameter_m * MM_PER_M) + " mm",
        fmt(t.stickout_m * MM_PER_M) + " mm stickout", (e.teeth || "?") + " teeth"];
      info.textContent = parts.join(", ") + (e.warnings.length ? ". Note: " + e.warnings.join("; ") : ".");
      if (e.teeth) $("teeth").value = e.teeth;
    }
  }

  function fillJson() {
    try {
      const a = selectionAssembly();
      $("assembly-json").value = JSON.stringify(a, null, 1);
    } catch (err) {
      showError("Building the assembly failed", err);
    }
  }

  function frequencyBand() {
    return {
      start_hz: numberFrom("freq-start", "Frequency from"),
      stop_hz: numberFrom("freq-stop", "Frequency to"),
      step_hz: numberFrom("freq-step", "Frequency step"),
    };
  }

  /** The assembly of the current choices (spindle, holder and tool, joints, band). */
  function selectionAssembly() {
    if (!state.ra1) throw new ApiError("the RA-1 defaults are not loaded yet", 0, null);
    const ra1 = JSON.parse(JSON.stringify(state.ra1));
    const a = { frequency: frequencyBand(), beam_theory: ra1.beam_theory, shear_coefficient: ra1.shear_coefficient };
    const spindle = $("spindle");
    const option = spindle.selectedOptions[0];
    a.spindle = spindle.value === "ra1" ? ra1.spindle : { measurement_id: spindle.value };
    const entryValue = $("entry").value;
    const entry = entryValue === "ra1" || entryValue === "custom" ? null : entryById(entryValue);
    const holder = entry ? entry.holder : ra1.holder;
    if (!(option && option.dataset.plane === "holder_tip")) a.holder = holder;
    a.tool = entry ? entry.tool : ra1.tool;
    if ($("joints-ra1").checked) a.joints = ra1.joints;
    const clamping = $("clamping").value;
    if (clamping !== "point") {
      a.joints = Object.assign({}, a.joints || {});
      a.joints.holder_tool = clamping === "bonded" ? { model: "bonded" } : {
        model: "contact",
        interface_stiffness_n_m3: numberFrom("interface-stiffness", "Interface stiffness"),
      };
    }
    return a;
  }

  function assemblyToSend() {
    if ($("entry").value !== "custom") return selectionAssembly();
    let doc;
    try {
      doc = JSON.parse($("assembly-json").value);
    } catch (err) {
      throw new ApiError("the assembly JSON is not valid JSON (" + err.message + ")", 0, null);
    }
    if (doc === null || typeof doc !== "object" || Array.isArray(doc)) {
      throw new ApiError("the assembly JSON must be an object {spindle, holder, tool, ...}", 0, null);
    }
    doc.frequency = frequencyBand();
    return doc;
  }

  function describeSelection() {
    const spindle = $("spindle");
    const sp = spindle.value === "ra1" ? "RA-1 spindle" : spindle.value;
    const entry = $("entry");
    let tool = "RA-1 tool";
    if (entry.value === "custom") tool = "custom assembly";
    else if (entry.value !== "ra1") {
      const e = entryById(entry.value);
      tool = e ? (e.number !== null && e.number !== undefined ? "T" + e.number + " " : "") + e.description : entry.value;
    }
    return tool + " on " + sp;
  }

  // ------------------------------------------------------------------ predict

  async function predict() {
    clearError();
    const button = $("predict");
    let assembly;
    try {
      assembly = assemblyToSend();
    } catch (err) {
      showError("Prediction not started", err);
      return;
    }
    button.disabled = true;
    document.body.dataset.frf = "busy";
    setStatus("predict-status", "Predicting …");
    const t0 = performance.now();
    try {
      const option = uncertaintyOption();
      const body = option ? Object.assign({}, assembly, { uncertainty: option }) : assembly;
      const result = await (await call("v1/tool-point-frf?tool_point=h", { method: "POST", json: body })).json();
      state.assembly = assembly;
      state.uncertainty = option;
      state.prediction = result;
      state.label = describeSelection();
      state.lobes = null;
      state.lobesRequest = null;
      drawFrf(result);
      summarizeFrf(result);
      for (const id of ["download-frf-csv", "download-frf-png", "download-frf-svg", "lobes"]) $(id).disabled = false;
      for (const id of ["download-lobes-csv", "download-lobes-png", "download-lobes-svg"]) $(id).disabled = true;
      clearPlot("lobes-plot", "Stability lobes: press Lobes");
      setStatus("lobes-status", "Ready: press Lobes.");
      setStatus("predict-status", state.label + ": " + result.frequency_hz.length + " lines in " +
        ((performance.now() - t0) / 1000).toFixed(2) + " s.");
      document.body.dataset.frf = "drawn";
    } catch (err) {
      setStatus("predict-status", "Prediction failed.");
      document.body.dataset.frf = "error";
      showError("Prediction failed", err);
    } finally {
      button.disabled = false;
    }
  }

  function summarizeFrf(r) {
    const nat = r.natural_frequencies_hz.map((f) => f.toFixed(2) + " Hz");
    $("nat-freqs").textContent = nat.length ? nat.join(", ") +
      (r.natural_frequencies_method === "modal_fit" ? " (modal-fit estimates)" : "") : "none in the band";
    const peaks = r.peaks.slice().sort((a, b) => b.magnitude_m_n - a.magnitude_m_n).slice(0, 5)
      .map((p) => fmt(p.frequency_hz, 5) + " Hz: " + fmt(p.magnitude_m_n * UM_PER_M, 3) + " µm/N");
    $("peaks").textContent = peaks.length ? peaks.join("; ") : "none";
    $("static-stiffness").textContent = r.static_stiffness_n_m === null || r.static_stiffness_n_m === undefined
      ? "not available (measured spindle)" : fmt(r.static_stiffness_n_m / UM_PER_M, 4) + " N/µm";
    $("min-real").textContent = fmt(r.min_real_m_n * UM_PER_M, 4) + " µm/N at " + fmt(r.min_real_frequency_hz, 5) + " Hz";
    const notes = $("notes");
    notes.replaceChildren();
    for (const n of r.notes || []) {
      const li = document.createElement("li");
      li.textContent = n;
      notes.appendChild(li);
    }
  }

  // ------------------------------------------------------------------ lobes

  /** The uncertainty option of the draws field (null for 0 draws): a fixed seed, so a result repeats. */
  function uncertaintyOption() {
    const draws = numberFrom("draws", "Uncertainty draws", { integer: true, optional: true });
    return draws ? { draws: draws, seed: 0 } : null;
  }

  function lobesRequest() {
    const r = state.prediction;
    // robust lobes need the assembly (its draws)
    const robust = Boolean(state.uncertainty);
    const source = robust ? { assembly: state.assembly, uncertainty: state.uncertainty }
      : { frf_x: { frequency_hz: r.frequency_hz, h: r.tool_point.h } };
    return {
      ...source,
      teeth: numberFrom("teeth", "Teeth", { integer: true }),
      tangential_coefficient_n_m2: numberFrom("kt", "Kt"),
      radial_ratio: numberFrom("kr", "Kr"),
      radial_immersion: numberFrom("immersion", "Radial immersion"),
      milling: $("milling").value,
      method: $("lobes-method").value,
      spindle_speed_rpm: {
        start: numberFrom("speed-start", "Speed from"),
        stop: numberFrom("speed-stop", "Speed to"),
        count: numberFrom("speed-count", "Speed points", { integer: true }),
      },
    };
  }

  function operatingPoint() {
    const n = numberFrom("op-speed", "Operating speed", { optional: true });
    const ap = numberFrom("op-depth", "Operating depth", { optional: true });
    if (n === null || ap === null) return null;
    return { spindle_speed_rpm: n, depth_m: ap / MM_PER_M };
  }

  async function lobes() {
    clearError();
    if (!state.prediction) return;
    let request, point;
    try {
      request = lobesRequest();
      point = operatingPoint();
    } catch (err) {
      showError("Lobes not started", err);
      return;
    }
    const button = $("lobes");
    button.disabled = true;
    document.body.dataset.lobes = "busy";
    setStatus("lobes-status", "Computing lobes …");
    const t0 = performance.now();
    try {
      const result = await (await call("v1/stability-lobes", { method: "POST", json: request })).json();
      state.lobes = result;
      state.lobesRequest = request;
      drawLobes(result, point);
      summarizeLobes(result, point);
      showLobesNotes(result);
      for (const id of ["download-lobes-csv", "download-lobes-png", "download-lobes-svg"]) $(id).disabled = false;
      setStatus("lobes-status", result.lobes.length + " lobes in " + ((performance.now() - t0) / 1000).toFixed(2) +
        " s" + (result.frf_y_source === "same_as_x" ? " (Φyy = Φxx assumed)." : "."));
      document.body.dataset.lobes = "drawn";
    } catch (err) {
      setStatus("lobes-status", "Lobes failed.");
      document.body.dataset.lobes = "error";
      showError("Stability lobes failed", err);
    } finally {
      button.disabled = false;
    }
  }

  /** Local maxima of the envelope (the chatter-free pockets), deepest first. */
  function pockets(speed, depth) {
    const out = [];
    for (let i = 1; i < depth.length - 1; i++) {
      const d = depth[i];
      if (d === null || depth[i - 1] === null || depth[i + 1] === null) continue;
      if (d > depth[i - 1] && d >= depth[i + 1]) out.push({ n: speed[i], d: d });
    }
    return out.sort((a, b) => b.d - a.d);
  }

  function envelopeAt(result, n) {
    const s = result.spindle_speed_rpm;
    const d = result.depth_limit_m;
    for (let i = 0; i < s.length - 1; i++) {
      if (n >= s[i] && n <= s[i + 1]) {
        if (d[i] === null || d[i + 1] === null) return null;
        const t = (n - s[i]) / (s[i + 1] - s[i]);
        return d[i] + t * (d[i + 1] - d[i]);
      }
    }
    return null;
  }

  /** The tool's flute length (m) when the lobes are of a known assembly: no stepdown exceeds it. */
  function fluteLength(result) {
    if (result.flute_length_m) return result.flute_length_m;
    const tool = state.assembly && state.assembly.tool;
    return tool && tool.flute_length_m ? tool.flute_length_m : null;
  }

  /** The limit the summary judges by: the robust one when there is one, else the nominal; a
   *  semi-discretization speed without a limit is stable to the search depth; all capped at the
   *  flute length. */
  function usableLimit(result) {
    const flute = fluteLength(result);
    const nominal = result.depth_limit_m;
    const robust = result.depth_limit_robust_m;
    const deep = result.depth_search_max_m || null;
    return nominal.map((v, i) => {
      let d = robust ? robust[i] : v;
      if (d === null && v === null && deep !== null) d = deep;  // no limit found below the search depth
      if (d === null) return null;
      return flute !== null ? Math.min(d, flute) : d;
    });
  }

  function summarizeLobes(result, point) {
    const flute = fluteLength(result);
    const capped = (d) => (flute !== null && d >= flute * (1 - 1e-9) ? " (the flute length: stable deeper)" : "");
    $("lobes-min-depth").textContent = result.min_depth_limit_m === null ? "—"
      : fmt(result.min_depth_limit_m * MM_PER_M, 3) + " mm (chatter at " +
        fmt(result.min_depth_chatter_frequency_hz, 5) + " Hz): stable at any speed below it";
    const limit = usableLimit(result);
    const best = pockets(result.spindle_speed_rpm, limit).slice(0, 3)
      .map((p) => fmt(p.d * MM_PER_M, 3) + " mm at " + Math.round(p.n) + " rpm" + capped(p.d));
    $("lobes-pockets").textContent = (best.length ? best.join("; ") : "none in this speed range") +
      (result.depth_limit_robust_m ? " — on the robust limit (p" + result.robust.percentile + " of draws)" : "");
    if (!point) {
      $("lobes-op").textContent = "not given";
      return;
    }
    const at = envelopeAt({ spindle_speed_rpm: result.spindle_speed_rpm, depth_limit_m: limit }, point.spindle_speed_rpm);
    const where = fmt(point.depth_m * MM_PER_M, 3) + " mm at " + Math.round(point.spindle_speed_rpm) + " rpm";
    const over = flute !== null && point.depth_m > flute ? "; deeper than the flute length " + fmt(flute * MM_PER_M, 3) + " mm" : "";
    $("lobes-op").textContent = at === null ? where + ": outside the computed lobes" + over
      : where + (point.depth_m < at ? ": stable" : ": chatter expected") + " (limit " + fmt(at * MM_PER_M, 3) + " mm" +
        (result.depth_limit_robust_m ? ", robust" : "") + ")" + over;
  }

  /** The lobes' notes (under-resolved speeds, a grid too coarse for them), and which method auto chose. */
  function showLobesNotes(result) {
    const list = $("lobes-notes");
    list.replaceChildren();
    const notes = (result.notes || []).slice();
    if (result.method_reason) notes.unshift("method " + result.method + " — " + result.method_reason);
    for (const n of notes) {
      const li = document.createElement("li");
      li.textContent = n;
      list.appendChild(li);
    }
  }

  // ------------------------------------------------------------------ downloads

  async function download(path, body, fileName, statusId) {
    clearError();
    setStatus(statusId, "Preparing " + fileName + " …");
    try {
      const blob = await (await call(path, { method: "POST", json: body })).blob();
      const url = URL.createObjectURL(blob);
      const a = document.createElement("a");
      a.href = url;
      a.download = fileName;
      document.body.appendChild(a);
      a.click();
      a.remove();
      setTimeout(() => URL.revokeObjectURL(url), 60000);
      setStatus(statusId, fileName + " downloaded (" + Math.round(blob.size / 1024) + " kB).");
    } catch (err) {
      setStatus(statusId, "Download failed.");
      showError("Download of " + fileName + " failed", err);
    }
  }

  function stem() {
    return state.label.replace(/[^A-Za-z0-9._-]+/g, "-").replace(/^-+|-+$/g, "").slice(0, 80) || "rcsa";
  }

  function frfFigure(format) {
    const r = state.prediction;
    download("v1/plots/frf?format=" + format, {
      frf: { frequency_hz: r.frequency_hz, h: r.tool_point.h }, layout: "full", title: state.label,
    }, stem() + "-frf." + format, "frf-download-status");
  }

  function lobesFigure(format) {
    let point = null;
    try {
      point = operatingPoint();
    } catch (err) {
      point = null;
    }
    const body = Object.assign({}, state.lobesRequest, { title: state.label });
    if (point) body.operating_point = point;
    download("v1/plots/lobes?format=" + format, body, stem() + "-lobes." + format, "lobes-download-status");
  }

  // ------------------------------------------------------------------ drawing (inline SVG)

  function svgEl(name, attrs, parent) {
    const node = document.createElementNS(NS, name);
    for (const [k, v] of Object.entries(attrs || {})) node.setAttribute(k, String(v));
    if (parent) parent.appendChild(node);
    return node;
  }

  function clearPlot(id, title) {
    const svg = $(id);
    svg.replaceChildren();
    svgEl("title", { id: id + "-title" }, svg).textContent = title;
  }

  function niceStep(span, target) {
    const raw = span / Math.max(target, 1);
    const mag = Math.pow(10, Math.floor(Math.log10(raw)));
    const norm = raw / mag;
    const nice = norm < 1.5 ? 1 : norm < 3 ? 2 : norm < 7 ? 5 : 10;
    return nice * mag;
  }

  function linearTicks(lo, hi, target) {
    if (!(hi > lo)) return [lo];
    const step = niceStep(hi - lo, target);
    const ticks = [];
    for (let t = Math.ceil(lo / step) * step; t <= hi + step * 1e-9; t += step) {
      ticks.push(Math.abs(t) < step * 1e-9 ? 0 : t);
    }
    return ticks;
  }

  function tickLabel(t) {
    const a = Math.abs(t);
    if (a !== 0 && (a >= 1e5 || a < 1e-3)) return t.toExponential(0).replace("e+", "e");
    return Number(t.toPrecision(6)).toString();
  }

  function extent(arrays, positiveOnly) {
    let lo = Infinity;
    let hi = -Infinity;
    for (const arr of arrays) {
      for (const v of arr) {
        if (v === null || !Number.isFinite(v) || (positiveOnly && v <= 0)) continue;
        if (v < lo) lo = v;
        if (v > hi) hi = v;
      }
    }
    return [lo, hi];
  }

  /**
   * One axes: frame, grid, ticks, labels, and a scaler for the data.
   * box: {x, y, w, h} in SVG units; x/y: {min, max, log, label, ticks}.
   */
  function axes(svg, box, x, y) {
    const g = svgEl("g", { class: "axes" }, svg);
    const ly = (v) => (y.log ? Math.log10(v) : v);
    const y0 = ly(y.min);
    const y1 = ly(y.max);
    const sx = (v) => box.x + ((v - x.min) / (x.max - x.min)) * box.w;
    const sy = (v) => box.y + box.h - ((ly(v) - y0) / (y1 - y0)) * box.h;
    const xt = x.ticks || linearTicks(x.min, x.max, 8);
    let yt = y.ticks;
    if (!yt) {
      if (y.log) {
        yt = [];
        for (let e = Math.ceil(y0); e <= Math.floor(y1); e++) yt.push(Math.pow(10, e));
      } else {
        yt = linearTicks(y.min, y.max, 5);
      }
    }
    for (const t of xt) {
      const px = sx(t);
      svgEl("line", { class: "gridline", x1: px, x2: px, y1: box.y, y2: box.y + box.h }, g);
      if (x.showLabels !== false) {
        svgEl("text", { class: "tick", x: px, y: box.y + box.h + 16, "text-anchor": "middle" }, g).textContent = tickLabel(t);
      }
    }
    for (const t of yt) {
      const py = sy(t);
      svgEl("line", { class: "gridline", x1: box.x, x2: box.x + box.w, y1: py, y2: py }, g);
      svgEl("text", { class: "tick", x: box.x - 6, y: py + 4, "text-anchor": "end" }, g).textContent = tickLabel(t);
    }
    svgEl("rect", { class: "frame", x: box.x, y: box.y, width: box.w, height: box.h }, g);
    if (x.label) {
      svgEl("text", { class: "axis-label", x: box.x + box.w / 2, y: box.y + box.h + 36, "text-anchor": "middle" }, g)
        .textContent = x.label;
    }
    if (y.label) {
      const cx = box.x - 62;
      const cy = box.y + box.h / 2;
      svgEl("text", { class: "axis-label", x: cx, y: cy, "text-anchor": "middle", transform: "rotate(-90 " + cx + " " + cy + ")" }, g)
        .textContent = y.label;
    }
    const clipId = svg.id + "-clip-" + svg.querySelectorAll("clipPath").length;
    const clip = svgEl("clipPath", { id: clipId }, svg);
    svgEl("rect", { x: box.x, y: box.y, width: box.w, height: box.h }, clip);
    const plot = svgEl("g", { "clip-path": "url(#" + clipId + ")" }, svg);
    return { sx, sy, plot, box };
  }

  /** SVG path through (x[i], y[i]); null or non-finite values (or non-positive on log axes) break it. */
  function pathData(ax, xs, ys, log) {
    const parts = [];
    let pen = false;
    let points = 0;
    for (let i = 0; i < xs.length; i++) {
      const v = ys[i];
      if (v === null || xs[i] === null || !Number.isFinite(v) || (log && v <= 0)) {
        pen = false;
        continue;
      }
      parts.push((pen ? "L" : "M") + ax.sx(xs[i]).toFixed(2) + " " + ax.sy(v).toFixed(2));
      pen = true;
      points += 1;
    }
    return { d: parts.join(""), points };
  }

  function line(ax, xs, ys, cls, id, log) {
    const p = pathData(ax, xs, ys, log);
    return svgEl("path", { class: cls, id: id, d: p.d, "data-points": p.points }, ax.plot);
  }

  function legend(svg, x, y, items) {
    const g = svgEl("g", { class: "legend" }, svg);
    const width = 44 + 7.5 * Math.max(...items.map((item) => item.label.length));
    svgEl("rect", { class: "legend-box", x: x - 8, y: y - 12, width: width, height: 18 * items.length + 6, rx: 3 }, g);
    items.forEach((item, i) => {
      const yy = y + i * 18;
      svgEl("line", { class: item.cls, x1: x, x2: x + 24, y1: yy, y2: yy }, g);
      svgEl("text", { class: "tick", x: x + 30, y: yy + 4 }, g).textContent = item.label;
    });
  }

  function drawFrf(r) {
    const svg = $("frf-plot");
    clearPlot("frf-plot", "Tool-point FRF of " + state.label + ": real and imaginary parts, magnitude and phase");
    const f = r.frequency_hz;
    const re = r.tool_point.h.real.map((v) => v * UM_PER_M);
    const im = r.tool_point.h.imag.map((v) => v * UM_PER_M);
    const mag = re.map((v, i) => Math.hypot(v, im[i]));
    const phase = re.map((v, i) => (Math.atan2(im[i], v) * 180) / Math.PI);
    const x = { min: f[0], max: f[f.length - 1] };
    if (!(x.max > x.min)) x.max = x.min + 1;
    const left = 90;
    const width = 960 - left - 24;

    let [lo, hi] = extent([re, im]);
    const pad = (hi - lo) * 0.05 || Math.abs(hi) * 0.1 || 1;
    const a1 = axes(svg, { x: left, y: 16, w: width, h: 250 }, Object.assign({ showLabels: false }, x),
      { min: lo - pad, max: hi + pad, label: "Re, Im h (µm/N)" });
    svgEl("line", { class: "zero", x1: left, x2: left + width, y1: a1.sy(0), y2: a1.sy(0) }, a1.plot);
    for (const fn of r.natural_frequencies_hz) {
      const px = a1.sx(fn);
      const mark = svgEl("line", { class: "natural", x1: px, x2: px, y1: 16, y2: 266 }, a1.plot);
      svgEl("title", {}, mark).textContent = fn.toFixed(2) + " Hz";
    }
    line(a1, f, re, "series-real", "frf-real-path");
    line(a1, f, im, "series-imag", "frf-imag-path");
    if (Number.isFinite(r.min_real_m_n)) {
      const m = svgEl("circle", { class: "min-real", cx: a1.sx(r.min_real_frequency_hz), cy: a1.sy(r.min_real_m_n * UM_PER_M), r: 5 }, a1.plot);
      svgEl("title", {}, m).textContent = "most negative real part " + fmt(r.min_real_m_n * UM_PER_M) + " µm/N";
    }
    legend(svg, left + width - 150, 34, [{ cls: "series-real", label: "real" }, { cls: "series-imag", label: "imaginary" }]);

    [lo, hi] = extent([mag], true);
    if (!Number.isFinite(lo)) {
      lo = 1e-3;
      hi = 1;
    }
    const lmin = Math.pow(10, Math.floor(Math.log10(lo)));
    const lmax = Math.pow(10, Math.ceil(Math.log10(hi)));
    const a2 = axes(svg, { x: left, y: 290, w: width, h: 170 }, Object.assign({ showLabels: false }, x),
      { min: lmin, max: lmax > lmin ? lmax : lmin * 10, log: true, label: "|h| (µm/N)" });
    if (r.uncertainty) {  // the p05–p95 band of |h| over the draws, under the nominal curve
      const p05 = r.uncertainty.h_magnitude_m_n.p05.map((v) => v * UM_PER_M);
      const p95 = r.uncertainty.h_magnitude_m_n.p95.map((v) => v * UM_PER_M);
      const pts = [];
      f.forEach((fi, i) => { if (p95[i] > 0) pts.push(a2.sx(fi).toFixed(2) + "," + a2.sy(p95[i]).toFixed(2)); });
      for (let i = f.length - 1; i >= 0; i--) {
        if (p05[i] > 0) pts.push(a2.sx(f[i]).toFixed(2) + "," + a2.sy(p05[i]).toFixed(2));
      }
      const band = svgEl("polygon", { class: "band", id: "frf-band", points: pts.join(" ") }, a2.plot);
      svgEl("title", {}, band).textContent = "p05–p95 of |h| over " + r.uncertainty.draws + " draws";
    }
    line(a2, f, mag, "series-mag", "frf-mag-path", true);
    if (r.uncertainty) {
      legend(svg, left + width - 150, 308, [{ cls: "series-mag", label: "nominal" },
        { cls: "band-key", label: "p05–p95, " + r.uncertainty.draws + " draws" }]);
    }

    const a3 = axes(svg, { x: left, y: 484, w: width, h: 110 }, Object.assign({ label: "Frequency (Hz)" }, x),
      { min: -180, max: 180, ticks: [-180, -90, 0, 90, 180], label: "Phase (°)" });
    line(a3, f, phase, "series-phase", "frf-phase-path");
    attachReadout(svg, a1, f, (i) => "f = " + fmt(f[i], 6) + " Hz · Re " + fmt(re[i]) + ", Im " + fmt(im[i]) +
      " · |h| " + fmt(mag[i]) + " µm/N · phase " + phase[i].toFixed(1) + "°", "frf-readout");
  }

  function drawLobes(result, point) {
    const svg = $("lobes-plot");
    clearPlot("lobes-plot", "Stability lobes of " + state.label + ": axial depth limit in mm against spindle speed in rpm");
    const n = result.spindle_speed_rpm;
    const env = result.depth_limit_m.map((v) => (v === null ? null : v * MM_PER_M));
    const minMm = result.min_depth_limit_m === null ? null : result.min_depth_limit_m * MM_PER_M;
    const flute = fluteLength(result);
    const fluteMm = flute === null ? null : flute * MM_PER_M;
    let [, top] = extent([env]);
    if (!Number.isFinite(top)) top = minMm || fluteMm || 1;
    if (minMm) top = Math.min(top, 8 * minMm);
    if (fluteMm !== null && top > fluteMm) top = fluteMm;  // deeper limits than the flute cannot be used
    if (point) top = Math.max(top, point.depth_m * MM_PER_M);
    top *= 1.1;
    // a semi-discretization speed without a limit is stable up to the search depth: shade it
    const deepMm = result.depth_search_max_m ? result.depth_search_max_m * MM_PER_M : null;
    const shade = env.map((v) => (v === null && deepMm !== null ? Math.min(deepMm, top) : v));
    const left = 90;
    const width = 960 - left - 24;
    const ax = axes(svg, { x: left, y: 16, w: width, h: 340 }, { min: n[0], max: n[n.length - 1], label: "Spindle speed (rpm)" },
      { min: 0, max: top, label: "Axial depth limit (mm)" });
    // stable region under the envelope, one polygon per covered stretch
    let run = [];
    const flush = () => {
      if (run.length > 1) {
        const pts = run.map(([xx, yy]) => ax.sx(xx).toFixed(2) + "," + ax.sy(yy).toFixed(2));
        pts.push(ax.sx(run[run.length - 1][0]).toFixed(2) + "," + ax.sy(0).toFixed(2));
        pts.push(ax.sx(run[0][0]).toFixed(2) + "," + ax.sy(0).toFixed(2));
        svgEl("polygon", { class: "stable", points: pts.join(" ") }, ax.plot);
      }
      run = [];
    };
    shade.forEach((v, i) => (v === null ? flush() : run.push([n[i], Math.min(v, top)])));
    flush();
    if (fluteMm !== null && fluteMm <= top) {
      const fl = svgEl("line", { id: "flute-length", class: "flute", x1: left, x2: left + width, y1: ax.sy(fluteMm),
        y2: ax.sy(fluteMm) }, ax.plot);
      svgEl("title", {}, fl).textContent = "flute length " + fmt(fluteMm, 3) + " mm: no deeper stepdown";
    }
    result.lobes.forEach((lobe) => {
      line(ax, lobe.spindle_speed_rpm, lobe.depth_limit_m.map((v) => (v === null ? null : v * MM_PER_M)),
        "series-lobe", "lobe-" + lobe.index + "-path");
    });
    line(ax, n, env, "series-envelope", "lobes-envelope-path");
    // speeds whose semi-discretization limit two resolutions disagree on: greyed, not to be trusted
    const unresolved = result.resolved ? result.resolved.map((ok) => !ok) : n.map(() => false);
    unresolved.forEach((bad, i) => {
      if (!bad) return;
      const lo = i > 0 ? (n[i - 1] + n[i]) / 2 : n[i];
      const hi = i < n.length - 1 ? (n[i] + n[i + 1]) / 2 : n[i];
      const r = svgEl("rect", { class: "unresolved", x: ax.sx(lo).toFixed(2), y: ax.sy(top).toFixed(2),
        width: Math.max(1, ax.sx(hi) - ax.sx(lo)).toFixed(2), height: (ax.sy(0) - ax.sy(top)).toFixed(2) }, ax.plot);
      svgEl("title", {}, r).textContent = Math.round(n[i]) + " rpm: not resolved (two resolutions disagree by more than 1 %)";
    });
    if (result.depth_limit_robust_m) {
      line(ax, n, result.depth_limit_robust_m.map((v) => (v === null ? null : v * MM_PER_M)), "series-robust",
        "lobes-robust-path");
      legend(svg, left + width - 230, 34, [{ cls: "series-envelope", label: "nominal limit" },
        { cls: "series-robust", label: "robust limit (p" + result.robust.percentile + " of draws)" }]);
    }
    if (minMm) {
      svgEl("line", { class: "limit", x1: left, x2: left + width, y1: ax.sy(minMm), y2: ax.sy(minMm) }, ax.plot);
    }
    if (point) {
      const limit = envelopeAt(result, point.spindle_speed_rpm);
      const stable = limit !== null && point.depth_m < limit;
      const c = svgEl("circle", { id: "operating-point", class: stable ? "op-stable" : "op-unstable",
        cx: ax.sx(point.spindle_speed_rpm), cy: ax.sy(point.depth_m * MM_PER_M), r: 7 }, ax.plot);
      svgEl("title", {}, c).textContent = stable ? "operating point: stable" : "operating point: chatter expected";
    }
    const keys = [{ cls: "series-envelope", label: "stability limit" },
      { cls: "limit", label: "absolute limit " + (minMm ? fmt(minMm, 3) + " mm" : "") }];
    if (unresolved.some((b) => b)) keys.push({ cls: "unresolved", label: "not resolved: do not use" });
    legend(svg, left + 14, 34, keys);
    attachReadout(svg, ax, n, (i) => Math.round(n[i]) + " rpm · limit " + (env[i] === null ? "—" : fmt(env[i], 3) + " mm") +
      (result.chatter_frequency_hz[i] ? " · chatter " + fmt(result.chatter_frequency_hz[i], 5) + " Hz" : "") +
      (unresolved[i] ? " · NOT RESOLVED" : ""), "lobes-readout");
  }

  /** Show the values under the pointer (nearest grid point) below the plot. */
  function attachReadout(svg, ax, xs, text, readoutId) {
    svg.onmousemove = (ev) => {
      const m = svg.getScreenCTM();
      if (!m) return;
      const p = new DOMPoint(ev.clientX, ev.clientY).matrixTransform(m.inverse());
      if (p.x < ax.box.x || p.x > ax.box.x + ax.box.w) return;
      const v = xs[0] + ((p.x - ax.box.x) / ax.box.w) * (xs[xs.length - 1] - xs[0]);
      let lo = 0;
      let hi = xs.length - 1;
      while (hi - lo > 1) {
        const mid = (lo + hi) >> 1;
        if (xs[mid] < v) lo = mid; else hi = mid;
      }
      const i = Math.abs(xs[lo] - v) <= Math.abs(xs[hi] - v) ? lo : hi;
      $(readoutId).textContent = text(i);
    };
  }

  // ------------------------------------------------------------------ shared with diagnosis.js

  /** What the page's other script (diagnosis.js) uses: API access, messages, the assembly, SVG drawing. */
  window.rcsaWeb = {
    ApiError, call, showError, clearError, setStatus, numberFrom, fmt, assemblyToSend, describeSelection,
    svgEl, clearPlot, axes, line, legend, UM_PER_M, MM_PER_M,
  };

  // ------------------------------------------------------------------ start

  function wire() {
    $("predict").addEventListener("click", predict);
    $("lobes").addEventListener("click", lobes);
    $("library-file").addEventListener("change", uploadLibrary);
    $("entry").addEventListener("change", entryChanged);
    $("fill-json").addEventListener("click", fillJson);
    $("error-close").addEventListener("click", clearError);
    $("download-frf-csv").addEventListener("click", () =>
      download("v1/exports/frf.csv", state.uncertainty ? Object.assign({}, state.assembly,
      { uncertainty: state.uncertainty }) : state.assembly, stem() + "-frf.csv", "frf-download-status"));
    $("download-frf-png").addEventListener("click", () => frfFigure("png"));
    $("download-frf-svg").addEventListener("click", () => frfFigure("svg"));
    $("download-lobes-csv").addEventListener("click", () =>
      download("v1/exports/lobes.csv", state.lobesRequest, stem() + "-lobes.csv", "lobes-download-status"));
    $("download-lobes-png").addEventListener("click", () => lobesFigure("png"));
    $("download-lobes-svg").addEventListener("click", () => lobesFigure("svg"));
  }

  async function start() {
    wire();
    entryChanged();
    const loads = [
      loadRa1().catch((err) => showError("Loading the RA-1 defaults failed", err)),
      loadSpindles().catch((err) => showError("Listing the stored spindles failed", err)),
    ];
    await Promise.all(loads);
    document.body.dataset.ready = "true";
  }

  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start);
  else start();
})();
