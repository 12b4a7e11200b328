// report.html's script (experiment/report_html/viewer.js, compiled into the tool by
// cmake/embed_files.cmake). It reads the page's data (the JSON element #scatterlab-data and one
// element per image: base64 of deflated half-float RGB, low bytes then high bytes) and builds
// the header, one viewer per reference scene, the sortable metrics table and the plots. No
// network: everything it needs is in the page. window.scatterlabReport is for the browser
// test (tests/experiment/test_report_html_browser.py).
"use strict";
(function () {
  const DATA = JSON.parse(document.getElementById("scatterlab-data").textContent);

  // ---- Pixels -------------------------------------------------------------------------------

  /// IEEE half (binary16) bits -> float, for all 65536 patterns.
  const HALF = new Float32Array(65536);
  for (let h = 0; h < 65536; ++h) {
    const sign = h & 0x8000 ? -1 : 1, e = (h >> 10) & 31, m = h & 1023;
    HALF[h] = e === 0 ? sign * m * 2 ** -24
      : e === 31 ? (m ? NaN : sign * Infinity)
      : sign * (1 + m / 1024) * 2 ** (e - 15);
  }

  const decoding = new Map();  // image index -> Promise of Float32Array (RGB, rows from the top)
  const decoded = new Map();   // image index -> Float32Array, once ready (for the readout)

  function decodeImage(k) {
    if (!decoding.has(k)) {
      decoding.set(k, (async () => {
        const meta = DATA.images[k];
        const el = document.getElementById(meta.data);
        if (!el) throw new Error(`report.html: the data of ${meta.exr} (#${meta.data}) is missing`);
        const text = atob(el.textContent.trim());
        const packed = new Uint8Array(text.length);
        for (let i = 0; i < text.length; ++i) packed[i] = text.charCodeAt(i);
        const stream = new Blob([packed]).stream().pipeThrough(new DecompressionStream("deflate"));
        const raw = new Uint8Array(await new Response(stream).arrayBuffer());
        const n = meta.w * meta.h * 3;
        if (raw.length !== 2 * n)
          throw new Error(`report.html: ${meta.exr} has ${raw.length} bytes, expected ${2 * n}`);
        const px = new Float32Array(n);
        for (let i = 0; i < n; ++i) px[i] = HALF[raw[i] | (raw[n + i] << 8)];
        decoded.set(k, px);
        return px;
      })());
    }
    return decoding.get(k);
  }

  // The tool's tone curves (core/image.cpp): exposure, the curve, then the sRGB transfer.
  function srgb(v) {
    if (!(v > 0)) return 0;
    if (v >= 1) return 1;
    return v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055;
  }
  function hable(x) {
    const A = 0.15, B = 0.5, C = 0.1, D = 0.2, E = 0.02, F = 0.3;
    return (x * (A * x + C * B) + D * E) / (x * (A * x + B) + D * F) - E / F;
  }
  const HABLE_WHITE = hable(11.2);
  const CURVES = {
    linear: (v) => (v > 0 ? Math.min(v, 1) : 0),
    filmic: (v) => (v > 0 ? Math.min(1, hable(v) / HABLE_WHITE) : 0),
    aces: (v) => (v > 0 ? Math.min(1, Math.max(0, (v * (2.51 * v + 0.03)) / (v * (2.43 * v + 0.59) + 0.14))) : 0),
  };

  /// The denominator floor of the relative error: 1 % of the reference's mean value, so that
  /// black pixels of the reference do not make every difference infinite.
  function relativeFloor(ref) {
    let sum = 0;
    for (let i = 0; i < ref.length; ++i) sum += ref[i];
    return 0.01 * (sum / Math.max(1, ref.length));
  }
  /// Signed relative error of pixel i: (mean(a) - mean(r)) / (mean(r) + floor).
  function relError(a, r, i, floor) {
    const ma = (a[3 * i] + a[3 * i + 1] + a[3 * i + 2]) / 3;
    const mr = (r[3 * i] + r[3 * i + 1] + r[3 * i + 2]) / 3;
    return (ma - mr) / (mr + floor);
  }

  // ---- Small DOM helpers --------------------------------------------------------------------

  function el(tag, attrs, ...children) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (k === "class") e.className = v;
      else if (k === "text") e.textContent = v;
      else e.setAttribute(k, v);
    }
    for (const c of children) if (c !== null && c !== undefined) e.append(c);
    return e;
  }
  /// Inline Markdown of the config's texts as DOM nodes (never HTML): `code`, **strong**, *em* and
  /// [text](http(s) or relative link); anything else stays text.
  function markdown(text) {
    const out = [];
    const re = /`([^`]+)`|\*\*([^*]+)\*\*|\*([^*\s][^*]*)\*|\[([^\]]+)\]\(([^)\s]+)\)/g;
    let last = 0, m;
    while ((m = re.exec(text)) !== null) {
      if (m.index > last) out.push(text.slice(last, m.index));
      if (m[1] !== undefined) out.push(el("code", { text: m[1] }));
      else if (m[2] !== undefined) out.push(el("strong", { text: m[2] }));
      else if (m[3] !== undefined) out.push(el("em", { text: m[3] }));
      else if (/^https?:\/\//i.test(m[5]) || !m[5].includes(":")) out.push(el("a", { href: m[5], text: m[4] }));
      else out.push(m[0]);
      last = re.lastIndex;
    }
    if (last < text.length) out.push(text.slice(last));
    return out;
  }

  function fmt(v) {
    if (!Number.isFinite(v)) return String(v);
    const a = Math.abs(v);
    return a !== 0 && (a < 1e-3 || a >= 1e5) ? v.toExponential(3) : v.toPrecision(4);
  }

  // ---- The viewer ---------------------------------------------------------------------------

  const viewers = [];
  let active = null;

  class Viewer {
    constructor(group, index) {
      this.group = group;
      this.index = index;
      this.items = group.items;
      this.ref = group.reference >= 0 ? group.reference : 0;
      const firstRun = this.items.findIndex((it) => it.kind === "run");
      this.a = firstRun >= 0 ? firstRun : 0;
      this.b = -1;  // split off
      this.split = 0.5;
      // As the PNGs beside the EXRs: the harness's exposure, its linear curve.
      this.exposure = DATA.png_exposure || 0;
      this.tone = DATA.png_tone || "linear";
      this.mode = "image";
      this.errScale = 0.1;
      this.view = null;  // {s, ox, oy}: image pixel (x, y) shows at canvas (ox + s x, oy + s y)
      this.layers = new Map();
      this.pending = 0;
      this.waiters = [];
      this.drawToken = 0;
      this.build();
    }

    meta(item) { return DATA.images[this.items[item].image]; }

    build() {
      const g = this.group;
      this.root = el("section", { class: "viewer", id: `viewer-${this.index}`, tabindex: "0" });
      this.root.append(el("h3", { text: g.title }));
      this.buttons = this.items.map((it, k) => {
        const b = el("button", { type: "button", title: (it.run ? `run ${it.run}; ` : "") +
          "click: show; shift-click: split against it" },
          k < 9 ? el("span", { class: "key", text: String(k + 1) }) : null, it.label);
        b.addEventListener("click", (ev) => {
          this.activate();
          if (ev.shiftKey) this.setB(k === this.b ? -1 : k);
          else this.setA(k);
        });
        return b;
      });
      this.root.append(el("div", { class: "items" }, ...this.buttons));

      const options = (sel, extra) => {
        for (const [v, t] of extra) sel.append(el("option", { value: String(v), text: t }));
        this.items.forEach((it, k) => sel.append(el("option", { value: String(k), text: `${k + 1} ${it.label}` })));
        return sel;
      };
      this.exposureInput = el("input", { type: "range", class: "exposure", min: "-10", max: "10", step: "0.25", value: String(this.exposure) });
      this.exposureOut = el("output", { text: (this.exposure >= 0 ? "+" : "") + this.exposure });
      this.toneSelect = el("select", { class: "tone" });
      for (const t of ["linear", "filmic", "aces"]) this.toneSelect.append(el("option", { value: t, text: t }));
      this.toneSelect.value = this.tone;
      this.modeSelect = el("select", { class: "mode" },
        el("option", { value: "image", text: "image" }),
        el("option", { value: "error", text: "relative error vs reference" }));
      this.refSelect = options(el("select", { class: "reference" }), []);
      this.refSelect.value = String(this.ref);
      this.scaleSelect = el("select", { class: "errscale" });
      for (const s of [0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1]) this.scaleSelect.append(el("option", { value: String(s), text: `±${s * 100}%` }));
      this.scaleSelect.value = String(this.errScale);
      this.splitSelect = options(el("select", { class: "splitb" }), [[-1, "off"]]);
      this.splitInput = el("input", { type: "range", class: "split", min: "0", max: "1", step: "0.001", value: "0.5" });
      const fit = el("button", { type: "button", class: "fit", text: "fit (f)" });
      this.root.append(el("div", { class: "controls" },
        el("label", {}, "exposure ", this.exposureInput, " ", this.exposureOut, " stops"),
        el("label", {}, "tone map ", this.toneSelect),
        el("label", {}, "show ", this.modeSelect),
        el("label", {}, "reference ", this.refSelect),
        el("label", {}, "error scale ", this.scaleSelect, " ", el("span", { class: "legend", title: "blue: darker than the reference; red: brighter" })),
        el("label", {}, "split with ", this.splitSelect, " ", this.splitInput),
        fit));
      this.canvas = el("canvas", { class: "view" });
      this.stage = el("div", { class: "stage" }, this.canvas);
      this.readout = el("div", { class: "readout", text: "move the pointer over the image for its values" });
      this.links = el("div", { class: "links" });
      this.root.append(this.stage, this.readout, this.links);

      this.exposureInput.addEventListener("input", () => this.setExposure(Number(this.exposureInput.value)));
      this.toneSelect.addEventListener("change", () => { this.tone = this.toneSelect.value; this.draw(); });
      this.modeSelect.addEventListener("change", () => { this.mode = this.modeSelect.value; this.draw(); });
      this.refSelect.addEventListener("change", () => { this.ref = Number(this.refSelect.value); this.draw(); });
      this.scaleSelect.addEventListener("change", () => { this.errScale = Number(this.scaleSelect.value); this.draw(); });
      this.splitSelect.addEventListener("change", () => this.setB(Number(this.splitSelect.value)));
      this.splitInput.addEventListener("input", () => { this.split = Number(this.splitInput.value); this.paint(); });
      fit.addEventListener("click", () => { this.view = null; this.paint(); });
      this.root.addEventListener("pointerdown", () => this.activate());
      this.root.addEventListener("focusin", () => this.activate());
      this.bindPointer();
    }

    activate() {
      if (active && active !== this) active.root.classList.remove("active");
      active = this;
      this.root.classList.add("active");
    }

    setA(k) { this.a = k; this.draw(); }
    setB(k) { this.b = k === this.a ? -1 : k; this.splitSelect.value = String(this.b); this.draw(); }
    setExposure(stops) {
      this.exposure = Math.max(-10, Math.min(10, stops));
      this.exposureInput.value = String(this.exposure);
      this.exposureOut.textContent = (this.exposure >= 0 ? "+" : "") + this.exposure;
      this.draw();
    }

    /// Canvas size: the stage's width, the first image's aspect, at most 60 % of the window.
    resize() {
      const m = this.meta(0);
      const w = Math.max(64, Math.round(this.stage.clientWidth || 800));
      const h = Math.max(48, Math.min(Math.round(window.innerHeight * 0.6), Math.round((w * m.h) / m.w)));
      if (this.canvas.width !== w || this.canvas.height !== h) {
        this.canvas.width = w;
        this.canvas.height = h;
        this.view = null;
      }
    }

    fitView() {
      const m = this.meta(this.a), cw = this.canvas.width, ch = this.canvas.height;
      const s = Math.min(cw / m.w, ch / m.h);
      this.view = { s, ox: (cw - m.w * s) / 2, oy: (ch - m.h * s) / 2 };
    }

    /// The tone-mapped (or error-map) RGBA of item k as a canvas of its own size.
    async layer(k) {
      const key = [k, this.exposure, this.tone, this.mode, this.ref, this.errScale].join("|");
      if (this.layers.has(key)) return this.layers.get(key);
      const m = this.meta(k);
      const px = await decodeImage(this.items[k].image);
      const out = new ImageData(m.w, m.h);
      const d = out.data, n = m.w * m.h;
      if (this.mode === "error") {
        const rm = this.meta(this.ref);
        const rp = await decodeImage(this.items[this.ref].image);
        if (rm.w !== m.w || rm.h !== m.h)
          throw new Error(`report.html: ${m.exr} (${m.w}×${m.h}) and the reference ${rm.exr} (${rm.w}×${rm.h}) differ in size`);
        const floor = relativeFloor(rp);
        for (let i = 0; i < n; ++i) {
          const e = relError(px, rp, i, floor);
          const t = Math.round(255 * Math.min(1, Math.abs(e) / this.errScale));
          d[4 * i] = e > 0 ? t : 0;
          d[4 * i + 1] = 0;
          d[4 * i + 2] = e < 0 ? t : 0;
          d[4 * i + 3] = 255;
        }
      } else {
        const scale = 2 ** this.exposure, curve = CURVES[this.tone];
        for (let i = 0; i < n; ++i) {
          for (let c = 0; c < 3; ++c) d[4 * i + c] = Math.floor(srgb(curve(px[3 * i + c] * scale)) * 255 + 0.5);
          d[4 * i + 3] = 255;
        }
      }
      const c = el("canvas");
      c.width = m.w;
      c.height = m.h;
      c.getContext("2d").putImageData(out, 0, 0);
      if (this.layers.size > 12) this.layers.delete(this.layers.keys().next().value);
      this.layers.set(key, c);
      return c;
    }

    /// Recomputes the layers shown, then paints; draws started later win.
    async draw() {
      const token = ++this.drawToken;
      this.pending++;
      this.buttons.forEach((b, k) => {
        b.classList.toggle("a", k === this.a);
        b.classList.toggle("b", k === this.b);
      });
      this.updateLinks();
      try {
        const shown = [this.a].concat(this.b >= 0 ? [this.b] : []);
        const layers = await Promise.all(shown.map((k) => this.layer(k)));
        if (token === this.drawToken) {
          this.shown = layers;
          this.paint();
        }
      } catch (e) {
        this.readout.textContent = String(e.message || e);
        console.error(e);
      } finally {
        if (--this.pending === 0) this.waiters.splice(0).forEach((f) => f());
      }
    }

    /// Resolves once no draw is in flight (used by the browser test).
    idle() { return this.pending === 0 ? Promise.resolve() : new Promise((f) => this.waiters.push(f)); }

    paint() {
      if (!this.shown) return;
      this.resize();
      if (!this.view) this.fitView();
      const ctx = this.canvas.getContext("2d"), cw = this.canvas.width, ch = this.canvas.height;
      const { s, ox, oy } = this.view, m = this.meta(this.a);
      ctx.setTransform(1, 0, 0, 1, 0, 0);
      ctx.clearRect(0, 0, cw, ch);
      ctx.imageSmoothingEnabled = false;
      ctx.setTransform(s, 0, 0, s, ox, oy);
      ctx.drawImage(this.shown[0], 0, 0, m.w, m.h);
      if (this.shown.length > 1) {
        const sx = Math.round(this.split * cw);
        ctx.save();
        ctx.setTransform(1, 0, 0, 1, 0, 0);
        ctx.beginPath();
        ctx.rect(sx, 0, cw - sx, ch);
        ctx.clip();
        ctx.setTransform(s, 0, 0, s, ox, oy);
        ctx.drawImage(this.shown[1], 0, 0, m.w, m.h);
        ctx.restore();
        ctx.setTransform(1, 0, 0, 1, 0, 0);
        ctx.fillStyle = "rgba(255,255,255,0.85)";
        ctx.fillRect(sx - 1, 0, 2, ch);
      }
    }

    updateLinks() {
      const link = (k) => {
        const m = this.meta(k);
        const size = m.factor > 1 ? ` (${m.full_w}×${m.full_h}; shown ${m.w}×${m.h}, box-filtered ${m.factor}×${m.factor})` : ` (${m.w}×${m.h})`;
        return [el("a", { href: m.exr, text: m.exr }), size];
      };
      this.links.replaceChildren("EXR: ", ...link(this.a));
      if (this.b >= 0) this.links.append(" | split with: ", ...link(this.b));
    }

    /// Canvas coordinates of a pointer event.
    at(ev) {
      const r = this.canvas.getBoundingClientRect();
      return [((ev.clientX - r.left) * this.canvas.width) / r.width, ((ev.clientY - r.top) * this.canvas.height) / r.height];
    }

    bindPointer() {
      let drag = null;
      this.canvas.addEventListener("wheel", (ev) => {
        if (!this.view) return;
        ev.preventDefault();
        const [mx, my] = this.at(ev), f = Math.exp(-ev.deltaY * 0.0015);
        const v = this.view, s = Math.min(256, Math.max(0.05, v.s * f)), g = s / v.s;
        this.view = { s, ox: mx - (mx - v.ox) * g, oy: my - (my - v.oy) * g };
        this.paint();
      }, { passive: false });
      this.canvas.addEventListener("pointerdown", (ev) => {
        if (!this.view) return;
        const [mx, my] = this.at(ev);
        const onSplit = this.b >= 0 && Math.abs(mx - this.split * this.canvas.width) < 6;
        drag = { mx, my, ox: this.view.ox, oy: this.view.oy, split: onSplit };
        this.canvas.setPointerCapture(ev.pointerId);
      });
      this.canvas.addEventListener("pointermove", (ev) => {
        const [mx, my] = this.at(ev);
        if (drag && drag.split) {
          this.split = Math.min(1, Math.max(0, mx / this.canvas.width));
          this.splitInput.value = String(this.split);
          this.paint();
        } else if (drag) {
          this.view = { s: this.view.s, ox: drag.ox + mx - drag.mx, oy: drag.oy + my - drag.my };
          this.paint();
        }
        this.showValues(mx, my);
      });
      const end = () => { drag = null; };
      this.canvas.addEventListener("pointerup", end);
      this.canvas.addEventListener("pointercancel", end);
    }

    /// The values under canvas point (mx, my): the image shown there, the reference, the
    /// relative error.
    showValues(mx, my) {
      if (!this.view) return;
      const m = this.meta(this.a);
      const x = Math.floor((mx - this.view.ox) / this.view.s), y = Math.floor((my - this.view.oy) / this.view.s);
      if (x < 0 || y < 0 || x >= m.w || y >= m.h) {
        this.readout.textContent = "outside the image";
        return;
      }
      const here = this.b >= 0 && mx >= this.split * this.canvas.width ? this.b : this.a;
      const i = y * m.w + x;
      const rgb = (k) => {
        const px = decoded.get(this.items[k].image), mk = this.meta(k);
        if (!px || mk.w !== m.w || mk.h !== m.h) return "…";
        return [0, 1, 2].map((c) => fmt(px[3 * i + c]).padStart(10)).join(" ");
      };
      const full = m.factor > 1 ? ` (full size: ${x * m.factor}–${Math.min(m.full_w, (x + 1) * m.factor) - 1}, ${y * m.factor}–${Math.min(m.full_h, (y + 1) * m.factor) - 1})` : "";
      const lines = [`pixel (${x}, ${y})${full}   linear RGB`,
        `image     ${rgb(here)}   ${this.items[here].label}`,
        `reference ${rgb(this.ref)}   ${this.items[this.ref].label}`];
      const a = decoded.get(this.items[here].image), r = decoded.get(this.items[this.ref].image);
      if (a && r && a.length === r.length) {
        const e = relError(a, r, i, relativeFloor(r));
        lines[2] += `   relative error ${e >= 0 ? "+" : ""}${(100 * e).toFixed(2)}%`;
      }
      this.readout.textContent = lines.join("\n");
    }
  }

  // ---- Keys ----------------------------------------------------------------------------------

  document.addEventListener("keydown", (ev) => {
    const t = ev.target;
    if (t && (t.tagName === "SELECT" || (t.tagName === "INPUT" && t.type !== "range"))) return;
    if (ev.ctrlKey || ev.metaKey || ev.altKey) return;
    const v = active || viewers[0];
    if (!v) return;
    const digit = /^Digit([1-9])$/.exec(ev.code);
    if (digit) {
      const k = Number(digit[1]) - 1;
      if (k < v.items.length) ev.shiftKey ? v.setB(k === v.b ? -1 : k) : v.setA(k);
    } else if (ev.key === "e") {
      v.mode = v.mode === "error" ? "image" : "error";
      v.modeSelect.value = v.mode;
      v.draw();
    } else if (ev.key === "f") {
      v.view = null;
      v.paint();
    } else if (ev.key === "+" || ev.key === "=") {
      v.setExposure(v.exposure + 0.5);
    } else if (ev.key === "-") {
      v.setExposure(v.exposure - 0.5);
    } else {
      return;
    }
    ev.preventDefault();
  });
  window.addEventListener("resize", () => viewers.forEach((v) => v.paint()));

  // ---- The page ------------------------------------------------------------------------------

  function header(main) {
    main.append(el("h1", { text: DATA.title }));
    if (DATA.description) main.append(el("p", { class: "description" }, ...markdown(DATA.description)));
    main.append(el("p", { class: "meta" }, "Config ", el("code", { text: DATA.config }),
      `; ${DATA.runs} runs (${DATA.rendered} rendered now, ${DATA.resumed} resumed, ${DATA.failed} failed, ${DATA.refused || 0} refused). Written ${DATA.written}. `,
      "Tables and definitions: ", el("a", { href: "report.md", text: "report.md" }), ", ",
      el("a", { href: "results.csv", text: "results.csv" }), ", ", el("a", { href: "results.json", text: "results.json" }), "."));
    if (DATA.machines.length > 1)
      main.append(el("p", {}, el("strong", { text: `These runs come from ${DATA.machines.length} different machines or commits: compare times only between runs of one machine.` })));
    for (const m of DATA.machines) main.append(el("p", { class: "machine" }, el("strong", { text: "Machine: " }), ...markdown(m)));
    for (const m of DATA.missing) main.append(el("p", { class: "note", text: `Left out (unreadable): ${m}` }));
  }

  /// One row of thumbnails (the PNGs beside the EXRs) per viewer; a click opens that image there.
  function overviewSection(main) {
    if (!DATA.groups.length) return;
    main.append(el("h2", { text: "Overview" }));
    const grid = el("div", { class: "overview" });
    DATA.groups.forEach((g, k) => {
      const row = el("div", { class: "overview-row" }, el("div", { class: "overview-title", text: g.title }));
      g.items.forEach((it, i) => {
        if (!it.png) return;
        const fig = el("figure", { class: "thumb", title: `${it.label}: show in its viewer` },
          el("img", { src: it.png, alt: it.label, loading: "lazy" }), el("figcaption", { text: it.label }));
        fig.addEventListener("click", () => {
          const v = viewers[k];
          v.activate();
          v.setA(i);
          v.root.scrollIntoView({ block: "start" });
        });
        row.append(fig);
      });
      grid.append(row);
    });
    main.append(grid);
  }

  function viewersSection(main) {
    main.append(el("h2", { text: "Images" }));
    main.append(el("p", { class: "note", text:
      `Per reference scene: the references and every run measured against them, as linear half floats (images whose longer side exceeds ${DATA.max_side} px box-filtered, the EXR linked). ` +
      "Keys act on the outlined viewer (the last one clicked). Keys 1–9 (or a click) show an image, shift+1–9 (or shift-click) split against one; drag to pan, wheel to zoom (shared by all images of a viewer); " +
      "+/− exposure, e toggles the relative error map ((mean(image) − mean(reference)) / (mean(reference) + 1 % of the reference's mean); red: brighter, blue: darker), f fits." }));
    if (!DATA.groups.length) main.append(el("p", { text: "No successful run has an image." }));
    DATA.groups.forEach((g, k) => {
      const v = new Viewer(g, k);
      viewers.push(v);
      main.append(v.root);
    });
  }

  function tableSection(main) {
    main.append(el("h2", { text: "Metrics" }));
    main.append(el("p", { class: "note", text:
      `Against the reference ${DATA.reference}, as in report.md: median time per frame, relative L2, masked relative L2 (K px around each light masked), relative L1, visibly wrong share. Click a header to sort, a row to open its images.` }));
    const cols = DATA.table.columns, rows = DATA.table.rows;
    const numeric = cols.map((_, c) => rows.some((r) => r.cells[c] && typeof r.cells[c].v === "number"));
    const thead = el("tr", {}, ...cols.map((c) => el("th", { scope: "col", text: c })));
    const tbody = el("tbody");
    const trs = rows.map((r) => {
      const tr = el("tr", { "data-run": r.run });
      if (!r.ok) {
        tr.className = r.status === "refused" ? "refused" : "failed";
        r.cells.forEach((c) => tr.append(el("td", { text: c.t })));
        tr.append(el("td", { colspan: String(cols.length - r.cells.length), text: `${r.status || "failed"}: ${r.error}` }));
      } else {
        r.cells.forEach((c, k) => tr.append(el("td", { class: numeric[k] ? "num" : "", text: c.t })));
      }
      if (r.group !== undefined) {
        tr.classList.add("has-image");
        tr.title = "show its images";
        tr.addEventListener("click", () => {
          const v = viewers[r.group];
          v.activate();
          v.setA(r.item);
          v.root.scrollIntoView({ block: "start" });
        });
      }
      tr.row = r;
      return tr;
    });
    tbody.append(...trs);
    let sorted = { col: -1, dir: 1 };
    [...thead.children].forEach((th, c) => th.addEventListener("click", () => {
      sorted = { col: c, dir: sorted.col === c ? -sorted.dir : 1 };
      const key = (tr) => (tr.row.cells[c] ? tr.row.cells[c].v : null);
      trs.sort((x, y) => {
        const a = key(x), b = key(y);
        if (a === null || a === undefined) return b === null || b === undefined ? 0 : 1;
        if (b === null || b === undefined) return -1;
        return (typeof a === "number" && typeof b === "number" ? a - b : String(a).localeCompare(String(b), undefined, { numeric: true })) * sorted.dir;
      });
      tbody.append(...trs);
      [...thead.children].forEach((h, k) => (k === c ? h.setAttribute("aria-sort", sorted.dir > 0 ? "ascending" : "descending") : h.removeAttribute("aria-sort")));
    }));
    main.append(el("div", { class: "table-wrap" }, el("table", { class: "metrics" }, el("thead", {}, thead), tbody)));
    if (DATA.failures.length) {
      main.append(el("h3", { text: "Failures" }));
      main.append(el("ul", {}, ...DATA.failures.map((f) => el("li", {}, el("code", { text: f.run }), `: ${f.error}`))));
    }
  }

  function plotsSection(main) {
    main.append(el("h2", { text: "Plots" }));
    if (DATA.plots_note) main.append(el("p", { class: "note", text: `No plots: ${DATA.plots_note}.` }));
    else if (!DATA.plots.length) main.append(el("p", { class: "note", text: "No sweep of this experiment has data for a plot." }));
    for (const p of DATA.plots) {
      if (p.missing) {
        main.append(el("p", { class: "note", text: `${p.caption} (missing: ${p.missing})` }));
        continue;
      }
      main.append(el("figure", { class: "plot" }, el("img", { src: p.src, alt: p.caption }),
        el("figcaption", {}, p.caption, " (", el("a", { href: p.svg, text: "SVG" }), ")")));
    }
  }

  const main = document.getElementById("report");
  header(main);
  const overview = el("div");
  main.append(overview);
  viewersSection(main);
  overviewSection(overview);
  tableSection(main);
  plotsSection(main);
  if (viewers.length) viewers[0].activate();
  viewers.forEach((v) => v.draw());
  window.scatterlabReport = {
    data: DATA,
    viewers,
    /// Resolves when no viewer has a draw in flight.
    idle: () => Promise.all(viewers.map((v) => v.idle())),
    decodeImage,
  };
})();
