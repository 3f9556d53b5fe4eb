// The bar above everything: files, undo and redo, Run and Cancel with the run's progress,
// and the model's name with its file and whether it has unsaved changes.
import { runStatus } from "./runs.js";
import { useStudio } from "./store.js";

/**
 * @param {{files: ReturnType<typeof import("./hooks/useFiles.js").useFiles>, edit: import("./hooks/useEditing.js").Edit,
 *   runner: ReturnType<typeof import("./hooks/useRun.js").useRun>, onOpen: () => void}} props
 */
export default function Toolbar({ files, edit, runner, onOpen }) {
  const name = useStudio((s) => s.hist.present.name);
  const file = useStudio((s) => s.file);
  const busy = useStudio((s) => s.busy);
  const canUndo = useStudio((s) => s.hist.past.length > 0);
  const canRedo = useStudio((s) => s.hist.future.length > 0);
  const hasSelection = useStudio((s) => s.selection.length > 0);
  const run = useStudio((s) => s.run);
  const undo = useStudio((s) => s.undo);
  const redo = useStudio((s) => s.redo);
  const going = runner.going;
  const cancelling = run && run.state === "cancelling";
  const where = file.path || (file.example ? `example ${file.example}` : "not saved");
  return (
    <header className="kn-bar">
      <div className="kn-brand" title="kinetwork studio">
        <svg viewBox="0 0 16 16" width="18" height="18">
          <circle cx="4" cy="4" r="3" fill="#5f5f5f" />
          <circle cx="12" cy="12" r="3" fill="#007f00" />
          <path d="M4 4L12 12" stroke="#404040" strokeWidth="2" />
        </svg>
        <span className="kn-brand-name">kinetwork</span>
      </div>
      <div className="kn-group">
        <button className="kn-btn" data-testid="new" onClick={files.newModel} title="A new, empty model">New</button>
        <button className="kn-btn" data-testid="open" onClick={onOpen} title="Open a model file or an example">Open…</button>
        <button className="kn-btn" data-testid="save" onClick={files.save} title="Save (Ctrl+S)">Save</button>
        <button className="kn-btn" data-testid="save-as" onClick={files.saveAs}>Save as…</button>
      </div>
      <div className="kn-group">
        <button className="kn-btn" data-testid="undo" disabled={!canUndo} onClick={undo} title="Undo (Ctrl+Z)">↶</button>
        <button className="kn-btn" data-testid="redo" disabled={!canRedo} onClick={redo} title="Redo (Ctrl+Y)">↷</button>
        <button className="kn-btn" data-testid="make-subsystem" disabled={!hasSelection} onClick={() => edit.makeSub()} title="Turn the selected blocks into a subsystem">Make subsystem</button>
      </div>
      <div className="kn-group">
        <button className="kn-btn kn-run" data-testid="run" disabled={going} onClick={runner.run} title="Simulate the model">▶ Run</button>
        <button
          className={`kn-btn ${cancelling ? "kn-cancelling" : ""}`}
          data-testid="cancel"
          data-state={cancelling ? "cancelling" : going ? "ready" : "idle"}
          disabled={!going || cancelling}
          onClick={runner.cancel}
          title="Stop the run: what it computed so far is kept and plotted"
        >
          {cancelling ? "Cancelling…" : "■ Cancel"}
        </button>
        <div className={`kn-progress ${going ? "on" : ""}`} data-testid="progress" data-state={run ? run.state : "idle"}>
          <div className="kn-progress-bar" style={{ width: `${Math.round(((run && run.progress) || 0) * 100)}%` }} />
        </div>
        <span className="kn-status" data-testid="run-status" data-state={run ? run.state : "idle"}>
          {runStatus(run)}
        </span>
      </div>
      {/* the name never gives way to the path, nor the unsaved mark to either: what is cut
          shows "…", and the whole is the title */}
      <div className="kn-file" data-testid="file" title={`${name} · ${where}${files.dirty ? " · unsaved changes" : ""}`}>
        {busy ? <span className="kn-muted kn-file-busy">{busy}</span> : null}
        <b className="kn-file-name">{name}</b>
        <span className="kn-muted">·</span>
        {/* cut at its start, so that the file's own name shows */}
        <span className="kn-muted kn-file-path">
          <bdi>{where}</bdi>
        </span>
        {files.dirty ? (
          <span className="kn-dirty" data-testid="dirty" title="unsaved changes">
            ●
          </span>
        ) : null}
      </div>
    </header>
  );
}
