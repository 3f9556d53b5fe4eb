// A wire as the router laid it: straight segments with square corners (as Modelica and
// MapleSim draw them), from one port's handle to the other's.
import { memo } from "react";
import { BaseEdge } from "@xyflow/react";

/** An SVG path through ``points``. */
export function wirePath(points) {
  return `M${points.map((p) => `${p.x} ${p.y}`).join(" L")}`;
}

/** @param {import("@xyflow/react").EdgeProps} props */
function WireEdge({ id, data, style, markerEnd, markerStart, sourceX, sourceY, targetX, targetY }) {
  const given = /** @type {{x: number, y: number}[] | undefined} */ (data && data.points);
  const points = given && given.length > 1 ? given : [{ x: sourceX, y: sourceY }, { x: targetX, y: targetY }];
  return <BaseEdge id={id} path={wirePath(points)} style={style} markerEnd={markerEnd} markerStart={markerStart} interactionWidth={12} />;
}

export default memo(WireEdge);
