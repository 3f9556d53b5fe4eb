// An exposed port of the definition being edited: a connector on the diagram, wired (dashed)
// to the inner port it stands for, as MapleSim draws a subsystem's ports from inside.
import { memo } from "react";
import { Handle, Position } from "@xyflow/react";
import { DOMAIN_COLORS } from "./model.js";

const FACING = { left: Position.Right, right: Position.Left, top: Position.Bottom, bottom: Position.Top };

function PortNode({ data, selected }) {
  const { name, domain, side } = data;
  const color = DOMAIN_COLORS[domain] || "#888";
  return (
    <div className={`kn-extport ${selected ? "selected" : ""}`} data-testid={`port-${name}`} style={{ "--port-color": color }}
      title={`exposed port ${name} (${domain}): ${data.ref}`}>
      <span className="kn-extport-mark" />
      {name}
      <Handle id="port" type="source" position={FACING[side] || Position.Right} className={`kn-port kn-port-${domain}`}
        style={{ "--port-color": color }} data-testid={`handle-@${name}-port`} />
    </div>
  );
}

export default memo(PortNode);
