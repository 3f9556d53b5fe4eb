// A plot's export: its data as CSV (the time and every curve drawn, named as in the legend,
// with the unit), and its picture as SVG (drawn again from the data, axes and ticks uPlot
// chose) or PNG (uPlot's canvas with the title and legend around it). Pure functions of
// what the plot holds, so the unit tests read them without a browser's canvas.

/** A CSV field: quoted when it holds a comma, a quote or a line break. */
function field(text) {
  const s = String(text);
  return /[",\n\r]/.test(s) ? `"${s.replace(/"/g, '""')}"` : s;
}

/** A number as CSV writes it: as many digits as the double holds, empty for a gap. */
function number(v) {
  return v == null || Number.isNaN(v) ? "" : String(v);
}

/**
 * The CSV of a plot: a header ("t [s]", each curve's label with the unit) and one row per
 * time of the grid.
 * @param {(number | null)[][]} data uPlot's data: the times, then one column per curve
 * @param {string[]} labels the curves' names (without the time)
 * @param {string} unit the curves' unit ("" for none)
 */
export function plotCsv(data, labels, unit) {
  const head = ["t [s]", ...labels.map((l) => (unit ? `${l} [${unit}]` : l))].map(field).join(",");
  const rows = [head];
  for (let i = 0; i < data[0].length; i++) rows.push(data.map((col) => number(col[i])).join(","));
  return `${rows.join("\n")}\n`;
}

function esc(text) {
  return String(text).replace(/&/g, "&amp;").replace(/</g, "&lt;").replace(/>/g, "&gt;").replace(/"/g, "&quot;");
}

/**
 * The SVG of a plot, drawn from its data within the ranges and at the ticks on screen.
 * @param {{title: string, unit: string, width: number, height: number,
 *   x: {min: number, max: number, ticks: number[], labels: string[]},
 *   y: {min: number, max: number, ticks: number[], labels: string[]},
 *   data: (number | null)[][],
 *   series: {label: string, stroke: string, width: number, dash?: number[]}[]}} plot
 */
export function plotSvg(plot) {
  const { width, height, x, y, data, series } = plot;
  const legendRows = Math.ceil(series.length / 2);
  const top = 26;
  const left = 64;
  const right = 16;
  const bottom = 34 + 16 * legendRows;
  const w = width - left - right;
  const h = height - top - bottom;
  const px = (v) => left + ((v - x.min) / (x.max - x.min || 1)) * w;
  const py = (v) => top + h - ((v - y.min) / (y.max - y.min || 1)) * h;
  const out = [
    `<svg xmlns="http://www.w3.org/2000/svg" width="${width}" height="${height}" viewBox="0 0 ${width} ${height}" font-family="system-ui, sans-serif" font-size="11">`,
    `<rect width="${width}" height="${height}" fill="#fff"/>`,
    `<text x="${left}" y="16" font-size="13" font-weight="600">${esc(plot.title)}${plot.unit ? ` [${esc(plot.unit)}]` : ""}</text>`,
  ];
  x.ticks.forEach((v, i) => {
    const at = px(v).toFixed(1);
    out.push(`<line x1="${at}" x2="${at}" y1="${top}" y2="${top + h}" stroke="#eceef1"/>`);
    out.push(`<text x="${at}" y="${top + h + 15}" text-anchor="middle" fill="#555">${esc(x.labels[i])}</text>`);
  });
  y.ticks.forEach((v, i) => {
    const at = py(v).toFixed(1);
    out.push(`<line x1="${left}" x2="${left + w}" y1="${at}" y2="${at}" stroke="#eceef1"/>`);
    out.push(`<text x="${left - 6}" y="${at}" dy="0.35em" text-anchor="end" fill="#555">${esc(y.labels[i])}</text>`);
  });
  out.push(`<rect x="${left}" y="${top}" width="${w}" height="${h}" fill="none" stroke="#ccc"/>`);
  out.push(`<text x="${left + w / 2}" y="${top + h + 29}" text-anchor="middle" fill="#555">t [s]</text>`);
  out.push(`<clipPath id="kn-area"><rect x="${left}" y="${top}" width="${w}" height="${h}"/></clipPath>`);
  series.forEach((s, k) => {
    const col = data[k + 1];
    let d = "";
    let pen = "M";
    for (let i = 0; i < data[0].length; i++) {
      const v = col[i];
      if (v == null || Number.isNaN(v)) continue;
      d += `${pen}${px(data[0][i]).toFixed(2)} ${py(v).toFixed(2)}`;
      pen = "L";
    }
    const dash = s.dash ? ` stroke-dasharray="${s.dash.join(" ")}"` : "";
    out.push(`<path d="${d}" fill="none" stroke="${s.stroke}" stroke-width="${s.width}"${dash} clip-path="url(#kn-area)"/>`);
    const lx = left + (k % 2) * (w / 2);
    const ly = top + h + 44 + 16 * Math.floor(k / 2);
    out.push(`<line x1="${lx}" x2="${lx + 16}" y1="${ly - 4}" y2="${ly - 4}" stroke="${s.stroke}" stroke-width="2"${dash}/>`);
    out.push(`<text x="${lx + 22}" y="${ly}">${esc(s.label)}</text>`);
  });
  out.push("</svg>");
  return `${out.join("\n")}\n`;
}

/** Offer ``blob`` to the user as the file ``name`` (the browser's download). */
export function download(blob, name) {
  const url = URL.createObjectURL(blob);
  const a = document.createElement("a");
  a.href = url;
  a.download = name;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 1000);
}

/** A file name made of words: "double_pendulum-angle". */
export function fileName(...parts) {
  return parts.filter(Boolean).map((p) => String(p).replace(/[^A-Za-z0-9_.-]+/g, "_")).join("-");
}
