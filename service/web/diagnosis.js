/* rcsa web view, section 4: diagnose tap tests of the tool point against the model.
 *
 * Flow: one row per stickout (mm) with its tap-test file (UFF 58, CSV/TSV with a header
 * naming columns and units, CutPro .frf, contract JSON). Each file is read by the service
 * (POST v1/measurements:read: the store's importers, nothing stored); the assembly of
 * section 1 is the base model; POST v1/diagnoses answers the verdict, the gap map and, per
 * measurement, the FRF once the verdict's effect is added (corrected_h). The base model's
 * FRF on each measurement's lines comes from POST v1/tool-point-frf. Drawn as inline SVG
 * with the helpers of app.js (window.rcsaWeb).
 */
"use strict";

(function () {
  const web = window.rcsaWeb;
  const $ = (id) => document.getElementById(id);
  const FILE_TYPES = ".csv,.tsv,.txt,.uff,.unv,.frf,.json";
  const DEFAULT_STICKOUTS_MM = ["", "", ""];
  //: options of the quick effort (the standard one is the service's defaults)
  const QUICK = { monte_carlo_draws: 100, max_lines: 400 };
  const Z_LIMIT = 8;
  const Z_FLAG = 3;
  let rows = 0;

  // ------------------------------------------------------------------ tap-test rows

  function addRow(stickoutMm) {
    const i = rows++;
    const row = document.createElement("div");
    row.className = "tap-row";
    row.id = "tap-row-" + i;
    const s = document.createElement("label");
    s.textContent = "Stickout (mm)";
    s.htmlFor = "tap-stickout-" + i;
    const stick = document.createElement("input");
    Object.assign(stick, { type: "number", id: "tap-stickout-" + i, min: "0.001", step: "any" });
    stick.inputMode = "decimal";
    stick.value = stickoutMm || "";
    const f = document.createElement("label");
    f.textContent = "Tap-test file";
    f.htmlFor = "tap-file-" + i;
    const file = document.createElement("input");
    Object.assign(file, { type: "file", id: "tap-file-" + i, accept: FILE_TYPES });
    const remove = document.createElement("button");
    Object.assign(remove, { type: "button", className: "link", textContent: "Remove" });
    remove.addEventListener("click", () => row.remove());
    row.append(s, stick, f, file, remove);
    $("tap-rows").appendChild(row);
  }

  /** [{stickout_mm, file}] of the filled rows; a half-filled row is an error. */
  function filledRows() {
    const out = [];
    for (const row of $("tap-rows").querySelectorAll(".tap-row")) {
      const stick = row.querySelector('input[type="number"]');
      const file = row.querySelector('input[type="file"]');
      const hasFile = file.files && file.files.length > 0;
      if (!hasFile && stick.value.trim() === "") continue;
      const label = "Stickout of row " + (out.length + 1);
      const mm = web.numberFrom(stick.id, label);
      if (!(mm > 0)) throw new web.ApiError(label + " must be > 0 mm", 0, null);
      if (!hasFile) throw new web.ApiError("the row with stickout " + mm + " mm has no tap-test file", 0, null);
      out.push({ stickout_mm: mm, file: file.files[0] });
    }
    if (!out.length) throw new web.ApiError("give at least one stickout with its tap-test file", 0, null);
    return out;
  }

  async function readTap(row) {
    const form = new FormData();
    form.append("file", row.file, row.file.name);
    const units = $("tap-units").value;
    if (units) form.append("units", units);
    try {
      return await (await web.call("v1/measurements:read", { method: "POST", form: form })).json();
    } catch (err) {
      err.message = row.file.name + ": " + err.message;
      throw err;
    }
  }

  // ------------------------------------------------------------------ diagnose

  async function diagnose() {
    web.clearError();
    let chosen, base;
    try {
      chosen = filledRows();
      base = web.assemblyToSend();
    } catch (err) {
      web.showError("Diagnosis not started", err);
      return;
    }
    const button = $("diagnose");
    button.disabled = true;
    document.body.dataset.diagnosis = "busy";
    const t0 = performance.now();
    try {
      web.setStatus("diagnose-status", "Reading " + chosen.length + " tap-test file(s) …");
      const taps = await Promise.all(chosen.map(readTap));
      const measurements = taps.map((doc, i) => {
        if (!doc.h) throw new web.ApiError(chosen[i].file.name + ": the file holds no receptance h", 0, null);
        const m = { tool: { stickout_m: chosen[i].stickout_mm / web.MM_PER_M }, frequency_hz: doc.frequency_hz,
          h: doc.h, label: web.fmt(chosen[i].stickout_mm, 4) + " mm" };
        if (Array.isArray(doc.coherence)) m.coherence = doc.coherence;
        return m;
      });
      const request = { assembly: base, measurements: measurements };
      if ($("diag-effort").value === "quick") request.options = Object.assign({}, QUICK);
      web.setStatus("diagnose-status", "Diagnosing " + measurements.length + " measurement(s) …");
      const [result, baseH] = await Promise.all([
        web.call("v1/diagnoses", { method: "POST", json: request }).then((r) => r.json()),
        Promise.all(measurements.map((m) => baseModel(base, m))),
      ]);
      showVerdict(result);
      drawGapMap(result);
      drawFrfs(measurements, baseH, result);
      web.setStatus("diagnose-status", "Done in " + ((performance.now() - t0) / 1000).toFixed(1) + " s (" +
        measurements.length + " measurements, " + web.describeSelection() + ").");
      document.body.dataset.diagnosis = "drawn";
    } catch (err) {
      web.setStatus("diagnose-status", "Diagnosis failed.");
      document.body.dataset.diagnosis = "error";
      web.showError("Diagnosis failed", err);
    } finally {
      button.disabled = false;
    }
  }

  /** The base model's tool-point h on a measurement's own lines (its stickout). */
  async function baseModel(base, m) {
    const a = JSON.parse(JSON.stringify(base));
    a.tool = Object.assign({}, a.tool, m.tool);
    a.frequency = { values_hz: m.frequency_hz };
    const r = await (await web.call("v1/tool-point-frf?tool_point=h", { method: "POST", json: a })).json();
    return r.tool_point.h;
  }

  function showVerdict(result) {
    const v = result.verdict;
    const box = $("diag-verdict");
    box.hidden = false;
    box.dataset.status = v.status;
    // status "none" with a significant gap: no candidate explains it, the gap is left unexplained
    const what = v.status === "none"
      ? (result.gap && result.gap.significant ? "Gap left unexplained by every candidate" : "No unmodelled effect needed")
      : v.status === "ambiguous" ? "Ambiguous: " + [v.effect].concat(v.ambiguous_with).join(", ")
        : "Verdict: " + v.effect + (result.effects[0] && result.effects[0].proposed_model
          ? " → " + result.effects[0].proposed_model : "");
    $("diag-verdict-title").textContent = what + " (" + v.status + ")";
    $("diag-sentence").textContent = v.sentence;
    $("diag-gap").textContent = result.gap.summary || "";
    const e = result.effects[0];
    $("diag-shrink").textContent = e
      ? "Gap " + web.fmt(e.gap_before_db, 3) + " dB → " + web.fmt(e.gap_after_db, 3) + " dB with " + e.effect +
        (e.held_out_gap_before_db !== null && e.held_out_gap_before_db !== undefined
          ? "; held out: " + web.fmt(e.held_out_gap_before_db, 3) + " → " + web.fmt(e.held_out_gap_after_db, 3) + " dB"
          : "") + "."
      : "";
    // the calibrated model: the verdict's effect with the base's own parameters where the data put them
    const c = result.calibrated;
    $("diag-shrink").textContent += c && c.gap_db !== null && c.gap_db !== undefined
      ? " Calibrated model (tolerances where the measurements put them): " + web.fmt(c.gap_db, 3) + " dB."
      : "";
  }

  // ------------------------------------------------------------------ gap map (z of every feature)

  const KIND = { peak: "peak", antiresonance: "anti-res.", band: "band", static: "static" };
  const FEATURE = { frequency: "freq.", amplitude: "height", level: "level", compliance: "compliance" };

  function featureName(m) {
    const kind = KIND[m.kind] || m.kind;
    const feature = FEATURE[m.feature] || m.feature;
    if (m.kind === "static") return kind + " " + feature;
    return kind + " " + (m.mode !== null && m.mode !== undefined ? m.mode + " " : "") + feature;
  }

  /** Diverging colour of a z-score: blue (model above) · white · red (measurement above). */
  function zColour(z) {
    const t = Math.max(-1, Math.min(1, z / Z_LIMIT));
    const a = Math.abs(t);
    const [r, g, b] = t > 0 ? [178, 24, 43] : [33, 102, 172];
    const mix = (c) => Math.round(255 + (c - 255) * a);
    return "rgb(" + mix(r) + "," + mix(g) + "," + mix(b) + ")";
  }

  function drawGapMap(result) {
    const svg = $("gap-plot");
    web.clearPlot("gap-plot", "Gap map: z-score of every feature of every measurement against the base model");
    const modes = result.gap.modes;
    const labels = [...new Set(modes.map((m) => m.label))];
    const names = [...new Set(modes.map(featureName))];
    const left = 110;
    const top = 24;
    const bottom = 100;
    const cellW = Math.min(70, (960 - left - 20) / Math.max(names.length, 1));
    const cellH = 30;
    const height = top + cellH * labels.length + bottom;
    svg.setAttribute("viewBox", "0 0 960 " + height);
    const g = web.svgEl("g", { class: "gap-map" }, svg);
    for (const m of modes) {
      const col = names.indexOf(featureName(m));
      const row = labels.indexOf(m.label);
      const x = left + col * cellW;
      const y = top + row * cellH;
      const cell = web.svgEl("rect", { class: "gap-cell" + (m.flagged ? " flagged" : ""), x: x, y: y,
        width: cellW - 1, height: cellH - 1, fill: zColour(m.z) }, g);
      web.svgEl("title", {}, cell).textContent = m.label + " · " + featureName(m) + ": z = " + web.fmt(m.z, 3) +
        (m.shift_pct !== undefined && m.shift_pct !== null ? " (frequency " + web.fmt(m.shift_pct, 3) + " %)" : "");
      if (Math.abs(m.z) > Z_FLAG) {
        web.svgEl("text", { class: "gap-z", x: x + cellW / 2, y: y + cellH / 2 + 4, "text-anchor": "middle" }, g)
          .textContent = Math.round(m.z);
      }
    }
    labels.forEach((label, row) => {
      web.svgEl("text", { class: "tick", x: left - 8, y: top + row * cellH + cellH / 2 + 4, "text-anchor": "end" }, g)
        .textContent = label;
    });
    names.forEach((name, col) => {
      const x = left + col * cellW + cellW / 2;
      const y = top + labels.length * cellH + 8;
      web.svgEl("text", { class: "tick", x: x, y: y, "text-anchor": "end", transform: "rotate(-50 " + x + " " + y + ")" }, g)
        .textContent = name;
    });
    web.svgEl("text", { class: "axis-label", x: left, y: 16 }, g).textContent =
      "z of each feature (|z| > " + Z_FLAG + " numbered): red, measured above the model; blue, below";
  }

  // ------------------------------------------------------------------ measured, base and corrected |h|

  function magnitudeUm(h) {
    return h.real.map((re, i) => Math.hypot(re, h.imag[i]) * web.UM_PER_M);
  }

  function drawFrfs(measurements, baseH, result) {
    const svg = $("diag-frf-plot");
    web.clearPlot("diag-frf-plot", "Measured, base-model and corrected |h| of every measurement");
    const effect = result.effects[0] || null;
    const panelH = 150;
    const gap = 46;
    const left = 90;
    const width = 960 - left - 24;
    const height = 16 + measurements.length * (panelH + gap);
    svg.setAttribute("viewBox", "0 0 960 " + height);
    measurements.forEach((m, i) => {
      const f = m.frequency_hz;
      // drawn in this order, so the measurement lies on top of the models
      const series = [{ y: magnitudeUm(baseH[i]), cls: "series-base", id: "diag-base-" + i, label: "base model" }];
      if (effect && effect.corrected_h) {
        series.push({ y: magnitudeUm(effect.corrected_h[i]), cls: "series-corrected", id: "diag-corrected-" + i,
          label: effect.proposed_model ? "base → " + effect.proposed_model : "base + " + effect.effect });
      }
      series.push({ y: magnitudeUm(m.h), cls: "series-measured", id: "diag-measured-" + i, label: "measured " + m.label });
      let lo = Infinity;
      let hi = -Infinity;
      for (const s of series) {
        for (const v of s.y) {
          if (v > 0 && Number.isFinite(v)) {
            lo = Math.min(lo, v);
            hi = Math.max(hi, v);
          }
        }
      }
      const ymin = Math.pow(10, Math.floor(Math.log10(lo)));
      const ymax = Math.pow(10, Math.ceil(Math.log10(hi)));
      const last = i === measurements.length - 1;
      const ax = web.axes(svg, { x: left, y: 16 + i * (panelH + gap), w: width, h: panelH },
        { min: f[0], max: f[f.length - 1] > f[0] ? f[f.length - 1] : f[0] + 1, label: last ? "Frequency (Hz)" : "" },
        { min: ymin, max: ymax > ymin ? ymax : ymin * 10, log: true, label: "|h| (µm/N)" });
      for (const s of series) web.line(ax, f, s.y, s.cls, s.id, true);
      web.legend(svg, left + width - 270, 34 + i * (panelH + gap), series.map((s) => ({ cls: s.cls, label: s.label })));
    });
  }

  // ------------------------------------------------------------------ start

  function start() {
    for (const mm of DEFAULT_STICKOUTS_MM) addRow(mm);
    $("tap-add").addEventListener("click", () => addRow(""));
    $("diagnose").addEventListener("click", diagnose);
  }

  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start);
  else start();
})();
