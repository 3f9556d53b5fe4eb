// The editing keys, where no text field has the focus: Delete, arrows (move the selection,
// Shift five times as far), Ctrl+Z / Ctrl+Y (Ctrl+Shift+Z), Ctrl+A, Ctrl+C, Ctrl+V (at the
// pointer), Ctrl+D (duplicate), Ctrl+R (rotate), Ctrl+S, Escape (close the menu, clear the
// selection).
import { useEffect } from "react";
import { studio } from "../store.js";
import { NUDGE } from "./useEditing.js";

const ARROWS = { ArrowLeft: [-1, 0], ArrowRight: [1, 0], ArrowUp: [0, -1], ArrowDown: [0, 1] };

function typing(target) {
  return !!target && (target.tagName === "INPUT" || target.tagName === "TEXTAREA" || target.tagName === "SELECT" || target.isContentEditable);
}

/**
 * @param {import("./useEditing.js").Edit} edit
 * @param {{save: () => unknown}} files
 */
export function useKeyboard(edit, files) {
  useEffect(() => {
    const onKey = (e) => {
      if (typing(e.target) || studio().dialog) return;
      const mod = e.ctrlKey || e.metaKey;
      if (e.key === "Escape") {
        if (studio().menu) studio().setMenu(null);
        else studio().select([]);
        return;
      }
      if (!mod && (e.key === "Delete" || e.key === "Backspace")) {
        e.preventDefault();
        edit.removeSelected();
        return;
      }
      if (!mod && ARROWS[e.key] && studio().selection.length) {
        e.preventDefault();
        const [dx, dy] = ARROWS[e.key];
        const step = e.shiftKey ? 5 * NUDGE : NUDGE;
        edit.nudge(dx * step, dy * step);
        return;
      }
      if (!mod) return;
      const k = e.key.toLowerCase();
      const selection = studio().selection;
      if (k === "z" && !e.shiftKey) studio().undo();
      else if (k === "y" || (k === "z" && e.shiftKey)) studio().redo();
      else if (k === "a") edit.selectAll();
      else if (k === "c") edit.copy();
      else if (k === "v") edit.paste(null);
      else if (k === "d") edit.duplicate(selection);
      else if (k === "r") edit.rotate(selection);
      else if (k === "s") files.save();
      else return;
      e.preventDefault();
    };
    window.addEventListener("keydown", onKey);
    return () => window.removeEventListener("keydown", onKey);
  }, [edit, files]);
}
