// A Bode plot of a linearisation: magnitude (dB) and phase (degrees) against frequency on a
// log scale, for one input-output pair at a time (uPlot).
import { useEffect, useRef, useState } from "react";
import uPlot from "uplot";

const WIDTH = 300;
const HEIGHT = 130;

function Chart({ x, y, label, testid }) {
  const ref = useRef(null);
  useEffect(() => {
    const el = ref.current;
    if (!el) return undefined;
    const u = new uPlot(
      {
        width: WIDTH,
        height: HEIGHT,
        scales: { x: { time: false, distr: 3 } },
        legend: { show: false },
        axes: [
          { stroke: "#555", size: 28, grid: { stroke: "#eceef1" } },
          { stroke: "#555", size: 44, grid: { stroke: "#eceef1" }, label, labelSize: 14 },
        ],
        series: [{}, { stroke: "#1f77b4", width: 1.6, spanGaps: true }],
      },
      [x, y],
      el,
    );
    return () => u.destroy();
  }, [x, y, label]);
  return <div ref={ref} data-testid={testid} />;
}

/**
 * @param {{bode: {omega: number[], pairs: {input: string, output: string, mag_db: number[], phase_deg: number[]}[]}}} props
 */
export default function Bode({ bode }) {
  const [k, setK] = useState(0);
  const pair = bode.pairs[Math.min(k, bode.pairs.length - 1)];
  if (!pair) return null;
  return (
    <div className="kn-bode" data-testid="bode">
      <div className="kn-section">Bode plot, ω in rad/s</div>
      {bode.pairs.length > 1 ? (
        <select className="kn-input" value={k} data-testid="bode-pair" onChange={(e) => setK(Number(e.target.value))}>
          {bode.pairs.map((p, i) => (
            <option key={i} value={i}>
              {p.input} → {p.output}
            </option>
          ))}
        </select>
      ) : (
        <div className="kn-muted kn-small">
          {pair.input} → {pair.output}
        </div>
      )}
      <Chart x={bode.omega} y={pair.mag_db} label="dB" testid="bode-mag" />
      <Chart x={bode.omega} y={pair.phase_deg} label="deg" testid="bode-phase" />
    </div>
  );
}
