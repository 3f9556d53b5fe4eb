// Probe plots (uPlot): one panel per probe quantity of the last run, chosen by chips; the
// last few runs overlaid (older ones dashed and faded), each named by what differed; a
// sweep's members overlaid, each named by its values; drag to zoom (all panels follow),
// double-click to zoom out; the cursor shows values and moves the 3-D view in time.
import { useEffect, useMemo, useRef, useState } from "react";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { OVERLAY } from "./hooks/useRun.js";
import { memberLabel } from "./runs.js";
import { TESTING, trace } from "./testing.js";

const COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf", "#8c564b", "#e377c2", "#7f7f7f"];
const AXES = ["x", "y", "z"];

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
  const series = [{ label: "t [s]", value: (u, v) => (v == null ? "–" : v.toFixed(3)) }];
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
  const latest = sources.filter((src) => src.r === 0).length;
  const latestCount = Object.values(columns).reduce((a, c) => a + c.length, 0) * latest;
  return { series, data, unit, columns, latestCount };
}

function Panel({ title, names, runs, bus, width, height }) {
  const ref = useRef(null);
  const plotRef = useRef(null);
  const built = useMemo(() => buildData(names, runs), [names, runs]);
  useEffect(() => {
    if (!ref.current || width < 50) return undefined;
    const opts = {
      width: Math.max(200, width),
      height,
      scales: { x: { time: false } },
      series: built.series,
      legend: { show: true, live: true },
      cursor: {
        sync: { key: "kn-plots", setSeries: false },
        drag: { x: true, y: false, setScale: true },
        points: { size: 5 },
      },
      axes: [
        { stroke: "#555", grid: { stroke: "#eceef1" }, ticks: { stroke: "#ccc" }, size: 30 },
        { stroke: "#555", grid: { stroke: "#eceef1" }, ticks: { stroke: "#ccc" }, size: 52, values: (u, vals) => vals.map(fmt0) },
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
    // the legend lists the latest run; older runs are drawn dashed (named in the header)
    u.root.querySelectorAll(".u-legend .u-series").forEach((row, i) => {
      if (i > built.latestCount) /** @type {HTMLElement} */ (row).style.display = "none";
    });
    bus.plots.add(u);
    if (TESTING) {
      // what is drawn: per signal, t and its columns of the latest run
      for (const [name, idx] of Object.entries(built.columns)) trace.plotted[name] = [built.data[0], ...idx.map((i) => built.data[i])];
      trace.plottedSeries[title] = built.series.length - 1;
    }
    return () => {
      if (TESTING) {
        for (const name of Object.keys(built.columns)) delete trace.plotted[name];
        delete trace.plottedSeries[title];
      }
      bus.plots.delete(u);
      u.destroy();
      plotRef.current = null;
    };
  }, [built, width, height, bus, title]);
  return (
    <div className="kn-plot" data-testid={`plot-${title}`}>
      <div className="kn-plot-title">
        {title}
        {built.unit ? <span className="kn-unit"> [{built.unit}]</span> : null}
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
    // uPlot cursor redraws its legend: at every frame it would halve the 3-D frame rate)
    pending: null,
    timer: null,
    follow(t) {
      this.pending = t;
      if (this.timer) return;
      this.timer = setTimeout(() => {
        this.timer = null;
        this.setTime(this.pending);
      }, 100);
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

export default function Plots({ runs, bus, running, progress, status }) {
  const wrap = useRef(null);
  const [width, setWidth] = useState(600);
  const [height, setHeight] = useState(300);
  const [hidden, setHidden] = useState(() => new Set());
  const [byQuantity, setByQuantity] = useState(true);
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
  const plotHeight = Math.max(80, Math.min(240, Math.floor((height - 8) / rows) - 64));
  return (
    <div className="kn-plots" data-testid="plots" data-runs={runs.length}>
      <div className="kn-plots-head">
        <span className="kn-panel-title-inline">Probes</span>
        {latest ? (
          <span className="kn-muted kn-small kn-runinfo" data-testid="plot-runs">
            <b>{latest.label}</b>
            {latest.kind !== "sweep" ? ` · ${latest.results.t.length} points` : ""}
            {latest.kind !== "sweep" && latest.results.partial ? ` · partial, to t = ${Number(latest.results.partial.t_reached).toPrecision(4)} s` : ""}
            {runs.length > 1 ? ` · dashed: ${runs.slice(1, OVERLAY).map((r) => r.label).join("; ")}` : ""}
          </span>
        ) : null}
        {latest ? (
          <button className="kn-chip on" data-testid="plot-grouping" title="one panel per quantity, or one per signal" onClick={() => setByQuantity((b) => !b)}>
            {byQuantity ? "by quantity" : "by signal"}
          </button>
        ) : null}
        <div className="kn-chips">
          {names.map((n) => (
            <button
              key={n}
              className={`kn-chip ${hidden.has(n) ? "" : "on"}`}
              data-testid={`plot-toggle-${n}`}
              title={hidden.has(n) ? "show it" : "hide it"}
              onClick={() =>
                setHidden((h) => {
                  const next = new Set(h);
                  if (next.has(n)) next.delete(n);
                  else next.add(n);
                  return next;
                })
              }
            >
              {n}
            </button>
          ))}
        </div>
      </div>
      <div className="kn-plots-grid" ref={wrap} style={{ gridTemplateColumns: `repeat(${cols}, 1fr)` }}>
        {!latest && (
          <div className="kn-empty">
            {running ? `Running… ${Math.round((progress || 0) * 100)} %` : status || "Press Run to simulate: the probes' quantities are plotted here."}
          </div>
        )}
        {latest && names.length === 0 && <div className="kn-empty">This model has no probes: add a Probe and wire it to a port to record its quantities.</div>}
        {latest && panels.map((p) => <Panel key={p.title} title={p.title} names={p.names} runs={runs} bus={bus} width={panelWidth} height={plotHeight} />)}
      </div>
    </div>
  );
}
