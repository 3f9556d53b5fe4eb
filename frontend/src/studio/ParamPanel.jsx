// The right-hand panel: the selected component's parameters (value or expression, with
// unit, bounds, default and doc), or, with nothing selected, the model (or definition): its
// name, parameters and simulation settings.
import { typeInfo } from "./model.js";
import { formatValue, parseValue } from "./values.js";
import { useStudio } from "./store.js";
import ModelPanel from "./ModelPanel.jsx";
import { Field } from "./Field.jsx";
import { TypeIcon } from "./icons.jsx";

function bounds(p) {
  const parts = [];
  if (p.min != null) parts.push(`≥ ${p.min}`);
  if (p.max != null) parts.push(`≤ ${p.max}`);
  return parts.join(", ");
}

function ParamRow({ p, value, problems, onSet }) {
  const given = value !== undefined;
  const bad = problems.length > 0;
  const shape = p.shape && p.shape.length ? `(${p.shape.join("×")})` : "";
  let input;
  if (p.kind === "bool") {
    const v = given ? !!value : !!p.default;
    input = (
      <input type="checkbox" checked={v} data-testid={`param-${p.name}`} onChange={(e) => onSet(e.target.checked)} />
    );
  } else if (p.kind === "names" && p.choices) {
    const current = Array.isArray(value) ? value : Array.isArray(p.default) ? p.default : [];
    const chosen = new Set(current);
    input = (
      <div className="kn-choices" data-testid={`param-${p.name}`}>
        {p.choices.map((c) => (
          <label key={c} className="kn-choice">
            <input
              type="checkbox"
              checked={chosen.has(c)}
              data-testid={`param-${p.name}-${c}`}
              onChange={(e) => {
                // in the order they were ticked: the order of the probe's signals
                const next = e.target.checked ? [...current.filter((x) => x !== c), c] : current.filter((x) => x !== c);
                onSet(next.length ? next : undefined);
              }}
            />
            {c}
          </label>
        ))}
      </div>
    );
  } else if (p.choices) {
    input = (
      <select className="kn-input" value={given ? String(value) : ""} data-testid={`param-${p.name}`} onChange={(e) => onSet(e.target.value === "" ? undefined : e.target.value)}>
        <option value="">{`default (${formatValue(p.default) || "none"})`}</option>
        {p.choices.map((c) => (
          <option key={c} value={c}>{c}</option>
        ))}
      </select>
    );
  } else {
    const hint = p.required ? "required" : formatValue(p.default) || "none";
    input = (
      <Field
        value={formatValue(value)}
        placeholder={hint}
        testid={`param-${p.name}`}
        bad={bad}
        title={`${p.required ? hint : `default ${hint}`}: a number, or an expression in the model's parameters${p.time ? " and time t" : ""}`}
        onCommit={(text) => onSet(parseValue(text))}
      />
    );
  }
  return (
    <div className={`kn-param ${bad ? "bad" : ""}`}>
      <div className="kn-param-head">
        <span className="kn-param-name">{p.name}</span>
        {p.unit ? <span className="kn-unit">[{p.unit}]</span> : null}
        {shape ? <span className="kn-muted kn-small">{shape}</span> : null}
        {p.required ? <span className="kn-req">required</span> : null}
        {given && p.kind !== "bool" ? (
          <button className="kn-link" title="back to the default" onClick={() => onSet(undefined)}>
            reset
          </button>
        ) : null}
      </div>
      {input}
      <div className="kn-param-doc">
        {p.doc}
        {!p.required && p.kind !== "names" ? <span className="kn-muted"> · default {formatValue(p.default) || "none"}</span> : null}
        {bounds(p) ? <span className="kn-muted"> · {bounds(p)}</span> : null}
        {p.time ? <span className="kn-muted"> · may use t</span> : null}
      </div>
      {problems.map((m, i) => (
        <div key={i} className="kn-param-problem" title={m.hint || undefined}>{m.text}</div>
      ))}
    </div>
  );
}

function ComponentPanel({ comp, info, problems, onRename, onSetParam, onOpen }) {
  const paramProblems = (key) => problems.filter((m) => m.parameter === key);
  const general = problems.filter((m) => !m.parameter || !(info && info.params.some((p) => p.name === m.parameter)));
  const given = comp.params || {};
  const unknownKeys = Object.keys(given).filter((k) => !info || !info.params.some((p) => p.name === k));
  return (
    <div className="kn-panel-body">
      <div className="kn-comp-head">
        <TypeIcon type={comp.type} subsystem={info && info.subsystem} />
        <div>
          <Field
            value={comp.name}
            testid="param-name"
            className="kn-name-input"
            onCommit={(text) => onRename(text.trim())}
          />
          <div className="kn-muted kn-small" data-testid="param-type">
            {comp.type}
            {info && info.subsystem ? " · subsystem" : ""}
          </div>
        </div>
      </div>
      {info && info.subsystem ? (
        <button className="kn-btn kn-small-btn" onClick={onOpen}>Open definition ⟶</button>
      ) : null}
      {info ? <div className="kn-doc">{String(info.doc || "").trim()}</div> : <div className="kn-problem">Unknown type {comp.type}</div>}
      {general.map((m, i) => (
        <div key={i} className="kn-param-problem" title={m.hint || undefined}>{m.text}</div>
      ))}
      {info && info.params.length === 0 ? <div className="kn-muted kn-pad">No parameters.</div> : null}
      {info &&
        info.params.map((p) => (
          <ParamRow key={p.name} p={p} value={given[p.name]} problems={paramProblems(p.name)} onSet={(v) => onSetParam(p.name, v)} />
        ))}
      {unknownKeys.map((k) => (
        <ParamRow
          key={k}
          p={{ name: k, doc: "not a parameter of this type", unit: "", default: null }}
          value={given[k]}
          problems={paramProblems(k)}
          onSet={(v) => onSetParam(k, v)}
        />
      ))}
    </div>
  );
}

/**
 * The right-hand panel: the component selected, a selection of several, or the model.
 * @param {{scope: import("./hooks/useDefinitions.js").Scope, edit: import("./hooks/useEditing.js").Edit,
 *   byBlock: Map<string, any[]>, here: any[]}} props
 */
export default function ParamPanel({ scope, edit, byBlock, here }) {
  const selected = useStudio((s) => s.selection);
  const summary = useStudio((s) => s.validation.summary);
  const { body, ctx } = scope;
  const comps = body.components || [];
  const one = selected.length === 1 ? comps.find((c) => c.name === selected[0]) : null;
  return (
    <div className="kn-params" data-testid="params">
      <div className="kn-panel-title">
        {one ? "Component" : selected.length > 1 ? "Selection" : scope.scope ? "Definition" : "Model"}
        {summary && !one ? (
          <span className="kn-muted kn-small kn-summary" data-testid="summary">
            {summary.dof != null ? `${summary.dof} dof · ` : ""}
            {summary.states ? `${summary.states.length} states · ` : ""}
            {summary.components} components
          </span>
        ) : null}
      </div>
      {one ? (
        <ComponentPanel
          key={one.name}
          comp={one}
          info={typeInfo(one.type, ctx)}
          problems={byBlock.get(one.name) || []}
          onRename={(to) => edit.rename(one.name, to)}
          onSetParam={(k, v) => edit.setParam(one.name, k, v)}
          onOpen={() => edit.open(one.name)}
        />
      ) : selected.length > 1 ? (
        <div className="kn-panel-body">
          <div className="kn-pad">{selected.length} components selected.</div>
          <button className="kn-btn" data-testid="make-subsystem-panel" onClick={() => edit.makeSub()}>
            Make subsystem
          </button>
          <div className="kn-muted kn-small kn-pad">
            Ctrl+C / Ctrl+V copy and paste them (at the pointer), Ctrl+D duplicates, arrow keys move them, Delete removes them.
          </div>
        </div>
      ) : (
        <ModelPanel body={body} isDefinition={!!scope.scope} scopeName={scope.scope} problems={here} edit={edit} />
      )}
    </div>
  );
}
