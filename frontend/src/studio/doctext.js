// A component's docstring as the studio shows it: its reStructuredText literals (``r``, and
// `r` or :math:`r` with a role) are code, not text with backticks round it.
const LITERAL = /(?::[a-z]+:)?``([^`]+)``|(?::[a-z]+:)?`([^`]+)`/g;

/**
 * The text in pieces: plain text, and the literals it marks as code.
 * @param {string} text @returns {{text: string, code: boolean}[]}
 */
export function docParts(text) {
  const s = String(text || "");
  const parts = [];
  let at = 0;
  for (const m of s.matchAll(LITERAL)) {
    if (m.index > at) parts.push({ text: s.slice(at, m.index), code: false });
    parts.push({ text: m[1] ?? m[2], code: true });
    at = m.index + m[0].length;
  }
  if (at < s.length) parts.push({ text: s.slice(at), code: false });
  return parts;
}

/** The text without its marks, where nothing can be styled (a tooltip). @param {string} text */
export function plainDoc(text) {
  return docParts(text).map((p) => p.text).join("");
}
