// The panel of the model (or of the definition opened): its name, description, parameters,
// exposed ports, and the simulation settings.
import { useState } from "react";
import { IDENT } from "./model.js";
import { formatValue, parseValue } from "./values.js";
import { useStudio } from "./store.js";
import { Field } from "./Field.jsx";

/**
 * The model (or the definition opened): name, description, parameters, and the simulation
 * settings, whose names, units, bounds and methods come from the server (GET /api/facts).
 */
/**
 * @param {{body: any, isDefinition: boolean, scopeName: string | null, problems: any[], edit: import("./hooks/useEditing.js").Edit}} props
 */
export default function ModelPanel({ body, isDefinition, scopeName, problems, edit }) {
  const facts = useStudio((s) => s.facts);
  const { setModelParam: onModelParam, renameModelParam: onRenameModelParam, setSim: onSim, setField: onField, setPort: onPort } = edit;
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
          {!facts ? <div className="kn-muted kn-pad">Loading the settings…</div> : null}
          {(facts ? facts.settings : []).map((f) => (
            <div className="kn-sim" key={f.name}>
              <label title={f.doc}>
                {f.name} {f.unit ? <span className="kn-unit">[{f.unit}]</span> : null}
              </label>
              {f.name === "method" ? (
                <select
                  className="kn-input"
                  value={sim.method ?? ""}
                  data-testid="sim-method"
                  title={(facts.methods.find((m) => m.name === (sim.method ?? f.default)) || {}).doc}
                  onChange={(e) => onSim("method", e.target.value || undefined)}
                >
                  <option value="">{`default (${f.default})`}</option>
                  {facts.methods.map((m) => (
                    <option key={m.name} value={m.name} title={m.doc}>
                      {m.name}
                    </option>
                  ))}
                </select>
              ) : (
                <Field
                  value={formatValue(sim[f.name])}
                  testid={`sim-${f.name}`}
                  placeholder={f.default == null ? "default" : `default ${formatValue(f.default)}`}
                  title={f.doc}
                  onCommit={(t) => onSim(f.name, parseValue(t))}
                />
              )}
            </div>
          ))}
        </>
      )}
      {modelProblems.length > 0 && (
        <div className="kn-section">Problems of the {isDefinition ? "definition" : "model"}</div>
      )}
      {modelProblems.map((m, i) => (
        <div key={i} className="kn-param-problem" title={m.hint || undefined}>{m.text}</div>
      ))}
    </div>
  );
}

