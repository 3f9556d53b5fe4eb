// Modal dialogs: Open (the root's model files and the shipped examples), a one-line prompt,
// and a choice among a few buttons (unsaved changes, a file changed on disk, a recovery).
import { useEffect, useRef, useState } from "react";
import { api } from "./api.js";

export function Modal({ title, onClose, children, testid, wide = false }) {
  useEffect(() => {
    const onKey = (e) => e.key === "Escape" && onClose();
    window.addEventListener("keydown", onKey);
    return () => window.removeEventListener("keydown", onKey);
  }, [onClose]);
  return (
    <div className="kn-modal-back" onMouseDown={(e) => e.target === e.currentTarget && onClose()}>
      <div className={`kn-modal${wide ? " kn-modal-wide" : ""}`} data-testid={testid} role="dialog" aria-label={title}>
        <div className="kn-modal-title">
          {title}
          <button className="kn-icon-btn" onClick={onClose} title="close">×</button>
        </div>
        {children}
      </div>
    </div>
  );
}

export function OpenDialog({ onOpen, onClose }) {
  const [files, setFiles] = useState(null);
  const [root, setRoot] = useState("");
  const [examples, setExamples] = useState(null);
  const [filter, setFilter] = useState("");
  const [error, setError] = useState(null);
  useEffect(() => {
    api.files().then((r) => { setFiles(r.files || []); setRoot(r.root || ""); }).catch((e) => setError(e.message));
    api.examples().then((r) => setExamples(r.examples || [])).catch(() => setExamples([]));
  }, []);
  const f = filter.toLowerCase();
  return (
    <Modal title="Open a model" onClose={onClose} testid="open-dialog">
      <input className="kn-input" autoFocus placeholder="Filter…" value={filter} onChange={(e) => setFilter(e.target.value)} data-testid="open-filter" />
      {error ? <div className="kn-problem">{error}</div> : null}
      <div className="kn-open-cols">
        <div>
          <div className="kn-section">Files in {root || "the studio's folder"}</div>
          <div className="kn-open-list">
            {files === null ? <div className="kn-muted">Loading…</div> : null}
            {files && files.length === 0 ? <div className="kn-muted">No .json files here.</div> : null}
            {(files || []).filter((p) => p.toLowerCase().includes(f)).map((p) => (
              <button key={p} className="kn-open-item" data-testid={`file-${p}`} onClick={() => onOpen({ path: p })}>{p}</button>
            ))}
          </div>
        </div>
        <div>
          <div className="kn-section">Examples shipped with kinetwork</div>
          <div className="kn-open-list">
            {examples === null ? <div className="kn-muted">Loading…</div> : null}
            {(examples || []).filter((p) => p.toLowerCase().includes(f)).map((p) => (
              <button key={p} className="kn-open-item" data-testid={`example-${p}`} onClick={() => onOpen({ example: p })}>{p}</button>
            ))}
          </div>
        </div>
      </div>
    </Modal>
  );
}

export function PromptDialog({ title, label, value, onOk, onClose, testid }) {
  const [text, setText] = useState(value || "");
  const ref = useRef(null);
  useEffect(() => {
    if (ref.current) ref.current.select();
  }, []);
  return (
    <Modal title={title} onClose={onClose} testid="prompt-dialog">
      <label className="kn-prompt-label">{label}</label>
      <input
        ref={ref}
        className="kn-input"
        autoFocus
        value={text}
        data-testid={testid}
        onChange={(e) => setText(e.target.value)}
        onKeyDown={(e) => e.key === "Enter" && onOk(text)}
      />
      <div className="kn-modal-buttons">
        <button className="kn-btn" onClick={onClose}>Cancel</button>
        <button className="kn-btn kn-primary" data-testid="prompt-ok" onClick={() => onOk(text)}>OK</button>
      </div>
    </Modal>
  );
}

/** A question and its answers as buttons; Escape or a click outside is no answer (null). */
export function ChoiceDialog({ title, message, choices, resolve, testid }) {
  return (
    <Modal title={title} onClose={() => resolve(null)} testid={testid || "choice-dialog"}>
      <div className="kn-choice-message">{message}</div>
      <div className="kn-modal-buttons">
        {choices.map((c) => (
          <button key={c.id} className={`kn-btn ${c.primary ? "kn-primary" : ""}`} data-testid={`choice-${c.id}`} autoFocus={!!c.primary} onClick={() => resolve(c.id)}>
            {c.label}
          </button>
        ))}
      </div>
    </Modal>
  );
}
