// The diagram: React Flow in loose connection mode (any port to any port; the domain rule
// decides), blocks placed from the palette by drag and drop. The document says where blocks
// are and what is selected; while the mouse drags, React Flow's positions are shown, and the
// drop commits them to the model (one undo step).
import { useCallback, useEffect, useMemo, useRef, useState } from "react";
import { Background, ConnectionMode, MiniMap, ReactFlow, useNodesInitialized, useReactFlow, useStoreApi } from "@xyflow/react";
import BlockNode from "./BlockNode.jsx";
import PortNode from "./PortNode.jsx";
import WireEdge from "./WireEdge.jsx";
import { GRID, SCALE } from "./model.js";
import { covers, diagramExtent, fitViewport, minimapBox } from "./fit.js";
import { studio, useStudio } from "./store.js";
import { edgeData } from "./hooks/useEditing.js";
import { useWires } from "./hooks/useWires.js";
import { TESTING, trace } from "./testing.js";

const nodeTypes = { block: BlockNode, extport: PortNode };
const edgeTypes = { wire: WireEdge };
export const DRAG_MIME = "application/x-kinetwork-type";
/** A right button released this close to where it went down opens the menu (else it panned). */
const CLICK_SLOP = 5;
/** The minimap by itself only where it leaves the diagram room: it covered half of a small canvas. */
const MINIMAP_ROOM = { width: 700, height: 380 };
const MIN_ZOOM = 0.1;
const MINIMAP = { width: 140, height: 90 };
const FIT_MAX_ZOOM = 1.1;

function sameList(a, b) {
  return a.length === b.length && a.every((x, i) => x === b[i]);
}

/**
 * @param {{nodes: any[], edges: any[], placed: boolean, edit: import("./hooks/useEditing.js").Edit}} props
 */
export default function Canvas({ nodes: nodesIn, edges: edgesIn, placed, edit }) {
  const flow = useReactFlow();
  const rf = useStoreApi();
  const selection = useStudio((s) => s.selection);
  const selectedEdges = useStudio((s) => s.selectedEdges);
  const fitRequest = useStudio((s) => s.fitRequest);
  // what React Flow holds while the mouse works: positions being dragged, measured sizes
  const [dragPos, setDragPos] = useState({});
  const [measured, setMeasured] = useState({});
  const box = useRef(null);
  const [roomy, setRoomy] = useState(true);
  const minimap = useStudio((s) => s.minimap);
  const mapClear = useStudio((s) => s.mapClear);
  // the minimap's corner free of blocks in the view last fitted
  const [cornerFree, setCornerFree] = useState(true);
  useEffect(() => studio().setMapClear(roomy && cornerFree), [roomy, cornerFree]);
  // the view the last fit set: while the user has not moved it, the pane's new size refits
  const fittedView = useRef(null);
  const refit = useRef(() => {});
  useEffect(() => {
    if (!box.current) return undefined;
    let frame = 0;
    const ro = new ResizeObserver((entries) => {
      const r = entries[0].contentRect;
      setRoomy(r.width >= MINIMAP_ROOM.width && r.height >= MINIMAP_ROOM.height);
      cancelAnimationFrame(frame);
      frame = requestAnimationFrame(() => refit.current());
    });
    ro.observe(box.current);
    return () => {
      cancelAnimationFrame(frame);
      ro.disconnect();
    };
  }, []);

  const nodes = useMemo(() => {
    const chosen = new Set(selection);
    return nodesIn.map((n) => {
      const out = { ...n, selected: chosen.has(n.id), position: dragPos[n.id] || n.position };
      return measured[n.id] ? { ...out, measured: measured[n.id] } : out;
    });
  }, [nodesIn, selection, dragPos, measured]);

  // wires routed around the blocks where they are shown, again as a block is dragged; the
  // view fitted to a model just opened is fitted again when its wires are routed (they may
  // run round the outside of the blocks), unless the user has moved it meanwhile
  const fitWires = useRef(false);
  const lastRouted = useRef(null);
  const onRouted = useCallback((out) => {
    lastRouted.current = out;
    if (!fitWires.current) return;
    fitWires.current = false;
    refit.current();
    if (TESTING) trace.fit = { ...trace.fit, wires: false };
  }, []);
  const routed = useWires(nodes, edgesIn, placed, onRouted);
  const edges = useMemo(() => {
    const chosen = new Set(selectedEdges);
    return routed.map((e) => (chosen.has(e.id) ? { ...e, selected: true } : e));
  }, [routed, selectedEdges]);

  // a selection set by the studio (not by a box): React Flow's box over the last one goes,
  // or it would take the clicks (a double-click on a block made a subsystem did nothing)
  const own = useRef(false);
  useEffect(() => {
    if (own.current) own.current = false;
    else rf.setState({ nodesSelectionActive: false });
  }, [selection, rf]);

  const onNodesChange = useCallback((changes) => {
    let drag = null;
    let sizes = null;
    let picked = null;
    for (const c of changes) {
      if (c.type === "position" && c.position) (drag = drag || {})[c.id] = c.position;
      else if (c.type === "dimensions" && c.dimensions) (sizes = sizes || {})[c.id] = c.dimensions;
      else if (c.type === "select") (picked = picked || new Map()).set(c.id, c.selected);
    }
    if (drag) setDragPos((d) => ({ ...d, ...drag }));
    if (sizes) setMeasured((m) => ({ ...m, ...sizes }));
    if (picked) {
      const now = studio().selection;
      const next = [...now.filter((id) => picked.get(id) !== false), ...[...picked].filter(([id, on]) => on && !now.includes(id)).map(([id]) => id)];
      if (!sameList(now, next)) {
        own.current = true;
        studio().select(next, studio().selectedEdges);
      }
    }
  }, []);

  const onEdgesChange = useCallback((changes) => {
    const picked = changes.filter((c) => c.type === "select");
    if (!picked.length) return;
    const now = studio().selectedEdges;
    const on = new Set(now);
    for (const c of picked) {
      if (c.selected) on.add(c.id);
      else on.delete(c.id);
    }
    const next = [...on];
    if (!sameList(now, next)) {
      own.current = true;
      studio().select(studio().selection, next);
    }
  }, []);

  const onNodeDragStop = useCallback(
    (_event, _node, dragged) => {
      const moved = {};
      for (const n of dragged || []) moved[n.id] = { x: Math.round(n.position.x / SCALE), y: Math.round(n.position.y / SCALE) };
      edit.moved(moved);
      setDragPos({});
    },
    [edit],
  );

  // the whole diagram in view, clear of the zoom buttons and the minimap: its blocks, what
  // stands out of them (ports, their names) and its wires
  const fit = useCallback(() => {
    const pane = box.current;
    const shown = flow.getNodes();
    if (!pane || !shown.length) return;
    const size = { width: pane.clientWidth, height: pane.clientHeight };
    const blocks = shown.map((n) => ({ x: n.position.x, y: n.position.y, width: n.measured?.width ?? 0, height: n.measured?.height ?? 0 }));
    const at = pane.getBoundingClientRect();
    const now = flow.getViewport();
    // the parts of the blocks drawn outside their boxes, from the page (diagram coordinates)
    const parts = [...pane.querySelectorAll(".react-flow__node .kn-port, .react-flow__node .kn-port-label, .react-flow__node .kn-block-badge")].map((el) => {
      const r = el.getBoundingClientRect();
      return { x: (r.left - at.left - now.x) / now.zoom, y: (r.top - at.top - now.y) / now.zoom, width: r.width / now.zoom, height: r.height / now.zoom };
    });
    const wires = flow.getEdges().map((e) => /** @type {any} */ (e.data)?.points || []);
    const extent = diagramExtent(flow.getNodesBounds(shown), parts.filter((r) => r.width > 0 && r.height > 0), wires);
    const view = fitViewport(extent, size, [], FIT_MAX_ZOOM, MIN_ZOOM);
    flow.setViewport(view, { duration: 0 });
    fittedView.current = flow.getViewport();
    if (TESTING) trace.fit = { ...trace.fit, pane: [size.width, size.height] };
    // the minimap by itself only where it hides no block and no wire
    const segments = wires.flatMap((pts) => pts.slice(1).map((q, i) => {
      const p = pts[i];
      return { x: Math.min(p.x, q.x) - 2, y: Math.min(p.y, q.y) - 2, width: Math.abs(q.x - p.x) + 4, height: Math.abs(q.y - p.y) + 4 };
    }));
    setCornerFree(!covers(view, [...blocks, ...segments], minimapBox(size, MINIMAP)));
  }, [flow]);
  useEffect(() => {
    refit.current = () => {
      const was = fittedView.current;
      const now = flow.getViewport();
      if (was && now.x === was.x && now.y === was.y && now.zoom === was.zoom) fit();
    };
  }, [flow, fit]);

  // fit the view to a model just opened, once its blocks are measured
  const initialized = useNodesInitialized();
  const fitted = useRef(0);
  useEffect(() => {
    if (!fitRequest || fitted.current === fitRequest || !initialized || !nodes.length || !placed) return undefined;
    const id = requestAnimationFrame(() => {
      fit();
      fitted.current = fitRequest;
      // the wires drawn are not yet those of this diagram: fit again when they are
      fitWires.current = lastRouted.current !== routed;
      if (TESTING) trace.fit = { ...trace.fit, request: fitRequest, wires: fitWires.current };
    });
    return () => cancelAnimationFrame(id);
  }, [fitRequest, initialized, nodes, placed, fit, routed]);

  const isValidConnection = useCallback((c) => edit.checkConnection(`${c.source}.${c.sourceHandle}`, `${c.target}.${c.targetHandle}`) === null, [edit]);
  const onConnect = useCallback((c) => edit.connect(`${c.source}.${c.sourceHandle}`, `${c.target}.${c.targetHandle}`), [edit]);
  const onConnectEnd = useCallback(
    (_event, state) => {
      if (!state || state.isValid !== false || !state.toHandle || !state.fromHandle) return;
      const a = `${state.fromHandle.nodeId}.${state.fromHandle.id}`;
      const b = `${state.toHandle.nodeId}.${state.toHandle.id}`;
      if (a === b) return; // a click on a handle
      const why = edit.checkConnection(a, b);
      if (why) studio().toast(why);
    },
    [edit],
  );

  const onDragOver = useCallback((e) => {
    if (e.dataTransfer.types.includes(DRAG_MIME)) {
      e.preventDefault();
      e.dataTransfer.dropEffect = "copy";
    }
  }, []);
  const onDrop = useCallback(
    (e) => {
      const type = e.dataTransfer.getData(DRAG_MIME);
      if (!type) return;
      e.preventDefault();
      const p = flow.screenToFlowPosition({ x: e.clientX, y: e.clientY });
      edit.place(type, { x: p.x - 58, y: p.y - 32 });
    },
    [flow, edit],
  );

  // the pointer's place, where Ctrl+V pastes
  const onMouseMove = useCallback(
    (e) => {
      const p = flow.screenToFlowPosition({ x: e.clientX, y: e.clientY });
      studio().setPointer({ x: p.x / SCALE, y: p.y / SCALE });
    },
    [flow],
  );
  const onMouseLeave = useCallback(() => studio().setPointer(null), []);

  // the right-click menu: opened on a click of the right button, not after it panned
  const rightDown = useRef(null);
  const onMouseDownCapture = useCallback((e) => {
    if (e.button === 2) rightDown.current = { x: e.clientX, y: e.clientY };
  }, []);
  const openMenu = useCallback((e, target) => {
    e.preventDefault();
    const down = rightDown.current;
    if (down && Math.hypot(e.clientX - down.x, e.clientY - down.y) > CLICK_SLOP) return;
    const p = flow.screenToFlowPosition({ x: e.clientX, y: e.clientY });
    if (target.kind === "node" && !studio().selection.includes(target.id)) studio().select([target.id]);
    studio().setMenu({ x: e.clientX, y: e.clientY, at: { x: p.x / SCALE, y: p.y / SCALE }, target });
  }, [flow]);
  const onNodeContextMenu = useCallback((e, node) => openMenu(e, { kind: node.type === "extport" ? "port" : "node", id: node.id }), [openMenu]);
  const onPaneContextMenu = useCallback((e) => openMenu(e, { kind: "pane" }), [openMenu]);
  const onSelectionContextMenu = useCallback((e) => openMenu(e, { kind: "selection" }), [openMenu]);
  const onEdgeContextMenu = useCallback((e, edge) => openMenu(e, { kind: "edge", id: edge.id, data: edgeData(edge.id) }), [openMenu]);
  const onPaneClick = useCallback(() => studio().setMenu(null), []);

  const onNodeDoubleClick = useCallback((_e, node) => edit.open(node.id), [edit]);

  return (
    <div
      className="kn-canvas"
      ref={box}
      data-testid="canvas"
      onDragOver={onDragOver}
      onDrop={onDrop}
      onMouseMove={onMouseMove}
      onMouseLeave={onMouseLeave}
      onMouseDownCapture={onMouseDownCapture}
    >
      <ReactFlow
        nodes={nodes}
        edges={edges}
        nodeTypes={nodeTypes}
        edgeTypes={edgeTypes}
        onNodesChange={onNodesChange}
        onEdgesChange={onEdgesChange}
        onNodeDragStop={onNodeDragStop}
        onConnect={onConnect}
        onConnectEnd={onConnectEnd}
        isValidConnection={isValidConnection}
        onNodeDoubleClick={onNodeDoubleClick}
        onNodeContextMenu={onNodeContextMenu}
        onPaneContextMenu={onPaneContextMenu}
        onSelectionContextMenu={onSelectionContextMenu}
        onEdgeContextMenu={onEdgeContextMenu}
        onPaneClick={onPaneClick}
        connectionMode={ConnectionMode.Loose}
        snapToGrid
        snapGrid={[GRID, GRID]}
        selectionOnDrag
        panOnDrag={[1, 2]}
        selectionKeyCode={null}
        multiSelectionKeyCode={["Meta", "Control", "Shift"]}
        deleteKeyCode={null}
        disableKeyboardA11y
        zoomOnDoubleClick={false}
        minZoom={MIN_ZOOM}
        maxZoom={3}
        connectionRadius={18}
        proOptions={{ hideAttribution: true }}
      >
        <Background gap={GRID * 2} size={1} color="#d4d8de" />
        {(minimap ?? mapClear) ? (
          <MiniMap pannable zoomable nodeStrokeWidth={2} nodeColor={(n) => (/** @type {any} */ (n.data).problems?.length ? "#e05555" : "#c9ced6")} style={{ width: MINIMAP.width, height: MINIMAP.height }} />
        ) : null}
      </ReactFlow>
    </div>
  );
}
