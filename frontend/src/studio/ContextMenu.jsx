// The right-click menu of the diagram: on a block (rename, open, duplicate, rotate, flip, make
// subsystem, copy, delete), on a selection, on a wire, and on the empty diagram (paste here,
// select all). Every item is an edit of the model, undone like any other.
import { useRef } from "react";
import { useClickAway } from "./hooks/useClickAway.js";
import { useStudio } from "./store.js";
import { resolveDef } from "./model.js";
import { findRepeat } from "./fold.js";

/**
 * @param {{edit: import("./hooks/useEditing.js").Edit, scope: import("./hooks/useDefinitions.js").Scope}} props
 */
export default function ContextMenu({ edit, scope }) {
  const menu = useStudio((s) => s.menu);
  const selection = useStudio((s) => s.selection);
  const setMenu = useStudio((s) => s.setMenu);
  const ref = useRef(null);

  useClickAway(ref, Boolean(menu), () => setMenu(null), true);

  if (!menu) return null;
  const { target } = menu;
  const blocks = selection.filter((n) => !n.startsWith("@"));
  const items = [];
  const add = (id, label, run, keys) => items.push({ id, label, run, keys });
  if (target.kind === "node" || target.kind === "selection") {
    const one = target.kind === "node" && blocks.length <= 1 ? target.id : null;
    const comp = one && (scope.body.components || []).find((c) => c.name === one);
    if (one) add("rename", "Rename…", () => edit.askRename(one), "");
    if (comp && resolveDef(comp.type, scope.ctx)) add("open", "Open subsystem", () => edit.open(one), "double-click");
    add("duplicate", "Duplicate", () => edit.duplicate(blocks), "Ctrl+D");
    add("rotate", "Rotate 90°", () => edit.rotate(blocks), "Ctrl+R");
    add("flip", "Flip left–right", () => edit.flip(blocks), "");
    add("make-subsystem", "Make subsystem…", () => edit.makeSub(blocks), "");
    add("copy", "Copy", () => edit.copy(), "Ctrl+C");
    add("delete", "Delete", () => edit.removeSelected(), "Del");
  } else if (target.kind === "edge") {
    add("delete", "Delete wire", () => edit.remove([], [target.data]), "Del");
  } else if (target.kind === "port") {
    add("delete", "Stop exposing this port", () => edit.remove([target.id], []), "Del");
  } else {
    add("paste", "Paste here", () => edit.paste(menu.at), "Ctrl+V");
    add("select-all", "Select all", () => edit.selectAll(), "Ctrl+A");
    add("fit", "Fit to view", () => useStudio.getState().fit(), "");
    if (findRepeat(scope.body)) add("fold", "Fold repeated blocks into subsystems…", () => edit.fold(), "");
  }
  const style = { left: Math.min(menu.x, window.innerWidth - 220), top: Math.min(menu.y, window.innerHeight - 34 * items.length - 12) };
  return (
    <div className="kn-menu" ref={ref} style={style} data-testid="context-menu" role="menu" onContextMenu={(e) => e.preventDefault()}>
      {items.map((it) => (
        <button
          key={it.id}
          className="kn-menu-item"
          role="menuitem"
          data-testid={`menu-${it.id}`}
          onClick={() => {
            setMenu(null);
            it.run();
          }}
        >
          <span>{it.label}</span>
          {it.keys ? <span className="kn-muted kn-small">{it.keys}</span> : null}
        </button>
      ))}
    </div>
  );
}
