// Probe plots (uPlot): one panel per probe quantity of the last run, chosen by chips; the
// last few runs overlaid (older ones dashed and faded), each named by what differed; a
// sweep's members overlaid, each named by its values; drag to zoom (all panels follow),
// double-click to zoom out; the cursor shows values and moves the 3-D view in time.
import { useEffect, useMemo, useRef, useState } from "react";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { Modal } from "./Dialogs.jsx";
import { useClickAway } from "./hooks/useClickAway.js";
import { OVERLAY } from "./hooks/useRun.js";
import { download, fileName, plotCsv, plotSvg } from "./plotexport.js";
import { memberLabel, runStatus } from "./runs.js";
import { useStudio } from "./store.js";
import { TESTING, trace } from "./testing.js";

const COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf", "#8c564b", "#e377c2", "#7f7f7f"];
const AXES = ["x", "y", "z"];
/** The axes' tick labels: one font, so that the y axis can be as wide as its longest label. */
const AXIS_FONT = "11px system-ui, -apple-system, 'Segoe UI', sans-serif";
/** The least room between two y ticks (px): uPlot's 30 left a short plot one tick. */
const Y_TICK_SPACE = 16;
const TICK_LENGTH = 6;
/** The least time (ms) between two moves of the cursors following the 3-D view. */
const FOLLOW_MS = 90;
const LABEL_GAP = 5;
let measurer = null;

/** The width (px) of ``text`` in the axes' font. */
export function textWidth(text) {
  if (!measurer) {
    measurer = document.createElement("canvas").getContext("2d");
    measurer.font = AXIS_FONT;
  }
  return measurer.measureText(text).width;
}

/** The nice step below ``step`` (5 -> 2 -> 1 -> 0.5 ... times a power of ten). */
function finer(step) {
  const p = 10 ** Math.floor(Math.log10(step));
  const m = Math.round(step / p);
  return m >= 5 ? 2 * p : m >= 2 ? p : p / 2;
}

/**
 * The y ticks: uPlot's, made finer until there are at least three (a short plot of a small
 * range had one, "0").
 */
export function yTicks(min, max, step) {
  const at = (s) => {
    const out = [];
    for (let k = Math.ceil(min / s - 1e-9); k * s <= max + 1e-9 * s; k++) out.push(+(k * s).toPrecision(12));
    return out;
  };
  if (!(max > min) || !(step > 0)) return [min];
  let ticks = at(step);
  for (let i = 0; ticks.length < 3 && i < 12; i++) {
    step = finer(step);
    ticks = at(step);
  }
  return ticks;
}

/** The y axis's width: its longest label, the gap and the tick (uPlot asks again as the labels change). */
function yAxisSize(u, values) {
  const widest = Math.max(24, ...(values || []).map((v) => textWidth(String(v))));
  return Math.ceil(widest + LABEL_GAP + TICK_LENGTH + 4);
}

function components(sig) {
  // a signal's columns: scalars one, vectors (3,) x y z, matrices flattened
  const n = (sig.shape || []).reduce((a, b) => a * b, 1);
  const flat = (row) => (Array.isArray(row) ? row.flat(Infinity) : [row]);
  const cols = [];
  for (let k = 0; k < n; k++) {
    cols.push(sig.values.map((row) => {
      const v = flat(row)[k];
      return v === null || v === undefined ? null : Number(v);
    }));
  }
  const labels = n === 1 ? [""] : n === 3 ? AXES : Array.from({ length: n }, (_, k) => `[${k}]`);
  return { cols, labels };
}

function sameGrid(a, b) {
  return a.length === b.length && a[0] === b[0] && a[a.length - 1] === b[b.length - 1];
}

function fmt(v) {
  if (v == null || Number.isNaN(v)) return "–";
  const a = Math.abs(v);
  if (a !== 0 && (a < 1e-3 || a >= 1e5)) return v.toExponential(3);
  return v.toFixed(4);
}

/** The probe a signal is of ("probe1", "upper.p1"): its descriptor's, sent by the server. */
function probeOf(sig, name) {
  if (sig && sig.probe) return sig.probe;
  const i = name.lastIndexOf(".");
  return i < 0 ? name : name.slice(0, i);
}

/** The quantity a signal records ("angle"): its descriptor's, sent by the server. */
export function quantityOf(sig, name) {
  if (sig && sig.quantity) return sig.quantity;
  const i = name.lastIndexOf(".");
  return i < 0 ? name : name.slice(i + 1);
}

/**
 * The curves a run entry draws: one for a run, one per member for a sweep (members that
 * have results), each with its name.
 */
export function sourcesOf(entry) {
  if (entry.kind === "sweep") {
    return (entry.members || []).filter((m) => m.results && m.results.t.length).map((m) => ({ results: m.results, label: memberLabel(m) || `member ${m.index}` }));
  }
  return [{ results: entry.results, label: entry.label || `run ${entry.n}` }];
}

/** uPlot's data and series for the signals ``names`` of the last runs (latest first). */
function buildData(names, runs) {
  const sources = runs.slice(0, OVERLAY).flatMap((run, r) => sourcesOf(run).map((src, m) => ({ ...src, r, m, sweep: run.kind === "sweep" })));
  const t0 = sources[0].results.t;
  const series = /** @type {any[]} */ ([{ label: "t [s]", value: (u, v) => (v == null ? "–" : v.toFixed(3)) }]);
  const tables = [];
  const columns = {};
  let unit = "";
  let color = 0;
  for (const src of sources) {
    // a signal has its colour in every run; a sweep's members each their own
    if (!src.sweep || src.m === 0) color = 0;
    for (const name of names) {
      const sig = src.results.signals.find((s) => s.name === name);
      const { cols, labels } = sig ? components(sig) : { cols: [], labels: [] };
      if (sig && !unit) unit = sig.unit || "";
      cols.forEach((col, k) => {
        const c = COLORS[color++ % COLORS.length];
        const label = names.length > 1 ? `${probeOf(sig, name)}${labels[k] ? ` ${labels[k]}` : ""}` : labels[k] || quantityOf(sig, name);
        const older = src.r > 0;
        series.push({
          label: sources.length > 1 ? `${label} · ${src.label}` : label,
          stroke: older ? `${c}66` : c,
          width: older ? 1 : 1.6,
          dash: older ? [5, 4] : undefined,
          value: (u, v) => fmt(v),
          points: { show: false },
          spanGaps: true,
        });
        if (src.r === 0 && src.m === 0) (columns[name] = columns[name] || []).push(tables.length + 1);
        tables.push({ t: src.results.t, y: col });
      });
      if (!sig && src.r === 0 && src.m === 0) columns[name] = [];
    }
  }
  let data;
  if (tables.every((tb) => sameGrid(tb.t, t0))) {
    data = [t0, ...tables.map((tb) => tb.y)];
  } else {
    data = uPlot.join(tables.map((tb) => [tb.t, tb.y]));
  }
  return { series, data, unit, columns };
}

/** The picture of a plot as PNG: uPlot's canvas, the title above, the legend below. */
function plotPng(u, title, unit, series) {
  const rows = Math.ceil(series.length / 2);
  const ratio = u.ctx.canvas.width / u.width;
  const canvas = document.createElement("canvas");
  canvas.width = Math.round(u.width * ratio);
  canvas.height = Math.round((u.height + 26 + 16 * rows + 8) * ratio);
  const ctx = canvas.getContext("2d");
  ctx.scale(ratio, ratio);
  ctx.fillStyle = "#fff";
  ctx.fillRect(0, 0, u.width, canvas.height / ratio);
  ctx.fillStyle = "#222";
  ctx.font = `600 13px ${AXIS_FONT.split(" ").slice(1).join(" ")}`;
  ctx.fillText(`${title}${unit ? ` [${unit}]` : ""}`, 8, 17);
  ctx.drawImage(u.ctx.canvas, 0, 26, u.width, u.height);
  ctx.font = AXIS_FONT;
  series.forEach((s, k) => {
    const x = 46 + (k % 2) * ((u.width - 46) / 2);
    const y = 26 + u.height + 14 + 16 * Math.floor(k / 2);
    ctx.strokeStyle = s.stroke;
    ctx.lineWidth = 2;
    ctx.setLineDash(s.dash || []);
    ctx.beginPath();
    ctx.moveTo(x, y - 4);
    ctx.lineTo(x + 16, y - 4);
    ctx.stroke();
    ctx.fillStyle = "#222";
    ctx.fillText(s.label, x + 22, y);
  });
  return new Promise((done) => canvas.toBlob(done, "image/png"));
}

/** What the axis ``i`` of ``u`` shows: its range, ticks and their labels. */
function axisOf(u, i) {
  const key = i === 0 ? "x" : "y";
  const ticks = u.axes[i]._splits || [];
  return { min: u.scales[key].min, max: u.scales[key].max, ticks, labels: (u.axes[i]._values || []).map(String), size: u.axes[i]._size };
}

function Panel({ title, names, runs, bus, width, height, onEnlarge = null, big = false }) {
  const ref = useRef(null);
  const plotRef = useRef(null);
  const model = useStudio((st) => st.hist.present.name);
  const built = useMemo(() => buildData(names, runs), [names, runs]);
  const curves = built.series.slice(1);
  const exportCsv = () => {
    const labels = curves.map((c) => c.label);
    download(new Blob([plotCsv(built.data, labels, built.unit)], { type: "text/csv" }), `${fileName(model, title)}.csv`);
  };
  const exportSvg = () => {
    const u = plotRef.current;
    if (!u) return;
    const svg = plotSvg({ title, unit: built.unit, width: u.width, height: u.height + 26 + 16 * Math.ceil(curves.length / 2) + 8,
      x: axisOf(u, 0), y: axisOf(u, 1), data: built.data, series: curves });
    download(new Blob([svg], { type: "image/svg+xml" }), `${fileName(model, title)}.svg`);
  };
  const exportPng = () => {
    const u = plotRef.current;
    if (u) plotPng(u, title, built.unit, curves).then((blob) => blob && download(blob, `${fileName(model, title)}.png`));
  };
  useEffect(() => {
    if (!ref.current || width < 50) return undefined;
    const opts = {
      width: Math.max(200, width),
      height,
      scales: { x: { time: false } },
      series: built.series,
      // every curve named: an overlaid run by its number and what differed from the one before
      legend: { show: true, live: true },
      cursor: {
        sync: { key: "kn-plots", setSeries: false },
        drag: { x: true, y: false, setScale: true },
        points: { size: 5 },
      },
      axes: [
        { stroke: "#555", font: AXIS_FONT, grid: { stroke: "#eceef1" }, ticks: { stroke: "#ccc", size: TICK_LENGTH }, gap: LABEL_GAP, size: 30 },
        {
          stroke: "#555",
          font: AXIS_FONT,
          grid: { stroke: "#eceef1" },
          ticks: { stroke: "#ccc", size: TICK_LENGTH },
          gap: LABEL_GAP,
          space: Y_TICK_SPACE,
          splits: (u, i, min, max, step) => yTicks(min, max, step),
          size: yAxisSize,
          values: (u, vals) => vals.map(fmt0),
        },
      ],
      hooks: {
        setCursor: [
          (u) => {
            if (bus.silent) return;
            const left = u.cursor.left;
            if (left != null && left >= 0) bus.cursor(u.posToVal(left, "x"));
          },
        ],
        setScale: [
          (u, key) => {
            if (key !== "x" || bus.zooming) return;
            bus.zooming = true;
            const { min, max } = u.scales.x;
            for (const other of bus.plots) if (other !== u) other.setScale("x", { min, max });
            bus.zooming = false;
          },
        ],
      },
    };
    const u = new uPlot(opts, built.data, ref.current);
    plotRef.current = u;
    bus.plots.add(u);
    if (TESTING) trace.plotAxes[big ? `big:${title}` : title] = () => ({ x: axisOf(u, 0), y: axisOf(u, 1), ySize: axisOf(u, 1).size, xSize: axisOf(u, 0).size, font: AXIS_FONT });
    if (TESTING && !big) {
      // what is drawn: per signal, t and its columns of the latest run
      for (const [name, idx] of Object.entries(built.columns)) trace.plotted[name] = [built.data[0], ...idx.map((i) => built.data[i])];
      trace.plottedSeries[title] = built.series.length - 1;
    }
    return () => {
      if (TESTING) delete trace.plotAxes[big ? `big:${title}` : title];
      if (TESTING && !big) {
        for (const name of Object.keys(built.columns)) delete trace.plotted[name];
        delete trace.plottedSeries[title];
      }
      bus.plots.delete(u);
      u.destroy();
      plotRef.current = null;
    };
  }, [built, width, height, bus, title, big]);
  const id = big ? `bigplot-${title}` : `plot-${title}`;
  return (
    <div className="kn-plot" data-testid={id}>
      <div className="kn-plot-title">
        <span className="kn-plot-name">
          {title}
          {built.unit ? <span className="kn-unit"> [{built.unit}]</span> : null}
        </span>
        <span className="kn-plot-tools">
          <button className="kn-tool" data-testid={`${id}-csv`} title="The plotted data as CSV" onClick={exportCsv}>CSV</button>
          <button className="kn-tool" data-testid={`${id}-png`} title="This plot as a PNG picture" onClick={exportPng}>PNG</button>
          <button className="kn-tool" data-testid={`${id}-svg`} title="This plot as an SVG drawing" onClick={exportSvg}>SVG</button>
          {onEnlarge ? <button className="kn-tool" data-testid={`${id}-enlarge`} title="A larger plot" onClick={onEnlarge}>⤢</button> : null}
        </span>
      </div>
      <div ref={ref} />
    </div>
  );
}

function fmt0(v) {
  if (v == null) return "";
  const a = Math.abs(v);
  if (a !== 0 && (a < 1e-3 || a >= 1e5)) return v.toExponential(1);
  return String(+v.toPrecision(6));
}

/**
 * What the plots share: their uPlot instances (zoom and cursor move together) and the time.
 * @param {(t: number) => void} cursor called when the user moves a plot's cursor to time t
 */
export function makeBus(cursor) {
  return {
    plots: new Set(),
    silent: false,
    zooming: false,
    cursor,
    // the 3-D view playing: the plots' cursors follow at most ten times a second (moving a
    // uPlot cursor redraws its legend: at every frame it would halve the 3-D frame rate), at
    // once when the last move is that long ago, so that they change in the frame the viewer's
    // time label does (one repaint of the page, not two)
    pending: null,
    timer: null,
    last: -Infinity,
    follow(t) {
      this.pending = t;
      if (this.timer) return;
      const wait = this.last + FOLLOW_MS - performance.now();
      if (wait <= 0) {
        this.last = performance.now();
        this.setTime(t);
        return;
      }
      this.timer = setTimeout(() => {
        this.timer = null;
        this.last = performance.now();
        this.setTime(this.pending);
      }, wait);
    },
    setTime(t) {
      if (TESTING) trace.plotTime = t;
      this.silent = true;
      try {
        for (const u of this.plots) {
          const left = u.valToPos(t, "x");
          if (Number.isFinite(left)) u.setCursor({ left, top: 20 }, false);
        }
      } finally {
        this.silent = false;
      }
    },
  };
}

/** What the head says of the runs plotted: the latest's name, points, whether partial, the older ones. */
function runInfo(latest, runs) {
  const one = latest.kind !== "sweep";
  return (
    latest.label +
    (one ? ` · ${latest.results.t.length} points` : "") +
    (one && latest.results.partial ? ` · partial, to t = ${Number(latest.results.partial.t_reached).toPrecision(4)} s` : "") +
    (runs.length > 1 ? ` · dashed: ${runs.slice(1, OVERLAY).map((r) => r.label).join("; ")}` : "")
  );
}

/**
 * A chip per signal, to hide or show it: in a row at the head's end while the row fits the
 * head, else folded into a "signals" button that opens them as a list (cut at the pane's
 * edge, the row hid the last chips and half of one).
 */
function SignalChips({ names, hidden, setHidden, head, height }) {
  const [folded, setFolded] = useState(false);
  const [open, setOpen] = useState(false);
  const pop = useRef(null);
  // measured as the head's size changes (a new run mounts this afresh, in a row)
  useEffect(() => {
    const el = head.current;
    if (!el) return undefined;
    let need = 0; // the head's width with the chips in a row
    let fold = false;
    const ro = new ResizeObserver(() => {
      if (!fold) {
        need = el.scrollWidth;
        fold = el.scrollWidth > el.clientWidth + 1;
      } else fold = el.clientWidth < need;
      setFolded(fold);
    });
    ro.observe(el);
    return () => ro.disconnect();
  }, [head]);
  useClickAway(pop, open, () => setOpen(false));
  const toggle = (n) =>
    setHidden((h) => {
      const next = new Set(h);
      if (next.has(n)) next.delete(n);
      else next.add(n);
      return next;
    });
  const chips = names.map((n) => (
    <button key={n} className={`kn-chip ${hidden.has(n) ? "" : "on"}`} data-testid={`plot-toggle-${n}`} title={hidden.has(n) ? "show it" : "hide it"} onClick={() => toggle(n)}>
      {n}
    </button>
  ));
  if (!folded) return <div className="kn-chips">{chips}</div>;
  return (
    <span className="kn-chips-fold" ref={pop}>
      <button className="kn-chip on" data-testid="plot-signals" aria-haspopup="true" aria-expanded={open} title="Show or hide each signal" onClick={() => setOpen(!open)}>
        signals {names.filter((n) => !hidden.has(n)).length}/{names.length} ▾
      </button>
      {open ? (
        <div className="kn-chips-pop" data-testid="plot-signals-list" style={{ maxHeight: Math.max(60, height - 4) }}>
          {chips}
        </div>
      ) : null}
    </span>
  );
}

/** "compiling 0 %" as the pane says it: "Compiling 0 %". */
function sentence(text) {
  return text.charAt(0).toUpperCase() + text.slice(1);
}

export default function Plots({ runs, bus, running, run, status }) {
  const wrap = useRef(null);
  const [width, setWidth] = useState(600);
  const [height, setHeight] = useState(300);
  const [hidden, setHidden] = useState(() => new Set());
  const [byQuantity, setByQuantity] = useState(true);
  const [enlarged, setEnlarged] = useState(null);
  const head = useRef(null);
  useEffect(() => {
    if (!wrap.current) return undefined;
    const ro = new ResizeObserver((entries) => {
      setWidth(Math.floor(entries[0].contentRect.width));
      setHeight(Math.floor(entries[0].contentRect.height));
    });
    ro.observe(wrap.current);
    return () => ro.disconnect();
  }, []);
  const latest = runs[0];
  const signals = useMemo(() => (latest ? sourcesOf(latest)[0].results.signals : []), [latest]);
  const names = useMemo(() => signals.map((s) => s.name), [signals]);
  // panels: one per quantity (every probe's angle together, as the seed paper plots them),
  // or one per signal
  const panels = useMemo(() => {
    const shown = names.filter((n) => !hidden.has(n));
    if (!byQuantity) return shown.map((n) => ({ title: n, names: [n] }));
    const groups = new Map();
    const byName = new Map(signals.map((s) => [s.name, s]));
    for (const n of shown) {
      const q = quantityOf(byName.get(n), n);
      if (!groups.has(q)) groups.set(q, []);
      groups.get(q).push(n);
    }
    return [...groups].map(([q, ns]) => ({ title: q, names: ns }));
  }, [signals, names, hidden, byQuantity]);
  const cols = width > 1000 ? 3 : width > 500 ? 2 : 1;
  const panelWidth = Math.floor((width - 12 * cols) / cols) - 8;
  // the panels fill the height they have (a title and a legend around each plot)
  const rows = Math.max(1, Math.ceil(panels.length / cols));
  // (never so short that the y axis has fewer than three ticks: the grid scrolls instead)
  const plotHeight = Math.max(110, Math.min(240, Math.floor((height - 8) / rows) - 64));
  const big = enlarged && panels.find((p) => p.title === enlarged);
  const info = latest ? runInfo(latest, runs) : "";
  return (
    <div className="kn-plots" data-testid="plots" data-runs={runs.length}>
      <div className="kn-plots-head" ref={head}>
        <span className="kn-panel-title-inline">Probes</span>
        {latest ? (
          <span className="kn-muted kn-small kn-runinfo" data-testid="plot-runs" title={info}>
            <b>{latest.label}</b>
            {info.slice(latest.label.length)}
          </span>
        ) : null}
        {latest ? (
          <button className="kn-chip on" data-testid="plot-grouping" title="one panel per quantity, or one per signal" onClick={() => setByQuantity((b) => !b)}>
            {byQuantity ? "by quantity" : "by signal"}
          </button>
        ) : null}
        <SignalChips key={latest ? `${latest.kind}-${latest.id}` : "none"} names={names} hidden={hidden} setHidden={setHidden} head={head} height={height} />
      </div>
      <div className="kn-plots-grid" ref={wrap} style={{ gridTemplateColumns: `repeat(${cols}, 1fr)` }}>
        {!latest && (
          <div className="kn-empty">
            {running ? sentence(runStatus(run)) : status || "Press Run to simulate: the probes' quantities are plotted here."}
          </div>
        )}
        {latest && names.length === 0 && <div className="kn-empty">This model has no probes: add a Probe and wire it to a port to record its quantities.</div>}
        {latest && panels.map((p) => <Panel key={p.title} title={p.title} names={p.names} runs={runs} bus={bus} width={panelWidth} height={plotHeight} onEnlarge={() => setEnlarged(p.title)} />)}
      </div>
      {big ? (
        <Modal title={`${big.title}: ${latest.label}`} onClose={() => setEnlarged(null)} testid="plot-dialog" wide>
          <Panel title={big.title} names={big.names} runs={runs} bus={bus} width={Math.round(window.innerWidth * 0.86) - 40} height={Math.round(window.innerHeight * 0.55)} big />
        </Modal>
      ) : null}
    </div>
  );
}
