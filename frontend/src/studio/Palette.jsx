// The component palette: every type of GET /api/palette, grouped by library, searchable;
// drag a type onto the canvas (or double-click it) to place it. The type under the mouse
// (or the last clicked) is described below the list: doc, ports, parameters with units.
import { useMemo, useState } from "react";
import { TypeIcon, LIBRARY_COLORS } from "./icons.jsx";
import { DOMAIN_COLORS } from "./model.js";
import { formatValue } from "./values.js";
import { DRAG_MIME } from "./Canvas.jsx";
import { search } from "./search.js";
import { docParts, plainDoc } from "./doctext.js";

function firstLine(doc) {
  return String(doc || "").trim().split("\n")[0];
}

/** A docstring's text with its literals (``r``) as code. @param {{text: string}} props */
function Doc({ text }) {
  return docParts(text).map((p, i) => (p.code ? <code key={i}>{p.text}</code> : p.text));
}

export function TypeInfoCard({ info }) {
  if (!info) {
    return (
      <div className="kn-typeinfo kn-muted" data-testid="palette-info">
        Point at a component to read what it is: its ports, its parameters with their units.
        Drag it onto the diagram (or double-click it) to place it.
      </div>
    );
  }
  return (
    <div className="kn-typeinfo" data-testid="palette-info">
      <div className="kn-typeinfo-title">{info.type}</div>
      <div className="kn-typeinfo-doc"><Doc text={String(info.doc || "").trim()} /></div>
      {info.ports && info.ports.length > 0 && (
        <>
          <div className="kn-typeinfo-h">Ports</div>
          <ul className="kn-typeinfo-ports">
            {info.ports.map((p) => (
              <li key={p.name}>
                <span className="kn-dot" style={{ background: DOMAIN_COLORS[p.domain] || "#888" }} />
                <b>{p.name}</b> <span className="kn-muted">{p.domain}{p.optional ? ", optional" : ""}</span>
                {p.doc ? <div className="kn-muted kn-small"><Doc text={p.doc} /></div> : null}
              </li>
            ))}
          </ul>
        </>
      )}
      {info.params && info.params.length > 0 && (
        <>
          <div className="kn-typeinfo-h">Parameters</div>
          <table className="kn-typeinfo-params">
            <tbody>
              {info.params.map((p) => (
                <tr key={p.name}>
                  <td><b>{p.name}</b></td>
                  <td className="kn-unit">{p.unit || ""}</td>
                  <td className="kn-muted">
                    {p.required ? "required" : `= ${formatValue(p.default) || "none"}`}
                    {p.min != null ? `, ≥ ${p.min}` : ""}
                    {p.max != null ? `, ≤ ${p.max}` : ""}
                    {p.doc ? <div className="kn-small"><Doc text={p.doc} /></div> : null}
                  </td>
                </tr>
              ))}
            </tbody>
          </table>
        </>
      )}
    </div>
  );
}

/**
 * @param {{palette: any, definitions: any[], onAdd: (type: string) => void}} props
 */
export default function Palette({ palette, definitions, onAdd }) {
  const [query, setQuery] = useState("");
  const [shown, setShown] = useState(null);
  const [collapsed, setCollapsed] = useState({});
  // the libraries; while searching, one list of what matches, best first
  const libs = useMemo(() => {
    if (!palette) return [];
    const all = palette.libraries.map((lib) => ({ name: lib.name, types: lib.types }));
    if (definitions && definitions.length) all.push({ name: "subsystems", types: definitions, subsystem: true });
    if (!query.trim()) return all;
    const subsystems = new Set((definitions || []).map((d) => d.type));
    const found = search(all.flatMap((l) => l.types), query);
    return found.length ? [{ name: "matches", types: found, ranked: true, subsystems }] : [];
  }, [palette, definitions, query]);
  const info = shown && ((palette && palette.types[shown]) || (definitions || []).find((d) => d.type === shown));

  return (
    <div className="kn-palette" data-testid="palette" data-ready={palette ? "1" : "0"} data-query={query}>
      <input
        className="kn-search"
        type="search"
        placeholder="Search components…"
        value={query}
        onChange={(e) => setQuery(e.target.value)}
        data-testid="palette-search"
      />
      <div className="kn-palette-list">
        {!palette && <div className="kn-muted kn-pad">Loading the palette…</div>}
        {palette && query.trim() && !libs.length ? <div className="kn-muted kn-pad" data-testid="palette-none">Nothing matches “{query.trim()}”.</div> : null}
        {libs.map((lib) => (
          <div key={lib.name} className="kn-lib">
            <div
              className="kn-lib-name"
              style={{ borderLeftColor: LIBRARY_COLORS[lib.subsystem ? "subsystem" : lib.name] || "#888" }}
              data-testid={`palette-lib-${lib.name}`}
              onClick={() => setCollapsed((c) => ({ ...c, [lib.name]: !c[lib.name] }))}
            >
              <span>{collapsed[lib.name] && !query ? "▸" : "▾"}</span> {lib.name}
              <span className="kn-muted kn-count">{lib.types.length}</span>
            </div>
            {(!collapsed[lib.name] || query) &&
              lib.types.map((t) => (
                <div
                  key={t.type}
                  className={`kn-palette-item ${shown === t.type ? "shown" : ""}`}
                  data-testid={`palette-${t.type}`}
                  draggable
                  onDragStart={(e) => {
                    e.dataTransfer.setData(DRAG_MIME, t.type);
                    e.dataTransfer.effectAllowed = "copy";
                  }}
                  onMouseEnter={() => setShown(t.type)}
                  onClick={() => setShown(t.type)}
                  onDoubleClick={() => onAdd(t.type)}
                  title={`${t.type}\n${plainDoc(firstLine(t.doc))}\n\n${(t.params || [])
                    .map((p) => `${p.name}${p.unit ? ` [${p.unit}]` : ""}${p.doc ? `: ${plainDoc(p.doc)}` : ""}`)
                    .join("\n")}`}
                >
                  <TypeIcon type={t.type} subsystem={lib.subsystem || (lib.subsystems && lib.subsystems.has(t.type))} size={0.75} />
                  <div className="kn-palette-text">
                    <div className="kn-palette-type">
                      {t.type.split(".").pop()}
                      {lib.ranked && t.type.includes(".") ? <span className="kn-muted kn-small"> {t.type.split(".")[0]}</span> : null}
                    </div>
                    <div className="kn-palette-doc"><Doc text={firstLine(t.doc)} /></div>
                  </div>
                </div>
              ))}
          </div>
        ))}
      </div>
      <TypeInfoCard info={info} />
    </div>
  );
}
