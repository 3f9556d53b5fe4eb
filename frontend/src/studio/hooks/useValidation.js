// Validation follows the document: 350 ms after the last edit the model goes to the server's
// checker (the checker of kn.load), and its problems are placed on the blocks they name.
import { useEffect, useMemo } from "react";
import { api } from "../api.js";
import { placeOf } from "../problems.js";
import { useStudio } from "../store.js";

export const DEBOUNCE_MS = 350;

/** Run the debounced validation of the document (once, in App). */
export function useValidation() {
  const doc = useStudio((s) => s.hist.present);
  const path = useStudio((s) => s.file.path);
  const ready = useStudio((s) => !!s.palette);
  useEffect(() => {
    if (!ready) return undefined;
    let gone = false;
    const id = setTimeout(() => {
      api
        .validate(doc, path)
        .then((r) => !gone && useStudio.setState({ validation: { ok: r.ok, problems: r.problems || [], summary: r.summary || null, doc } }))
        .catch((e) => {
          if (gone) return;
          const problems = e.problems && e.problems.length ? e.problems : [{ message: e.message }];
          useStudio.setState({ validation: { ok: false, problems, summary: null, doc } });
        });
    }, DEBOUNCE_MS);
    return () => {
      gone = true;
      clearTimeout(id);
    };
  }, [doc, path, ready]);
}

/**
 * Every problem known, placed: validation's, then the last run's (marked ``run``).
 * @returns {import("../problems.js").Place[]}
 */
export function usePlaces() {
  const problems = useStudio((s) => s.validation.problems);
  const run = useStudio((s) => s.run);
  return useMemo(
    () => [...problems.map(placeOf), ...((run && run.problems) || []).map((p) => ({ ...placeOf(p), run: true }))],
    [problems, run],
  );
}

/** The problems of the scope shown, and a block's. */
export function useScopeProblems(scope) {
  const places = usePlaces();
  const here = useMemo(() => places.filter((p) => p.scope === (scope || "")), [places, scope]);
  const byBlock = useMemo(() => {
    const out = new Map();
    for (const p of here) {
      if (!p.component) continue;
      if (!out.has(p.component)) out.set(p.component, []);
      out.get(p.component).push(p);
    }
    return out;
  }, [here]);
  return { places, here, byBlock };
}
