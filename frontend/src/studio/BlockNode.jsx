// A component on the diagram: its icon, name and type, its ports as handles on the sides
// (coloured by domain, as Modelica draws connectors), and what validation says about it.
import { memo } from "react";
import { Handle, Position } from "@xyflow/react";
import { DOMAIN_COLORS } from "./model.js";
import { blockGeometry } from "./geometry.js";
import { blockText } from "./problems.js";
import { TypeIcon } from "./icons.jsx";

const POS = { left: Position.Left, right: Position.Right, top: Position.Top, bottom: Position.Bottom };
function shortType(type, subsystem) {
  if (subsystem) return `${type} ▸`;
  return String(type || "?").split(".").pop();
}

function BlockNode({ data, selected }) {
  const { name, type, info, problems, subsystem, unknown, rotation, flip } = data;
  const ports = info ? info.ports : data.ports || [];
  const { handles, height, width } = blockGeometry(ports, rotation, flip);
  const bad = problems && problems.length > 0;
  const cls = ["kn-block", selected ? "selected" : "", bad ? "bad" : "", subsystem ? "subsystem" : "", unknown ? "unknown" : ""]
    .filter(Boolean)
    .join(" ");
  return (
    <div className={cls} data-testid={`node-${name}`} style={{ width, height }} title={`${name}: ${type}${info ? `\n${String(info.doc || "").trim()}` : " (unknown type)"}`}>
      <div className="kn-block-name" style={{ maxWidth: width - 12 }}>{name}</div>
      <div className={`kn-block-icon${flip ? " flipped" : ""}`}>
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
      {handles.map(({ port, side, x, y, room }) => {
        // the name of a port on the top or bottom stands beside it, outwards (left of the
        // middle: to the left), in the margin wires keep from the block
        const beside = side === "top" || side === "bottom" ? (x < width / 2 ? "-before" : "-after") : "";
        const color = DOMAIN_COLORS[port.domain] || "#888";
        const style = side === "left" || side === "right" ? { top: y } : { left: x };
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
            <span className={`kn-port-label kn-port-label-${side}${beside}`} style={room ? { maxWidth: room } : undefined}>
              {port.name}
            </span>
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
