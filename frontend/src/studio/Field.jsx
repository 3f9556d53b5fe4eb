// A one-line text field of the panels: an edit is committed once, on Enter or on leaving it.
import { useRef, useState } from "react";

/**
 * A text field that commits on Enter or when it loses focus (one undo step per edit);
 * Escape puts back the value it had before the edit, and commits nothing.
 */
/**
 * @param {{value: string, onCommit: (text: string) => unknown, testid?: string, placeholder?: string,
 *   className?: string, list?: string, bad?: boolean, title?: string}} props
 */
export function Field({ value, onCommit, testid, placeholder, className, list, bad, title }) {
  // the text being typed, while the field is edited; the value otherwise
  const [draft, setDraft] = useState(null);
  const settled = useRef(false);
  const finish = (commit) => {
    if (settled.current) return;
    settled.current = true;
    if (commit && draft !== null && draft !== value) onCommit(draft);
    setDraft(null);
  };
  return (
    <input
      className={`kn-input ${className || ""} ${bad ? "bad" : ""}`}
      value={draft ?? value}
      placeholder={placeholder}
      data-testid={testid}
      list={list}
      title={title}
      spellCheck={false}
      onFocus={() => {
        settled.current = false;
        setDraft(value);
      }}
      onBlur={() => finish(true)}
      onChange={(e) => setDraft(e.target.value)}
      onKeyDown={(e) => {
        if (e.key === "Enter") {
          finish(true);
          e.currentTarget.blur();
        } else if (e.key === "Escape") {
          e.stopPropagation();
          finish(false);
          e.currentTarget.blur();
        }
      }}
    />
  );
}
