// The diagram: React Flow in loose connection mode (any port to any port; the domain rule
// decides), blocks placed from the palette by drag and drop, positions committed on drop.
import { useCallback, useEffect, useMemo, useRef, useState } from "react";
import {
  Background,
  ConnectionMode,
  Controls,
  MiniMap,
  ReactFlow,
  applyEdgeChanges,
  applyNodeChanges,
  useNodesInitialized,
  useReactFlow,
} from "@xyflow/react";
import BlockNode from "./BlockNode.jsx";
import PortNode from "./PortNode.jsx";
import { GRID, SCALE } from "./model.js";

const nodeTypes = { block: BlockNode, extport: PortNode };
export const DRAG_MIME = "application/x-kinetwork-type";

export default function Canvas({
  nodesIn,
  edgesIn,
  selectRequest,
  fitRequest,
  placed,
  checkConnection,
  onConnectPorts,
  onRefused,
  onMoved,
  onDelete,
  onDropType,
  onOpenNode,
  onSelection,
}) {
  const [nodes, setNodes] = useState([]);
  const [edges, setEdges] = useState([]);
  const dragging = useRef(false);
  const applied = useRef(null);
  const flow = useReactFlow();

  // the document's nodes, keeping what React Flow holds of its own (selection, a drag)
  useEffect(() => {
    setNodes((prev) => {
      const old = new Map(prev.map((n) => [n.id, n]));
      // a request to select is applied once; after that, React Flow's selection holds
      const fresh = selectRequest && selectRequest !== applied.current;
      applied.current = selectRequest;
      const want = fresh ? new Set(selectRequest.names) : null;
      return nodesIn.map((n) => {
        const o = old.get(n.id);
        const selected = want ? want.has(n.id) : o ? !!o.selected : false;
        const position = dragging.current && o ? o.position : n.position;
        return o && o.measured ? { ...n, position, selected, measured: o.measured } : { ...n, position, selected };
      });
    });
  }, [nodesIn, selectRequest]);

  useEffect(() => {
    setEdges((prev) => {
      const old = new Map(prev.map((e) => [e.id, e]));
      return edgesIn.map((e) => ({ ...e, selected: old.has(e.id) ? !!old.get(e.id).selected : false }));
    });
  }, [edgesIn]);

  // fit the view to a model just opened, once its blocks are measured
  const initialized = useNodesInitialized();
  const pendingFit = useRef(0);
  useEffect(() => {
    if (fitRequest) pendingFit.current = fitRequest;
  }, [fitRequest]);
  useEffect(() => {
    if (!pendingFit.current || !initialized || !nodes.length || !placed) return undefined;
    if (nodes.length !== nodesIn.length || nodes.some((n, i) => n.id !== nodesIn[i].id)) return undefined;
    const id = requestAnimationFrame(() => {
      flow.fitView({ padding: 0.15, maxZoom: 1.1, duration: 0 });
      pendingFit.current = 0;
    });
    return () => cancelAnimationFrame(id);
  }, [fitRequest, initialized, nodes, nodesIn, placed, flow]);

  const onNodesChange = useCallback((changes) => {
    setNodes((ns) => applyNodeChanges(changes, ns));
  }, []);
  const onEdgesChange = useCallback((changes) => setEdges((es) => applyEdgeChanges(changes, es)), []);

  const onNodeDragStart = useCallback(() => {
    dragging.current = true;
  }, []);
  const onNodeDragStop = useCallback(
    (_event, _node, dragged) => {
      dragging.current = false;
      const moved = {};
      for (const n of dragged || []) {
        moved[n.id] = { x: Math.round(n.position.x / SCALE), y: Math.round(n.position.y / SCALE) };
      }
      onMoved(moved);
    },
    [onMoved],
  );

  const isValidConnection = useCallback(
    (c) => checkConnection(`${c.source}.${c.sourceHandle}`, `${c.target}.${c.targetHandle}`) === null,
    [checkConnection],
  );
  const onConnect = useCallback(
    (c) => onConnectPorts(`${c.source}.${c.sourceHandle}`, `${c.target}.${c.targetHandle}`),
    [onConnectPorts],
  );
  const onConnectEnd = useCallback(
    (_event, state) => {
      if (!state || state.isValid !== false || !state.toHandle || !state.fromHandle) return;
      const a = `${state.fromHandle.nodeId}.${state.fromHandle.id}`;
      const b = `${state.toHandle.nodeId}.${state.toHandle.id}`;
      if (a === b) return; // a click on a handle
      const why = checkConnection(a, b);
      if (why) onRefused(why);
    },
    [checkConnection, onRefused],
  );

  const onDeleteCb = useCallback(
    ({ nodes: ns, edges: es }) => onDelete(ns.map((n) => n.id), es.map((e) => e.data)),
    [onDelete],
  );

  const onSelectionChange = useCallback(
    ({ nodes: ns, edges: es }) => onSelection(ns.map((n) => n.id), es.map((e) => e.data)),
    [onSelection],
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
      onDropType(type, { x: p.x - 58, y: p.y - 32 });
    },
    [flow, onDropType],
  );

  const onNodeDoubleClick = useCallback((_e, node) => onOpenNode(node.id), [onOpenNode]);

  const defaultEdgeOptions = useMemo(() => ({ type: "smoothstep", pathOptions: { borderRadius: 6 } }), []);

  return (
    <div className="kn-canvas" data-testid="canvas" onDragOver={onDragOver} onDrop={onDrop}>
      <ReactFlow
        nodes={nodes}
        edges={edges}
        nodeTypes={nodeTypes}
        onNodesChange={onNodesChange}
        onEdgesChange={onEdgesChange}
        onNodeDragStart={onNodeDragStart}
        onNodeDragStop={onNodeDragStop}
        onConnect={onConnect}
        onConnectEnd={onConnectEnd}
        isValidConnection={isValidConnection}
        onDelete={onDeleteCb}
        onSelectionChange={onSelectionChange}
        onNodeDoubleClick={onNodeDoubleClick}
        onPaneContextMenu={(e) => e.preventDefault()}
        connectionMode={ConnectionMode.Loose}
        defaultEdgeOptions={defaultEdgeOptions}
        snapToGrid
        snapGrid={[GRID, GRID]}
        selectionOnDrag
        panOnDrag={[1, 2]}
        selectionKeyCode={null}
        multiSelectionKeyCode={["Meta", "Control", "Shift"]}
        deleteKeyCode={null}
        zoomOnDoubleClick={false}
        minZoom={0.1}
        maxZoom={3}
        connectionRadius={18}
        proOptions={{ hideAttribution: true }}
      >
        <Background gap={GRID * 2} size={1} color="#d4d8de" />
        <Controls showInteractive={false} />
        <MiniMap pannable zoomable nodeStrokeWidth={2} nodeColor={(n) => (n.data.problems && n.data.problems.length ? "#e05555" : "#c9ced6")} style={{ width: 140, height: 90 }} />
      </ReactFlow>
    </div>
  );
}
