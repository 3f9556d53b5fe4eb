// The studio: palette | diagram | parameters, with the probe plots and the 3-D view below.
// State is in the store (store.js); the work is in hooks/ (files, definitions, validation,
// runs, editing, keys); this component puts the pieces on the page.
import { useCallback, useEffect, useMemo, useRef, useState } from "react";
import { useReactFlow } from "@xyflow/react";
import { api, EXAMPLE, OPEN } from "./api.js";
import Canvas from "./Canvas.jsx";
import { findRepeat } from "./fold.js";
import ContextMenu from "./ContextMenu.jsx";
import { ChoiceDialog, OpenDialog, PromptDialog } from "./Dialogs.jsx";
import Palette from "./Palette.jsx";
import ParamPanel from "./ParamPanel.jsx";
import JsonView from "./JsonView.jsx";
import AnalysisPanel from "./AnalysisPanel.jsx";
import Plots, { makeBus } from "./Plots.jsx";
import Problems from "./Problems.jsx";
import { SPLITTER, paneSize, usePanes } from "./panes.js";
import Splitter from "./Splitter.jsx";
import Toolbar from "./Toolbar.jsx";
import Viewer from "./Viewer.jsx";
import { useDefinitions, useDefinitionTypes, useScope } from "./hooks/useDefinitions.js";
import { useDiagram } from "./hooks/useDiagram.js";
import { useEditing } from "./hooks/useEditing.js";
import { openModel, useFiles } from "./hooks/useFiles.js";
import { useKeyboard } from "./hooks/useKeyboard.js";
import { useRun } from "./hooks/useRun.js";
import { useScopeProblems, useValidation } from "./hooks/useValidation.js";
import { cursorSinceRun, studio, useStudio } from "./store.js";
import { TESTING, trace } from "./testing.js";

const PANELS = [
  ["params", "Parameters"],
  ["json", "JSON"],
  ["analysis", "Analysis"],
];

// One studio a page: the 3-D viewer shown, and the plots' bus (the plot cursor moves it)
let viewerShown = null;
const bus = makeBus((t) => {
  studio().setTime(t);
  cursorSinceRun.t = t;
  if (TESTING) trace.cursorTime = t;
  if (viewerShown) viewerShown.setTime(t);
});
if (TESTING) trace.bus = bus;

/** What the 3-D view shows of run ``run``: its animation, or the note saying why there is
 * none (yet: its results came ahead of it, ``views``). */
function viewOf(run, views) {
  if (!run) return { animation: null, note: null };
  const results = run.results;
  if (!results.animation_pending) return { animation: results.animation || null, note: results.animation_note || null };
  return views[run.id] || { animation: null, note: "The 3-D view is on its way…" };
}

function onViewer(v) {
  viewerShown = v;
  // a view that came after its plots: where their cursor has been put meanwhile
  if (v && cursorSinceRun.t != null) v.setTime(cursorSinceRun.t);
  if (TESTING) trace.viewer = v;
}

/** The palette and the server's facts, once. */
function useServerFacts() {
  useEffect(() => {
    api
      .palette()
      .then((p) => {
        const types = {};
        for (const lib of p.libraries) for (const t of lib.types) types[t.type] = t;
        useStudio.setState({ palette: { libraries: p.libraries, types } });
        if (TESTING) trace.timings.paletteReady = performance.now();
      })
      .catch((e) => studio().toast(`The palette could not be loaded: ${e.message}`));
    api
      .facts()
      .then((facts) => useStudio.setState({ facts }))
      .catch((e) => studio().toast(`The studio's settings could not be loaded: ${e.message}`));
  }, []);
}

/** How the diagram is worked, above it: elided where the bar is short, whole in its title. */
const HINT = "drag from the palette · wire port to port · box-select by dragging · right-click for more · wheel zooms, right-drag pans · arrows move · Del · Ctrl+Z/Y · Ctrl+A/C/V/D";

function Breadcrumbs() {
  const name = useStudio((s) => s.hist.present.name);
  const scopes = useStudio((s) => s.scopes);
  const setScopes = useStudio((s) => s.setScopes);
  return (
    <div className="kn-crumbs" data-testid="breadcrumb">
      <button className={`kn-crumb ${scopes.length ? "" : "here"}`} data-testid="crumb-0" onClick={() => setScopes([])}>
        {name}
      </button>
      {scopes.map((s, i) => (
        <span key={i}>
          <span className="kn-crumb-sep">›</span>
          <button className={`kn-crumb ${i === scopes.length - 1 ? "here" : ""}`} data-testid={`crumb-${i + 1}`} onClick={() => setScopes(scopes.slice(0, i + 1))}>
            {s}
          </button>
        </span>
      ))}
      <span className="kn-muted kn-small kn-hint" title={HINT}>
        {HINT}
      </span>
      <ViewTools />
    </div>
  );
}

/**
 * Zoom, fit and the minimap, in the bar above the diagram: floating over its corners they
 * covered blocks. The minimap shows by itself only where it covers none in the fitted view.
 */
function ViewTools() {
  const flow = useReactFlow();
  const fit = useStudio((s) => s.fit);
  const minimap = useStudio((s) => s.minimap);
  const mapClear = useStudio((s) => s.mapClear);
  const setMinimap = useStudio((s) => s.setMinimap);
  const shown = minimap ?? mapClear;
  return (
    <span className="kn-view-tools">
      <button className="kn-tool" data-testid="zoom-out" title="Zoom out" onClick={() => flow.zoomOut({ duration: 0 })}>−</button>
      <button className="kn-tool" data-testid="zoom-in" title="Zoom in" onClick={() => flow.zoomIn({ duration: 0 })}>+</button>
      <button className="kn-tool" data-testid="fit-view" title="The whole diagram" onClick={fit}>fit</button>
      <button className={`kn-tool${shown ? " kn-on" : ""}`} data-testid="minimap-toggle" title={shown ? "Hide the minimap" : "Show the minimap"} onClick={() => setMinimap(!shown)}>
        map
      </button>
    </span>
  );
}

/** Unsaved work of an earlier session, offered back above the diagram (not in its way). */
function RecoveryBar() {
  const offer = useStudio((s) => s.offer);
  if (!offer) return null;
  return (
    <div className="kn-offer" data-testid="recovery" role="alert">
      <span>{offer.message}</span>
      <button className="kn-btn kn-primary" data-testid="choice-recover" onClick={offer.recover}>
        Recover them
      </button>
      <button className="kn-btn" data-testid="choice-discard" onClick={offer.discard}>
        Discard them
      </button>
    </div>
  );
}

/** Blocks a fold must take off the diagram before the studio offers it unasked. */
const FOLD_OFFER = 24;

/**
 * A long repeated pattern (a chain of 32 links) offered folded into subsystems, in a bar
 * above the diagram (over it, it hid the top row), until folded or dismissed.
 * @param {{scope: any, edit: import("./hooks/useEditing.js").Edit}} props
 */
function FoldOffer({ scope, edit }) {
  const repeat = useMemo(() => findRepeat(scope.body), [scope.body]);
  const file = useStudio((s) => s.file);
  const [dismissed, setDismissed] = useState(() => new Set());
  const key = `${file.path || file.example || ""}|${scope.scopeKey}`;
  if (!repeat || repeat.n * (repeat.p - 1) < FOLD_OFFER || dismissed.has(key)) return null;
  const kinds = repeat.units[0].map((c) => String(c.type).split(".").pop()).join(" + ");
  return (
    <div className="kn-fold-offer" data-testid="fold-offer" role="status">
      <span>
        {repeat.n} alike units ({kinds}): fold each into a subsystem to read the diagram at a normal zoom?
      </span>
      <button className="kn-btn kn-primary" data-testid="fold-accept" onClick={() => edit.fold()}>
        Fold
      </button>
      <button className="kn-btn" data-testid="fold-dismiss" onClick={() => setDismissed(new Set([...dismissed, key]))}>
        Not now
      </button>
    </div>
  );
}

function Toasts() {
  const toasts = useStudio((s) => s.toasts);
  const dismiss = useStudio((s) => s.dismiss);
  return (
    <div className="kn-toasts">
      {toasts.map((t) => (
        <div key={t.id} className={`kn-toast ${t.kind}`} data-testid="toast" onClick={() => dismiss(t.id)}>
          {t.message}
        </div>
      ))}
    </div>
  );
}

function Dialog() {
  const dialog = useStudio((s) => s.dialog);
  const setDialog = useStudio((s) => s.setDialog);
  if (!dialog) return null;
  if (dialog.kind === "open") return <OpenDialog onOpen={(src) => openModel(src)} onClose={() => setDialog(null)} />;
  if (dialog.kind === "prompt") return <PromptDialog {...dialog} />;
  if (dialog.kind === "choice") return <ChoiceDialog {...dialog} />;
  return null;
}

/**
 * The size of an element, as it changes.
 * @returns {[import("react").RefObject<any>, {width: number, height: number}]}
 */
function useSize() {
  const ref = useRef(null);
  const [size, setSize] = useState({ width: window.innerWidth, height: window.innerHeight });
  useEffect(() => {
    if (!ref.current) return undefined;
    const ro = new ResizeObserver((entries) => {
      const r = entries[0].contentRect;
      setSize({ width: Math.round(r.width), height: Math.round(r.height) });
    });
    ro.observe(ref.current);
    return () => ro.disconnect();
  }, []);
  return [ref, size];
}

/** The panes' sizes on screen (px), from what the user chose and the room there is. */
function usePaneSizes(main, center) {
  const state = usePanes();
  const side = paneSize("side", state, main.width);
  const palette = paneSize("palette", state, main.width, side + 2 * SPLITTER);
  const centerWidth = main.width - side - palette - 2 * SPLITTER;
  // the results share the centre's height with the diagram (the crumbs' 30 px above)
  const results = paneSize("results", state, center.height - 30 - SPLITTER);
  const viewer = paneSize("viewer", state, centerWidth - SPLITTER);
  return { palette, side, results, viewer };
}

export default function App() {
  useServerFacts();
  useDefinitions();
  useValidation();
  const files = useFiles(OPEN, EXAMPLE);
  const scope = useScope();
  const { places, here, byBlock } = useScopeProblems(scope.scope);
  const diagram = useDiagram(scope, byBlock, here);
  const edit = useEditing(scope, diagram.exposed);
  const runner = useRun();
  useKeyboard(edit, files);

  const palette = useStudio((s) => s.palette);
  const validationOk = useStudio((s) => s.validation.ok);
  const runs = useStudio((s) => s.runs);
  const views = useStudio((s) => s.views);
  const run = useStudio((s) => s.run);
  const panel = useStudio((s) => s.panel);
  const setPanel = useStudio((s) => s.setPanel);
  const definitions = useDefinitionTypes();


  // plots drawn: the time from Run to results on screen
  useEffect(() => {
    if (!TESTING || !runs.length) return undefined;
    const id = requestAnimationFrame(() => {
      trace.timings.plotted = performance.now();
      if (trace.timings.runClicked) trace.timings.runToPlot = (trace.timings.plotted - trace.timings.runClicked) / 1000;
    });
    return () => cancelAnimationFrame(id);
  }, [runs]);

  const goTo = useCallback((p) => {
    const s = studio();
    const target = p.scope ? [p.scope] : [];
    if (target.join("/") !== s.scopes.join("/")) s.setScopes(target);
    if (p.component) {
      s.select([p.component]);
      s.setPanel("params");
    }
  }, []);

  const latest = runs[0];
  const shown = latest && latest.kind !== "sweep" ? latest : runs.find((r) => r.kind !== "sweep");
  const shownView = viewOf(shown, views);
  const placed = (scope.body.components || []).every((c) => scope.posOf(c.name));
  const going = runner.going;
  const [mainRef, mainSize] = useSize();
  const [centerRef, centerSize] = useSize();
  const sizes = usePaneSizes(mainSize, centerSize);
  const closed = usePanes((s) => s.closed);
  return (
    <div className="kn-app">
      <Toolbar files={files} edit={edit} runner={runner} onOpen={() => studio().setDialog({ kind: "open" })} />
      <div
        className="kn-main"
        ref={mainRef}
        style={{ gridTemplateColumns: `${sizes.palette}px ${SPLITTER}px minmax(0, 1fr) ${SPLITTER}px ${sizes.side}px` }}
      >
        {closed.palette ? <div /> : <Palette palette={palette} definitions={definitions} onAdd={edit.placeAtCentre} />}
        <Splitter pane="palette" axis="x" side="before" size={sizes.palette} label="Palette" />
        <div className="kn-center" ref={centerRef} style={{ gridTemplateRows: `auto 30px minmax(0, 1fr) ${SPLITTER}px ${sizes.results}px` }}>
          {/* a row of the centre's grid, always there, empty when nothing is offered */}
          <div className="kn-bars">
            <RecoveryBar />
            <FoldOffer scope={scope} edit={edit} />
          </div>
          <Breadcrumbs />
          <Canvas nodes={diagram.nodes} edges={diagram.edges} placed={placed} edit={edit} />
          <Splitter pane="results" axis="y" side="after" size={sizes.results} label="Plots and 3-D view" />
          <div className="kn-results" style={{ gridTemplateColumns: `minmax(0, 1fr) ${SPLITTER}px ${sizes.viewer}px` }}>
            {closed.results ? null : (
              <>
                <Plots runs={runs} bus={bus} running={going} run={run} status={run && run.state === "failed" ? `The run failed: ${run.error}` : null} />
                <Splitter pane="viewer" axis="x" side="after" size={sizes.viewer} label="3-D view" />
                {closed.viewer ? (
                  <div />
                ) : (
                  <Viewer
                    key={shown ? `${shown.kind}-${shown.id}` : "none"}
                    animation={shown ? shownView.animation : null}
                    reason={shown ? shownView.note : null}
                    bus={bus}
                    onViewer={onViewer}
                  />
                )}
              </>
            )}
          </div>
        </div>
        <Splitter pane="side" axis="x" side="after" size={sizes.side} label="Side panel" />
        {closed.side ? <div /> : <div className="kn-right">
          <div className="kn-tabs" role="tablist">
            {PANELS.map(([id, label]) => (
              <button key={id} role="tab" aria-selected={panel === id} className={`kn-tab ${panel === id ? "on" : ""}`} data-testid={`tab-${id}`} onClick={() => setPanel(id)}>
                {label}
              </button>
            ))}
          </div>
          {panel === "params" ? <ParamPanel scope={scope} edit={edit} byBlock={byBlock} here={here} /> : null}
          {panel === "json" ? <JsonView /> : null}
          {panel === "analysis" ? <AnalysisPanel runner={runner} scope={scope} /> : null}
          <Problems places={places} ok={validationOk} onGo={goTo} />
        </div>}
      </div>
      <ContextMenu edit={edit} scope={scope} />
      <Toasts />
      <Dialog />
    </div>
  );
}
