// The model as text: its JSON, editable, checked as it is typed (the JSON itself here, the
// model by the server's checker, as the diagram's edits are), and applied as one undoable
// edit. Untouched, the text follows the diagram.
import { useEffect, useRef, useState } from "react";
import { api } from "./api.js";
import { shapeProblem } from "./model.js";
import { parseJson } from "./values.js";
import { placeOf } from "./problems.js";
import { studio, useStudio } from "./store.js";
import { DEBOUNCE_MS } from "./hooks/useValidation.js";

export default function JsonView() {
  const doc = useStudio((s) => s.hist.present);
  const path = useStudio((s) => s.file.path);
  const shown = JSON.stringify(doc, null, 2);
  // the text being edited (null: the model's own)
  const [draft, setDraft] = useState(null);
  const [check, setCheck] = useState({ error: null, problems: null, checking: false });
  const timer = useRef(null);
  const seq = useRef(0);
  useEffect(() => () => clearTimeout(timer.current), []);

  const onChange = (text) => {
    setDraft(text);
    clearTimeout(timer.current);
    const { value, error } = parseJson(text);
    const shape = error ? null : shapeProblem(value);
    if (error || shape) {
      setCheck({ error: error || shape, problems: null, checking: false });
      return;
    }
    setCheck({ error: null, problems: null, checking: true });
    const mine = ++seq.current;
    timer.current = setTimeout(() => {
      api
        .validate(value, path)
        .then((r) => mine === seq.current && setCheck({ error: null, problems: (r.problems || []).map(placeOf), checking: false }))
        .catch((e) => mine === seq.current && setCheck({ error: e.message, problems: null, checking: false }));
    }, DEBOUNCE_MS);
  };

  const apply = () => {
    const { value, error } = parseJson(draft);
    if (error || shapeProblem(value)) return;
    studio().update(() => value);
    setDraft(null);
    setCheck({ error: null, problems: null, checking: false });
  };

  const text = draft ?? shown;
  const edited = draft !== null && draft !== shown;
  const bad = !!check.error;
  const state = !edited ? "the model as saved in its file" : check.error ? check.error : check.checking ? "checking…" : check.problems && check.problems.length ? `${check.problems.length} problem${check.problems.length > 1 ? "s" : ""}` : "valid";
  return (
    <div className="kn-json" data-testid="json-view">
      <textarea
        className={`kn-input kn-json-text ${bad ? "bad" : ""}`}
        spellCheck={false}
        value={text}
        data-testid="json-text"
        onChange={(e) => onChange(e.target.value)}
        onKeyDown={(e) => {
          if (e.key === "Enter" && (e.ctrlKey || e.metaKey)) {
            e.preventDefault();
            apply();
          } else if (e.key === "Escape") {
            setDraft(null);
            setCheck({ error: null, problems: null, checking: false });
          }
        }}
      />
      <div className="kn-json-bar">
        <span className={`kn-json-state ${bad ? "bad" : ""}`} data-testid="json-state" title={state}>
          {state}
        </span>
        <button
          className="kn-btn"
          disabled={!edited}
          onClick={() => {
            setDraft(null);
            setCheck({ error: null, problems: null, checking: false });
          }}
          title="Escape"
        >
          Revert
        </button>
        <button className="kn-btn kn-primary" data-testid="json-apply" disabled={!edited || bad} onClick={apply} title="Ctrl+Enter">
          Apply
        </button>
      </div>
      {edited && check.problems && check.problems.length ? (
        <div className="kn-json-problems" data-testid="json-problems">
          {check.problems.map((p, i) => (
            <div key={i} className="kn-param-problem">
              {p.text}
            </div>
          ))}
        </div>
      ) : null}
    </div>
  );
}
