// Subsystem definitions: which scope the diagram shows (the model, or a definition opened
// from it), what a block's position is there, and the definition files the model needs,
// fetched into the store's cache as they are met.
import { useCallback, useEffect, useMemo } from "react";
import { api } from "../api.js";
import { layoutBlocks } from "../layout.js";
import { resolveDef, resolveScope, shapeProblem, typeInfo, definitionSource } from "../model.js";
import { useStudio } from "../store.js";

/**
 * @typedef {object} Scope
 * @property {any} rootCtx  {palette, doc, docPath, defCache} of the model
 * @property {any} body     the body shown: the model, or the definition opened
 * @property {any} ctx      the context inside that body
 * @property {string | null} scope the definition opened, or null
 * @property {string} scopeKey
 * @property {any} resolved
 * @property {(name: string) => ({x: number, y: number} | null)} posOf
 */

/**
 * The scope shown and how to read it.
 * @returns {Scope}
 */
export function useScope() {
  const palette = useStudio((s) => s.palette);
  const doc = useStudio((s) => s.hist.present);
  const docPath = useStudio((s) => s.file.path);
  const defCache = useStudio((s) => s.defCache);
  const scopes = useStudio((s) => s.scopes);
  const autoPos = useStudio((s) => s.autoPos);
  const rootCtx = useMemo(() => ({ palette, doc, docPath, defCache }), [palette, doc, docPath, defCache]);
  const resolved = useMemo(() => resolveScope(scopes, rootCtx), [scopes, rootCtx]);
  const body = resolved ? resolved.body : doc;
  const ctx = resolved ? resolved.ctx : rootCtx;
  const scopeKey = scopes.join("/");
  const posOf = useCallback(
    (name) => {
      const l = body.layout && body.layout[name];
      if (l && typeof l.x === "number" && typeof l.y === "number") return l;
      return (autoPos[scopeKey] && autoPos[scopeKey][name]) || null;
    },
    [body, autoPos, scopeKey],
  );
  return { rootCtx, resolved, body, ctx, scope: scopes.length ? scopes[scopes.length - 1] : null, scopeKey, posOf };
}

/** The root-relative paths of definition files the document places and the cache lacks. */
export function wantedFiles(doc, rootCtx) {
  const { palette, defCache } = rootCtx;
  const want = new Set();
  const seen = new Set();
  const visit = (b, c, depth) => {
    if (depth > 16) return;
    for (const comp of b.components || []) {
      if (palette.types[comp.type] || seen.has(`${c.docPath}|${comp.type}`)) continue;
      seen.add(`${c.docPath}|${comp.type}`);
      const r = resolveDef(comp.type, c);
      if (!r) continue;
      if (r.body) visit(r.body, r.ctx, depth + 1);
      else if (r.src.kind === "file" && !defCache[r.src.key]) want.add(r.src.key);
    }
    for (const [name, entry] of Object.entries(b.definitions || {})) {
      if (entry && typeof entry === "object" && !entry.file) visit(entry, c, depth + 1);
      else if (entry && typeof entry.file === "string") {
        const r = resolveDef(name, c);
        if (r && !r.body && r.src.kind === "file" && !defCache[r.src.key]) want.add(r.src.key);
      }
    }
  };
  visit(doc, rootCtx, 0);
  return [...want];
}

/**
 * The studio's work on definitions: fetch the files the model needs; leave a definition
 * that is gone (undo, delete); lay out a definition opened without a layout; give blocks
 * without a place one.
 */
export function useDefinitions() {
  const { rootCtx, resolved, body, ctx, scopeKey, posOf } = useScope();
  const scopes = useStudio((s) => s.scopes);
  const doc = rootCtx.doc;

  useEffect(() => {
    if (!rootCtx.palette) return;
    const want = wantedFiles(doc, rootCtx);
    if (!want.length) return;
    const cache = (key, entry) => useStudio.setState((s) => ({ defCache: { ...s.defCache, [key]: entry } }));
    for (const key of want) {
      cache(key, { status: "loading" });
      api
        .openPath(key)
        .then((r) => cache(key, shapeProblem(r.model) ? { status: "missing" } : { status: "ok", model: r.model }))
        .catch(() => cache(key, { status: "missing" }));
    }
  }, [doc, rootCtx]);

  // a scope whose definition is gone (undo, delete): back to the model
  useEffect(() => {
    if (!scopes.length || resolved) return;
    const pending = scopes.some((s) => {
      const r = resolveDef(s, rootCtx);
      return r && !r.body && !r.missing;
    });
    if (!pending) useStudio.getState().setScopes([]);
  }, [scopes, resolved, rootCtx]);

  // blocks the layout does not place: the studio's own layered layout
  useEffect(() => {
    const missing = (body.components || []).map((c) => c.name).filter((n) => !posOf(n));
    // laid out once the ports of every block are known: definitions still loading wait
    const loading = (body.components || []).some((c) => {
      const r = !typeInfo(c.type, ctx) && resolveDef(c.type, ctx);
      return r && !r.body && !r.missing;
    });
    if (missing.length && !loading) useStudio.getState().setAutoPos(scopeKey, layoutBlocks(body, missing, ctx, typeInfo));
  }, [body, ctx, posOf, scopeKey]);
}
/** TypeInfo of the definitions the model has or places: the palette's "subsystems" group. */
export function useDefinitionTypes() {
  const { rootCtx } = useScope();
  return useMemo(() => {
    const { palette, doc, docPath } = rootCtx;
    if (!palette) return [];
    const names = new Set(Object.keys(doc.definitions || {}));
    for (const c of doc.components || []) if (!palette.types[c.type] && definitionSource(doc, docPath, c.type, palette)) names.add(c.type);
    return [...names].map((n) => typeInfo(n, rootCtx)).filter(Boolean);
  }, [rootCtx]);
}
