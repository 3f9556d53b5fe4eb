// Closing what floats over the page (a menu, a popover) on a mouse press outside it.
import { useEffect } from "react";

/**
 * While ``active``, ``away()`` on a mouse press outside ``ref``'s element; ``capture``: before
 * the page's own handlers see the press (the diagram's, which would act on it first).
 * @param {import("react").RefObject<HTMLElement|null>} ref
 * @param {boolean} active
 * @param {() => void} away
 * @param {boolean} [capture]
 */
export function useClickAway(ref, active, away, capture = false) {
  useEffect(() => {
    if (!active) return undefined;
    const press = (/** @type {MouseEvent} */ e) => {
      if (ref.current && !ref.current.contains(/** @type {Node} */ (e.target))) away();
    };
    window.addEventListener("mousedown", press, capture);
    return () => window.removeEventListener("mousedown", press, capture);
  }, [ref, active, away, capture]);
}
