// The 3-D view of a run: frontend/src/viewer3d's createViewer(element, animation, {controls,
// onTime}), loaded on demand (three.js is its own chunk, so the studio opens fast). Without
// an animation a note says why: no run yet, or a model with nothing to show in 3-D.
// The parent mounts one Viewer per animation (its key), so each starts afresh.
import { useEffect, useRef, useState } from "react";

// a glob, not an import: three.js stays out of the studio's first chunk
const modules = import.meta.glob("../viewer3d/index.js");
const loader = modules["../viewer3d/index.js"];

/**
 * @param {{animation: any, reason: string | null, bus: any, onViewer: (v: any) => void}} props
 */
export default function Viewer({ animation, reason, bus, onViewer }) {
  const host = useRef(null);
  const [error, setError] = useState(null);
  const [ready, setReady] = useState(false);
  useEffect(() => {
    const el = host.current;
    if (!loader || !animation || !el) return undefined;
    let viewer = null;
    let gone = false;
    loader()
      .then((mod) => {
        if (gone) return;
        const m = /** @type {any} */ (mod);
        const create = m.createViewer || (m.default && m.default.createViewer) || m.default;
        viewer = create(el, animation, { controls: true, onTime: (t) => bus.follow(t) });
        onViewer(viewer);
        setReady(true);
      })
      .catch((err) => {
        if (!gone) setError(String((err && err.message) || err));
      });
    return () => {
      gone = true;
      onViewer(null);
      if (viewer) {
        try {
          viewer.dispose();
        } catch {
          /* already gone */
        }
      }
      el.replaceChildren();
    };
  }, [animation, bus, onViewer]);
  let note = null;
  if (!loader) note = "The 3-D view is not built into this studio.";
  else if (error) note = `The 3-D view failed: ${error}`;
  else if (!animation) note = reason || "Run the model to see it move in 3-D.";
  return (
    <div className="kn-viewpane" data-testid="viewer" data-ready={ready ? "1" : "0"}>
      <div className="kn-viewpane-host" ref={host} />
      {note ? (
        <div className="kn-viewpane-note" data-testid="viewer-note">
          {note}
        </div>
      ) : null}
    </div>
  );
}
