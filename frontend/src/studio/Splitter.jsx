// A splitter between two panes: drag it to resize the pane it belongs to, click its arrow or
// double-click it to collapse or reopen that pane (panes.js keeps both).
import { useCallback, useRef } from "react";
import { usePanes } from "./panes.js";

const ARROWS = {
  // the pane's place relative to the splitter -> [arrow to collapse, arrow to reopen]
  before: { x: ["◂", "▸"], y: ["▴", "▾"] },
  after: { x: ["▸", "◂"], y: ["▾", "▴"] },
};

/**
 * @param {{pane: import("./panes.js").PaneName, axis: "x" | "y", side: "before" | "after",
 *   size: number, label: string}} props  ``side``: where the pane is (before: left or above)
 */
export default function Splitter({ pane, axis, side, size, label }) {
  const closed = usePanes((s) => s.closed[pane]);
  const resize = usePanes((s) => s.resize);
  const toggle = usePanes((s) => s.toggle);
  const drag = useRef(null);
  const sign = side === "before" ? 1 : -1;

  const onPointerDown = useCallback(
    (e) => {
      if (e.button !== 0 || /** @type {HTMLElement} */ (e.target).closest("button")) return;
      e.preventDefault();
      e.currentTarget.setPointerCapture(e.pointerId);
      drag.current = { from: axis === "x" ? e.clientX : e.clientY, size: closed ? 0 : size };
    },
    [axis, size, closed],
  );
  const onPointerMove = useCallback(
    (e) => {
      if (!drag.current) return;
      const at = axis === "x" ? e.clientX : e.clientY;
      resize(pane, drag.current.size + sign * (at - drag.current.from));
    },
    [axis, pane, resize, sign],
  );
  const onPointerUp = useCallback((e) => {
    drag.current = null;
    if (e.currentTarget.hasPointerCapture(e.pointerId)) e.currentTarget.releasePointerCapture(e.pointerId);
  }, []);

  const [shut, open] = ARROWS[side][axis];
  return (
    <div
      className={`kn-splitter kn-splitter-${axis}${closed ? " closed" : ""}`}
      data-testid={`splitter-${pane}`}
      role="separator"
      aria-orientation={axis === "x" ? "vertical" : "horizontal"}
      aria-label={`${label}: drag to resize, double-click to ${closed ? "show" : "hide"}`}
      title={`${label}: drag to resize, double-click to ${closed ? "show" : "hide"}`}
      onPointerDown={onPointerDown}
      onPointerMove={onPointerMove}
      onPointerUp={onPointerUp}
      onDoubleClick={() => toggle(pane)}
    >
      <button className="kn-splitter-toggle" data-testid={`toggle-${pane}`} title={`${closed ? "Show" : "Hide"} the ${label.toLowerCase()}`} onClick={() => toggle(pane)}>
        {closed ? open : shut}
      </button>
    </div>
  );
}
