// What validation (and the last run) says is wrong, each on the place it names: a click
// goes to the block (opening the definition it is in).
export default function Problems({ places, ok, count, onGo }) {
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
            <div key={i} className="kn-problem-item" data-testid="problem" onClick={() => onGo(p)} title="show it">
              <span className="kn-problem-where">
                {p.run ? "run · " : ""}
                {p.scope ? `${p.scope} › ` : ""}
                {p.component || (p.connection !== null ? `connection ${p.connection}` : "model")}
              </span>
              <span className="kn-problem-msg">{p.message}</span>
            </div>
          ))
        )}
      </div>
    </div>
  );
}
