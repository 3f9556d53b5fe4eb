// A component on the diagram: its icon, name and type, its ports as handles on the sides
// (coloured by domain, as Modelica draws connectors), and what validation says about it.
import { memo } from "react";
import { Handle, Position } from "@xyflow/react";
import { DOMAIN_COLORS, placedSide, portSide } from "./model.js";
import { blockText } from "./problems.js";
import { TypeIcon } from "./icons.jsx";

const POS = { left: Position.Left, right: Position.Right, top: Position.Top, bottom: Position.Bottom };
export const BLOCK_W = 116;
const PORT_STEP = 20;

/**
 * Where each port goes: {port, side, offset (0..1 along the side)}; the block's height. A
 * block turned by ``rotation`` degrees has its ports on the sides turned with it; a flipped
 * one has left and right exchanged first.
 */
export function blockGeometry(ports, rotation = 0, flip = false) {
  const sides = { left: [], right: [], top: [], bottom: [] };
  for (const p of ports) sides[placedSide(p.side || portSide(p.name, p.domain, ports), rotation, flip)].push(p);
  const tall = Math.max(sides.left.length, sides.right.length);
  const height = Math.max(64, tall * PORT_STEP + 24);
  const out = [];
  for (const [side, list] of Object.entries(sides)) {
    list.forEach((p, i) => out.push({ port: p, side, offset: (i + 1) / (list.length + 1) }));
  }
  return { handles: out, height, width: BLOCK_W };
}

function shortType(type, subsystem) {
  if (subsystem) return `${type} ▸`;
  return String(type || "?").split(".").pop();
}

function BlockNode({ data, selected }) {
  const { name, type, info, problems, subsystem, unknown, rotation, flip } = data;
  const ports = info ? info.ports : data.ports || [];
  const { handles, height } = blockGeometry(ports, rotation, flip);
  const bad = problems && problems.length > 0;
  const cls = ["kn-block", selected ? "selected" : "", bad ? "bad" : "", subsystem ? "subsystem" : "", unknown ? "unknown" : ""]
    .filter(Boolean)
    .join(" ");
  return (
    <div className={cls} data-testid={`node-${name}`} style={{ width: BLOCK_W, height }} title={`${name}: ${type}${info ? `\n${String(info.doc || "").trim()}` : " (unknown type)"}`}>
      <div className="kn-block-name">{name}</div>
      <div className="kn-block-icon" style={flip ? { transform: "scaleX(-1)" } : undefined}>
        <TypeIcon type={type} subsystem={subsystem} />
      </div>
      {bad ? (
        // what is wrong, inside the block: it covers no neighbour (the whole text on hover)
        <div className="kn-block-msg" data-testid={`node-msg-${name}`} title={problems.map((p) => p.text).join("\n")}>
          {blockText(problems[0])}
        </div>
      ) : (
        <div className="kn-block-type">{shortType(type, subsystem)}</div>
      )}
      {handles.map(({ port, side, offset }) => {
        const color = DOMAIN_COLORS[port.domain] || "#888";
        const along = `${offset * 100}%`;
        const style = side === "left" || side === "right" ? { top: along } : { left: along };
        return (
          <Handle
            key={port.name}
            id={port.name}
            type="source"
            position={POS[side]}
            className={`kn-port kn-port-${port.domain}`}
            style={{ ...style, "--port-color": color }}
            data-testid={`handle-${name}-${port.name}`}
            title={`${name}.${port.name} (${port.domain})${port.doc ? `: ${port.doc}` : ""}`}
          >
            <span className={`kn-port-label kn-port-label-${side}`}>{port.name}</span>
          </Handle>
        );
      })}
      {bad && (
        <div className="kn-block-badge" data-testid={`node-bad-${name}`} title={problems.map((p) => p.text).join("\n")}>
          {problems.length}
        </div>
      )}
    </div>
  );
}

export default memo(BlockNode);
