// What validation (and the last run) says is wrong, in the user's words, each on the place it
// names: a click goes to the block (opening the definition it is in).
import { whereOf } from "./problems.js";

/**
 * @param {{places: import("./problems.js").Place[], ok: boolean | null, onGo: (p: any) => void}} props
 */
export default function Problems({ places, ok, onGo }) {
  const count = places.length;
  return (
    <div className="kn-problems" data-testid="problems" data-count={count}>
      <div className="kn-panel-title">
        Problems
        <span className={`kn-badge ${count ? "bad" : ok ? "ok" : ""}`}>{count ? count : ok ? "✓" : "…"}</span>
      </div>
      <div className="kn-problems-list">
        {count === 0 ? (
          <div className="kn-muted kn-pad">{ok ? "The model is valid." : ok === null ? "Checking…" : "No problems reported."}</div>
        ) : (
          places.map((p, i) => (
            <div key={i} className={`kn-problem-item ${p.severity}`} data-testid="problem" onClick={() => onGo(p)} title={p.hint ? `${p.message}\n\n${p.hint}` : p.message}>
              <span className="kn-problem-where">
                {p.run ? "run · " : ""}
                {p.scope ? `${p.scope} › ` : ""}
                {whereOf(p) || "model"}
              </span>
              <span className="kn-problem-msg">{p.reason || p.text}</span>
              {p.hint ? <span className="kn-problem-hint">{p.hint}</span> : null}
            </div>
          ))
        )}
      </div>
    </div>
  );
}
