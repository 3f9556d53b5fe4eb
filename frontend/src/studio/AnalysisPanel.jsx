// Analysis from the page, through the library's own calls (the server runs kn.sweep,
// kn.sample and kn.linearize): a parameter sweep, on a grid or drawn at random, whose members
// are overlaid in the plots; and the model linearised at a time of its run (by default where
// the plot cursor is), with its poles and a Bode plot.
import { useState } from "react";
import { api } from "./api.js";
import { gridValues, inputCandidates } from "./analysis.js";
import { studio, useStudio } from "./store.js";
import Bode from "./Bode.jsx";

function SweepForm({ runner, params, limits }) {
  const [kind, setKind] = useState("grid");
  const [rows, setRows] = useState(() => (params.length ? [{ name: params[0], text: "", dist: "uniform", a: "", b: "" }] : []));
  const [n, setN] = useState("16");
  const [seed, setSeed] = useState("1");
  const [error, setError] = useState(null);
  const setRow = (i, patch) => setRows((rs) => rs.map((r, k) => (k === i ? { ...r, ...patch } : r)));

  const start = () => {
    const spec = { kind };
    if (kind === "grid") {
      spec.grid = {};
      for (const r of rows) {
        const { values, error: bad } = gridValues(r.text);
        if (bad) return setError(`${r.name}: ${bad}`);
        spec.grid[r.name] = values;
      }
    } else {
      spec.distributions = {};
      for (const r of rows) {
        const [a, b] = [Number(r.a), Number(r.b)];
        if (r.a === "" || r.b === "" || !Number.isFinite(a) || !Number.isFinite(b)) return setError(`${r.name}: give two numbers`);
        spec.distributions[r.name] = { [r.dist]: [a, b] };
      }
      spec.n = Number(n);
      spec.seed = seed === "" ? null : Number(seed);
    }
    if (!rows.length) return setError("add a parameter to sweep");
    setError(null);
    runner.sweep(spec);
    return undefined;
  };

  if (!params.length) return <div className="kn-muted kn-pad">The model has no parameters to sweep: add some (Parameters tab, with nothing selected) and use them in the components.</div>;
  const members = kind === "grid" ? rows.reduce((m, r) => m * ((gridValues(r.text).values || []).length || 0), 1) : Number(n) || 0;
  return (
    <div className="kn-analysis-form" data-testid="sweep-form">
      <div className="kn-seg">
        {[["grid", "Grid"], ["random", "Random"]].map(([k, label]) => (
          <button key={k} className={`kn-chip ${kind === k ? "on" : ""}`} data-testid={`sweep-kind-${k}`} onClick={() => setKind(k)}>
            {label}
          </button>
        ))}
      </div>
      {rows.map((r, i) => (
        <div className="kn-sweep-row" key={i}>
          <select className="kn-input" value={r.name} data-testid={`sweep-param-${i}`} onChange={(e) => setRow(i, { name: e.target.value })}>
            {params.map((p) => (
              <option key={p} value={p}>
                {p}
              </option>
            ))}
          </select>
          {kind === "grid" ? (
            <input className="kn-input" placeholder="1, 2, 3  or  1 .. 3 / 5" title="1, 2, 3  or  1 .. 3 / 5: the values, or n of them from a to b (a .. b / n)" value={r.text} data-testid={`sweep-values-${i}`} onChange={(e) => setRow(i, { text: e.target.value })} />
          ) : (
            <>
              <select className="kn-input" value={r.dist} title="the distribution: uniform from low to high, or normal with mean and std" data-testid={`sweep-dist-${i}`} onChange={(e) => setRow(i, { dist: e.target.value })}>
                <option value="uniform">uniform</option>
                <option value="normal">normal</option>
              </select>
              <input className="kn-input kn-num" placeholder={r.dist === "uniform" ? "low" : "mean"} value={r.a} data-testid={`sweep-a-${i}`} onChange={(e) => setRow(i, { a: e.target.value })} />
              <input className="kn-input kn-num" placeholder={r.dist === "uniform" ? "high" : "std"} value={r.b} data-testid={`sweep-b-${i}`} onChange={(e) => setRow(i, { b: e.target.value })} />
            </>
          )}
          <button className="kn-icon-btn" title="remove" onClick={() => setRows((rs) => rs.filter((_, k) => k !== i))}>
            ×
          </button>
        </div>
      ))}
      <div className="kn-sweep-row">
        <button className="kn-btn" data-testid="sweep-add" onClick={() => setRows((rs) => [...rs, { name: params.find((p) => !rs.some((r) => r.name === p)) || params[0], text: "", dist: "uniform", a: "", b: "" }])}>
          + parameter
        </button>
        {kind === "random" ? (
          <>
            <label className="kn-small">members</label>
            <input className="kn-input kn-num" value={n} data-testid="sweep-n" onChange={(e) => setN(e.target.value)} />
            <label className="kn-small">seed</label>
            <input className="kn-input kn-num" value={seed} data-testid="sweep-seed" onChange={(e) => setSeed(e.target.value)} />
          </>
        ) : null}
      </div>
      <div className="kn-sweep-row">
        <button className="kn-btn kn-run" data-testid="sweep-run" disabled={runner.going} onClick={start}>
          ▶ Sweep {members ? `${members} member${members > 1 ? "s" : ""}` : ""}
        </button>
        {limits ? <span className="kn-muted kn-small">at most {limits.sweep_members} members</span> : null}
      </div>
      {error ? <div className="kn-param-problem">{error}</div> : null}
    </div>
  );
}

function formatPole(re, im) {
  const f = (x) => (Math.abs(x) >= 1e4 || (Math.abs(x) < 1e-3 && x !== 0) ? x.toExponential(3) : x.toFixed(4));
  return im ? `${f(re)} ${im > 0 ? "+" : "−"} ${f(Math.abs(im))}j` : f(re);
}

function LinearizeForm({ scope }) {
  const doc = useStudio((s) => s.hist.present);
  const path = useStudio((s) => s.file.path);
  const time = useStudio((s) => s.time);
  const runs = useStudio((s) => s.runs);
  const [at, setAt] = useState("");
  const [inputs, setInputs] = useState([]);
  const [result, setResult] = useState(null);
  const [busy, setBusy] = useState(false);
  const candidates = inputCandidates(doc, scope.rootCtx);
  const latest = runs.find((r) => r.kind !== "sweep");
  const atTime = at === "" ? (time != null && latest ? time : 0) : Number(at);

  const go = async () => {
    if (!Number.isFinite(atTime) || atTime < 0) {
      studio().toast("linearize: the time must be a number >= 0");
      return;
    }
    setBusy(true);
    try {
      setResult(await api.linearize(doc, { at: atTime, inputs }, path));
    } catch (e) {
      setResult(null);
      studio().toast(`cannot linearize: ${e.message}`);
    } finally {
      setBusy(false);
    }
  };

  return (
    <div className="kn-analysis-form" data-testid="linearize-form">
      <div className="kn-sweep-row">
        <label className="kn-small">at t [s]</label>
        <input className="kn-input kn-num" placeholder={String(+atTime.toPrecision(6))} value={at} data-testid="lin-at" onChange={(e) => setAt(e.target.value)} />
        <span className="kn-muted kn-small">{at === "" ? (time != null && latest ? "the plot cursor's time" : "the start") : ""}</span>
      </div>
      {candidates.length ? (
        <div className="kn-choices" data-testid="lin-inputs">
          <span className="kn-small">inputs:</span>
          {candidates.map((c) => (
            <label key={c} className="kn-choice">
              <input type="checkbox" checked={inputs.includes(c)} data-testid={`lin-input-${c}`} onChange={(e) => setInputs((xs) => (e.target.checked ? [...xs, c] : xs.filter((x) => x !== c)))} />
              {c}
            </label>
          ))}
        </div>
      ) : (
        <div className="kn-muted kn-small">No inputs: add a signals.Input block (or leave a Torque's u unwired) for a Bode plot.</div>
      )}
      <button className="kn-btn kn-run" data-testid="lin-run" disabled={busy} onClick={go}>
        {busy ? "Linearizing…" : "Linearize"}
      </button>
      {result ? (
        <div className="kn-lin-result" data-testid="lin-result">
          <div className="kn-section">
            {result.state_names.length} states at t = {+Number(result.t).toPrecision(6)} s: poles
          </div>
          <table className="kn-poles" data-testid="lin-poles">
            <tbody>
              {result.poles.map(([re, im], i) => (
                <tr key={i} className={re > 1e-9 ? "unstable" : ""}>
                  <td>{formatPole(re, im)}</td>
                  <td className="kn-muted kn-small">{im ? `${(Math.hypot(re, im) / (2 * Math.PI)).toPrecision(4)} Hz, ζ = ${(-re / Math.hypot(re, im)).toPrecision(3)}` : re > 1e-9 ? "unstable" : ""}</td>
                </tr>
              ))}
            </tbody>
          </table>
          {result.bode ? <Bode bode={result.bode} /> : null}
        </div>
      ) : null}
    </div>
  );
}

/**
 * @param {{runner: any, scope: any}} props
 */
export default function AnalysisPanel({ runner, scope }) {
  const doc = useStudio((s) => s.hist.present);
  const facts = useStudio((s) => s.facts);
  const params = Object.keys(doc.parameters || {});
  return (
    <div className="kn-params kn-analysis" data-testid="analysis">
      <div className="kn-panel-title">Parameter sweep</div>
      <div className="kn-panel-body">
        <SweepForm key={params.join(",")} runner={runner} params={params} limits={facts && facts.limits} />
      </div>
      <div className="kn-panel-title">Linearization</div>
      <div className="kn-panel-body">
        <LinearizeForm scope={scope} />
      </div>
    </div>
  );
}
