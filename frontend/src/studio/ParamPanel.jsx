// The right-hand panel: the selected component's parameters (value or expression, with
// unit, bounds, default and doc), or, with nothing selected, the model (or definition): its
// name, parameters and simulation settings.
import { useEffect, useRef, useState } from "react";
import { formatValue, parseValue, IDENT } from "./model.js";
import { TypeIcon } from "./icons.jsx";

/** A text field that commits on Enter or when it loses focus (one undo step per edit). */
export function Field({ value, onCommit, testid, placeholder, className, list, bad, title }) {
  const [text, setText] = useState(value);
  const [focused, setFocused] = useState(false);
  useEffect(() => {
    if (!focused) setText(value);
  }, [value, focused]);
  useEffect(() => {
    sent.current = null;
  }, [value]);
  const sent = useRef(null);
  const commit = () => {
    // Enter commits and blurs: the blur must not commit the same text again
    if (text !== value && text !== sent.current) {
      sent.current = text;
      onCommit(text);
    }
  };
  return (
    <input
      className={`kn-input ${className || ""} ${bad ? "bad" : ""}`}
      value={text}
      placeholder={placeholder}
      data-testid={testid}
      list={list}
      title={title}
      spellCheck={false}
      onFocus={() => setFocused(true)}
      onBlur={() => {
        setFocused(false);
        commit();
      }}
      onChange={(e) => setText(e.target.value)}
      onKeyDown={(e) => {
        if (e.key === "Enter") {
          commit();
          e.currentTarget.blur();
        } else if (e.key === "Escape") {
          setText(value);
          e.currentTarget.blur();
        }
      }}
    />
  );
}

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
    input = (
      <Field
        value={formatValue(value)}
        placeholder={p.required ? "required" : formatValue(p.default) || "none"}
        testid={`param-${p.name}`}
        bad={bad}
        title={p.time ? "a number, or an expression in the model's parameters and time t" : "a number, or an expression in the model's parameters"}
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
        <div key={i} className="kn-param-problem">{m.message}</div>
      ))}
    </div>
  );
}

function ComponentPanel({ comp, info, problems, onRename, onSetParam, onOpen }) {
  const paramProblems = (key) => problems.filter((m) => m.param === key);
  const general = problems.filter((m) => !m.param || !(info && info.params.some((p) => p.name === m.param)));
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
        <div key={i} className="kn-param-problem">{m.message}</div>
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

const METHODS = ["auto", "cvodes-adams", "cvodes", "idas", "rk", "collocation", "midpoint", "rk45", "dop853", "radau", "bdf", "lsoda"];
const SIM = [
  ["t_end", "s", "end time"],
  ["n_points", "", "points of the output grid"],
  ["method", "", "integration method"],
  ["rtol", "", "relative tolerance"],
  ["atol", "", "absolute tolerance"],
];

function ModelPanel({ body, isDefinition, scopeName, problems, onModelParam, onRenameModelParam, onSim, onField, onPort }) {
  const [newName, setNewName] = useState("");
  const [newValue, setNewValue] = useState("");
  const [portName, setPortName] = useState("");
  const [portRef, setPortRef] = useState("");
  const params = body.parameters || {};
  const sim = body.simulation || {};
  const modelProblems = problems.filter((m) => !m.component);
  const add = () => {
    const name = newName.trim();
    if (!IDENT.test(name) || name in params) return;
    const v = parseValue(newValue);
    onModelParam(name, v === undefined ? 0 : v);
    setNewName("");
    setNewValue("");
  };
  return (
    <div className="kn-panel-body">
      {!isDefinition ? (
        <div className="kn-field">
          <label>Model name</label>
          <Field value={body.name || ""} testid="model-name" onCommit={(t) => onField("name", t.trim())} />
        </div>
      ) : (
        <div className="kn-field">
          <label>Definition</label>
          <div className="kn-def-name">{scopeName}</div>
        </div>
      )}
      <div className="kn-field">
        <label>Description</label>
        <textarea
          className="kn-input kn-textarea"
          defaultValue={body.description || ""}
          key={`${scopeName}:${body.description || ""}`}
          data-testid="model-description"
          onBlur={(e) => e.target.value !== (body.description || "") && onField("description", e.target.value)}
        />
      </div>
      <div className="kn-section">{isDefinition ? "Definition parameters" : "Model parameters"}</div>
      <table className="kn-mparams" data-testid="model-params">
        <tbody>
          {Object.entries(params).map(([k, v]) => (
            <tr key={k}>
              <td>
                <Field value={k} className="kn-mparam-name" testid={`mparam-name-${k}`} onCommit={(t) => onRenameModelParam(k, t.trim())} />
              </td>
              <td>
                <Field value={formatValue(v)} testid={`mparam-${k}`} onCommit={(t) => onModelParam(k, parseValue(t) ?? 0)} />
              </td>
              <td>
                <button className="kn-icon-btn" title={`remove ${k}`} data-testid={`mparam-remove-${k}`} onClick={() => onModelParam(k, undefined)}>
                  ×
                </button>
              </td>
            </tr>
          ))}
          <tr>
            <td>
              <input className="kn-input kn-mparam-name" placeholder="name" value={newName} data-testid="mparam-new-name" onChange={(e) => setNewName(e.target.value)} onKeyDown={(e) => e.key === "Enter" && add()} />
            </td>
            <td>
              <input className="kn-input" placeholder="value" value={newValue} data-testid="mparam-new-value" onChange={(e) => setNewValue(e.target.value)} onKeyDown={(e) => e.key === "Enter" && add()} />
            </td>
            <td>
              <button className="kn-icon-btn" title="add the parameter" data-testid="mparam-add" onClick={add} disabled={!IDENT.test(newName.trim()) || newName.trim() in params}>
                +
              </button>
            </td>
          </tr>
        </tbody>
      </table>
      {isDefinition ? (
        <>
          <div className="kn-section">Exposed ports</div>
          <table className="kn-mparams" data-testid="def-ports">
            <tbody>
              {Object.entries(body.ports || {}).map(([k, ref]) => (
                <tr key={k}>
                  <td><b>{k}</b></td>
                  <td className="kn-muted">{ref}</td>
                  <td>
                    <button className="kn-icon-btn" title={`stop exposing ${k}`} onClick={() => onPort(k, undefined)}>×</button>
                  </td>
                </tr>
              ))}
              <tr>
                <td><input className="kn-input" placeholder="port" value={portName} onChange={(e) => setPortName(e.target.value)} /></td>
                <td><input className="kn-input" placeholder="component.port" value={portRef} onChange={(e) => setPortRef(e.target.value)} /></td>
                <td>
                  <button
                    className="kn-icon-btn"
                    disabled={!IDENT.test(portName) || !/^\w+\.\w+$/.test(portRef)}
                    onClick={() => {
                      onPort(portName, portRef);
                      setPortName("");
                      setPortRef("");
                    }}
                  >
                    +
                  </button>
                </td>
              </tr>
            </tbody>
          </table>
        </>
      ) : (
        <>
          <div className="kn-section">Simulation</div>
          <datalist id="kn-methods">
            {METHODS.map((m) => (
              <option key={m} value={m} />
            ))}
          </datalist>
          {SIM.map(([key, unit, doc]) => (
            <div className="kn-sim" key={key}>
              <label title={doc}>
                {key} {unit ? <span className="kn-unit">[{unit}]</span> : null}
              </label>
              <Field
                value={formatValue(sim[key])}
                testid={`sim-${key}`}
                list={key === "method" ? "kn-methods" : undefined}
                placeholder="default"
                onCommit={(t) => onSim(key, key === "method" ? t.trim() || undefined : parseValue(t))}
              />
            </div>
          ))}
        </>
      )}
      {modelProblems.length > 0 && (
        <div className="kn-section">Problems of the {isDefinition ? "definition" : "model"}</div>
      )}
      {modelProblems.map((m, i) => (
        <div key={i} className="kn-param-problem">{m.message}</div>
      ))}
    </div>
  );
}

export default function ParamPanel(props) {
  const { selected, body, ctx, problemsOf, scope, summary } = props;
  const comps = body.components || [];
  const one = selected.length === 1 ? comps.find((c) => c.name === selected[0]) : null;
  return (
    <div className="kn-params" data-testid="params">
      <div className="kn-panel-title">
        {one ? "Component" : selected.length > 1 ? "Selection" : scope ? "Definition" : "Model"}
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
          info={props.infoOf(one.type)}
          problems={problemsOf(one.name)}
          onRename={(to) => props.onRename(one.name, to)}
          onSetParam={(k, v) => props.onSetParam(one.name, k, v)}
          onOpen={() => props.onOpenSubsystem(one.name)}
        />
      ) : selected.length > 1 ? (
        <div className="kn-panel-body">
          <div className="kn-pad">{selected.length} components selected.</div>
          <button className="kn-btn" data-testid="make-subsystem-panel" onClick={props.onMakeSubsystem}>
            Make subsystem
          </button>
          <div className="kn-muted kn-small kn-pad">
            Ctrl+C / Ctrl+V copy and paste them, Delete removes them.
          </div>
        </div>
      ) : (
        <ModelPanel
          body={body}
          isDefinition={!!scope}
          scopeName={scope}
          ctx={ctx}
          problems={props.scopeProblems}
          onModelParam={props.onModelParam}
          onRenameModelParam={props.onRenameModelParam}
          onSim={props.onSim}
          onField={props.onField}
          onPort={props.onPort}
        />
      )}
    </div>
  );
}
