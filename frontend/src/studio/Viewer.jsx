// The 3-D view of a run: frontend/src/viewer3d's createViewer(element, animation, {controls,
// onTime}), loaded on demand (three.js is its own chunk, so the studio opens fast). Until that
// module exists, or when a run has no animation, a placeholder says why.
import { useEffect, useRef, useState } from "react";

// a glob, not an import: the build works before viewer3d/index.js exists
const modules = import.meta.glob("../viewer3d/index.js");
const loader = modules["../viewer3d/index.js"];

export default function Viewer({ animation, bus, onViewer }) {
  const host = useRef(null);
  const [error, setError] = useState(null);
  const [ready, setReady] = useState(false);
  useEffect(() => {
    setError(null);
    setReady(false);
    if (!loader || !animation || !host.current) return undefined;
    let viewer = null;
    let gone = false;
    loader()
      .then((mod) => {
        if (gone) return;
        const create = mod.createViewer || (mod.default && mod.default.createViewer) || mod.default;
        viewer = create(host.current, animation, {
          controls: true,
          onTime: (t) => bus.follow(t),
        });
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
      if (host.current) host.current.replaceChildren();
    };
  }, [animation, bus, onViewer]);
  let note = null;
  if (!loader) note = "The 3-D view is not built into this studio yet.";
  else if (error) note = `The 3-D view failed: ${error}`;
  else if (!animation) note = "Run the model to see it move in 3-D.";
  return (
    <div className="kn-viewpane" data-testid="viewer" data-ready={ready ? "1" : "0"}>
      <div className="kn-viewpane-host" ref={host} />
      {note ? <div className="kn-viewpane-note">{note}</div> : null}
    </div>
  );
}
