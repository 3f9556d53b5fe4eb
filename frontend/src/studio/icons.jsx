// Small schematic icons of the component types, in the spirit of the Modelica libraries'
// diagrams: drawn in a 48 x 28 box, stroked in the library's colour.

/** @type {import("react").SVGProps<SVGSVGElement>} */
const S = { fill: "none", strokeWidth: 1.6, strokeLinecap: "round", strokeLinejoin: "round" };

function Zigzag({ y = 14, x0 = 6, x1 = 42 }) {
  const n = 6;
  const w = (x1 - x0 - 8) / n;
  let d = `M${x0} ${y} H${x0 + 4}`;
  for (let i = 0; i < n; i++) d += ` L${x0 + 4 + w * (i + 0.5)} ${y + (i % 2 ? 5 : -5)}`;
  d += ` L${x1 - 4} ${y} H${x1}`;
  return <path d={d} />;
}

function Dashpot({ y = 14, x0 = 6, x1 = 42 }) {
  const m = (x0 + x1) / 2;
  return (
    <path d={`M${x0} ${y} H${m + 2} M${m - 6} ${y - 5} H${m + 6} V${y + 5} H${m - 6} M${m + 2} ${y - 3} V${y + 3} M${m + 2} ${y} M${m + 6} ${y} H${x1}`} />
  );
}

/** A mechanism of three joints in a row (MSL's Joints.Assemblies): its joints' letters. */
function Linkage({ ends, last }) {
  const mark = (x, y, kind) =>
    kind === "S" ? <circle cx={x} cy={y} r="3" fill="#fff" /> : kind === "U" ? <g><circle cx={x} cy={y} r="3" fill="#fff" /><path d={`M${x - 3} ${y} H${x + 3}`} /></g> : kind === "P" ? <rect x={x - 4} y={y - 2.5} width="8" height="5" fill="#fff" /> : <rect x={x - 2.5} y={y - 3} width="5" height="6" fill="#fff" />;
  return (
    <g>
      <path d="M4 22 H8 L18 6 L32 20 H40 H44" />
      {mark(8, 22, ends[0])}
      {mark(18, 6, ends[1])}
      {mark(36, 20, last)}
    </g>
  );
}

/** An electrical meter: a circle with the letter of what it reads. */
function Meter({ letter }) {
  return (
    <g>
      <path d="M4 14 H14 M34 14 H44" />
      <circle cx="24" cy="14" r="10" />
      <text x="24" y="18" textAnchor="middle" fontSize="11" fill="currentColor" stroke="none">{letter}</text>
    </g>
  );
}

const DRAW = {
  Ground: () => (
    <g>
      <path d="M8 18 H40" />
      {[10, 16, 22, 28, 34, 40].map((x) => <path key={x} d={`M${x} 18 L${x - 5} 25`} />)}
      <path d="M24 18 V5" />
    </g>
  ),
  Revolute: () => (
    <g>
      <path d="M4 14 H14 M34 14 H44" />
      <rect x="14" y="6" width="8" height="16" rx="1" />
      <rect x="26" y="6" width="8" height="16" rx="1" />
      <path d="M22 14 H26" strokeWidth="3" />
    </g>
  ),
  Prismatic: () => (
    <g>
      <path d="M4 14 H12 M36 14 H44" />
      <rect x="12" y="6" width="14" height="16" />
      <rect x="20" y="10" width="16" height="8" />
    </g>
  ),
  Universal: () => (
    <g>
      <path d="M4 14 H16 M32 14 H44" />
      <circle cx="24" cy="14" r="8" />
      <path d="M16 14 H32 M24 6 V22" />
    </g>
  ),
  Spherical: () => (
    <g>
      <path d="M4 14 H16 M32 14 H44" />
      <circle cx="24" cy="14" r="8" />
      <circle cx="24" cy="14" r="3" fill="currentColor" />
    </g>
  ),
  FreeMotion: () => (
    <g>
      <path d="M4 14 H12 M36 14 H44" strokeDasharray="2 3" />
      <path d="M14 20 L34 8 M34 8 L28 8 M34 8 L32 13" />
    </g>
  ),
  Cylindrical: () => (
    <g>
      <path d="M4 14 H12 M36 14 H44" />
      <ellipse cx="18" cy="14" rx="4" ry="8" />
      <path d="M18 6 H32 M18 22 H32" />
      <ellipse cx="32" cy="14" rx="4" ry="8" />
    </g>
  ),
  Planar: () => (
    <g>
      <path d="M4 14 H12 M36 14 H44" />
      <path d="M12 22 L18 6 H36 L30 22 Z" />
    </g>
  ),
  RigidBody: () => (
    <g>
      <path d="M4 14 H16" />
      <circle cx="28" cy="14" r="10" />
      <path d="M28 4 A10 10 0 0 1 38 14 H28 Z" fill="currentColor" />
      <path d="M28 14 V24 A10 10 0 0 1 18 14 Z" fill="currentColor" />
    </g>
  ),
  BodyBox: () => (
    <g>
      <path d="M4 14 H10 M38 14 H44" />
      <rect x="10" y="7" width="28" height="14" />
      <path d="M10 7 L14 4 H42 V18 L38 21 M38 7 L42 4" />
    </g>
  ),
  BodyCylinder: () => (
    <g>
      <path d="M4 14 H10 M38 14 H44" />
      <ellipse cx="12" cy="14" rx="3" ry="8" />
      <path d="M12 6 H36 M12 22 H36" />
      <ellipse cx="36" cy="14" rx="3" ry="8" />
    </g>
  ),
  BodySphere: () => (
    <g>
      <circle cx="24" cy="14" r="10" />
      <ellipse cx="24" cy="14" rx="10" ry="3.5" />
    </g>
  ),
  FixedTranslation: () => (
    <g>
      <path d="M4 14 H44" />
      <rect x="10" y="11" width="28" height="6" fill="currentColor" stroke="none" opacity="0.85" />
    </g>
  ),
  FixedRotation: () => (
    <g>
      <path d="M4 14 H14 M34 14 H44" />
      <path d="M14 14 A10 10 0 0 1 34 14" />
      <path d="M34 14 L30 10 M34 14 L36 9" />
    </g>
  ),
  SpringDamper: () => (
    <g>
      <path d="M4 14 H8 V8 M8 14 V20 M40 14 H44 M40 8 V20" />
      <Zigzag y={8} x0={8} x1={40} />
      <Dashpot y={20} x0={8} x1={40} />
    </g>
  ),
  Spring: () => <Zigzag />,
  Damper: () => <Dashpot />,
  WorldForce: () => (
    <g>
      <path d="M6 14 H40 M40 14 L33 9 M40 14 L33 19" strokeWidth="2.4" />
    </g>
  ),
  WorldTorque: () => (
    <g>
      <path d="M14 20 A10 10 0 1 1 34 20" strokeWidth="2.2" />
      <path d="M34 20 L29 18 M34 20 L35 15" strokeWidth="2.2" />
    </g>
  ),
  Torque: () => (
    <g>
      <path d="M14 20 A10 10 0 1 1 34 20" strokeWidth="2.2" />
      <path d="M34 20 L29 18 M34 20 L35 15" strokeWidth="2.2" />
    </g>
  ),
  Force: () => <path d="M6 14 H40 M40 14 L33 9 M40 14 L33 19" strokeWidth="2.4" />,
  Fixed: () => (
    <g>
      <path d="M24 4 V16 M10 16 H38" />
      {[12, 18, 24, 30, 36].map((x) => <path key={x} d={`M${x} 16 L${x - 5} 23`} />)}
    </g>
  ),
  Inertia: () => (
    <g>
      <path d="M4 14 H14 M34 14 H44" />
      <rect x="14" y="4" width="20" height="20" rx="2" fill="currentColor" opacity="0.25" />
      <rect x="14" y="4" width="20" height="20" rx="2" />
    </g>
  ),
  Mass: () => (
    <g>
      <path d="M4 14 H14 M34 14 H44" />
      <rect x="14" y="5" width="20" height="18" fill="currentColor" opacity="0.25" />
      <rect x="14" y="5" width="20" height="18" />
    </g>
  ),
  IdealGear: () => (
    <g>
      <path d="M4 10 H16 M32 18 H44" />
      <rect x="16" y="3" width="7" height="14" />
      <rect x="25" y="11" width="7" height="14" />
    </g>
  ),
  Position: () => (
    <g>
      <path d="M8 14 H40" />
      <path d="M16 22 L16 6 M32 22 L32 6" />
      <path d="M12 18 H36" strokeDasharray="2 2" />
    </g>
  ),
  Sensor: () => (
    <g>
      <path d="M12 22 A12 12 0 0 1 36 22" />
      <path d="M24 22 L31 12" strokeWidth="2" />
      <circle cx="24" cy="22" r="1.8" fill="currentColor" />
    </g>
  ),
  Probe: () => (
    <g>
      <circle cx="24" cy="14" r="9" />
      <path d="M19 17 L22 11 L26 16 L29 10" />
    </g>
  ),
  Constant: () => <path d="M8 14 H40" strokeWidth="2" />,
  Step: () => <path d="M6 22 H22 V6 H42" strokeWidth="2" />,
  Ramp: () => <path d="M6 22 H16 L32 6 H42" strokeWidth="2" />,
  Sine: () => <path d="M6 14 C12 0 16 0 20 14 C24 28 28 28 34 14 C36 9 38 7 42 6" strokeWidth="2" />,
  Table: () => (
    <g>
      <rect x="10" y="4" width="28" height="20" />
      <path d="M10 11 H38 M10 17 H38 M24 4 V24" />
    </g>
  ),
  Gain: () => <path d="M12 4 L38 14 L12 24 Z" />,
  Limiter: () => <path d="M6 22 H16 L32 6 H42" strokeWidth="2" />,
  Integrator: () => <text x="24" y="19" textAnchor="middle" fontSize="12" fill="currentColor" stroke="none">1/s</text>,
  Derivative: () => <text x="24" y="19" textAnchor="middle" fontSize="12" fill="currentColor" stroke="none">s</text>,
  FirstOrder: () => <path d="M6 22 C12 8 20 6 42 6" strokeWidth="2" />,
  PID: () => <text x="24" y="19" textAnchor="middle" fontSize="12" fill="currentColor" stroke="none" fontWeight="bold">PID</text>,
  Add: () => <text x="24" y="20" textAnchor="middle" fontSize="16" fill="currentColor" stroke="none">+</text>,
  Sum: () => <text x="24" y="20" textAnchor="middle" fontSize="16" fill="currentColor" stroke="none">Σ</text>,
  Product: () => <text x="24" y="20" textAnchor="middle" fontSize="16" fill="currentColor" stroke="none">×</text>,
  InverseDynamics: () => <text x="24" y="19" textAnchor="middle" fontSize="10" fill="currentColor" stroke="none">M·a+h</text>,
  BodyShape: () => (
    <g>
      <path d="M4 14 H12 M36 14 H44" />
      <rect x="12" y="9" width="24" height="10" rx="5" fill="currentColor" opacity="0.25" />
      <rect x="12" y="9" width="24" height="10" rx="5" />
    </g>
  ),
  SphericalSpherical: () => (
    <g>
      <path d="M4 14 H9 M39 14 H44 M15 14 H33" />
      <circle cx="12" cy="14" r="3.5" />
      <circle cx="36" cy="14" r="3.5" />
    </g>
  ),
  UniversalSpherical: () => (
    <g>
      <path d="M4 14 H7 M39 14 H44 M17 14 H33" />
      <circle cx="12" cy="14" r="5" />
      <path d="M7 14 H17 M12 9 V19" />
      <circle cx="36" cy="14" r="3.5" />
    </g>
  ),
  JointRRR: () => (
    <g>
      <path d="M6 22 L16 8 L30 20 L42 6" />
      <circle cx="16" cy="8" r="2.5" fill="#fff" />
      <circle cx="30" cy="20" r="2.5" fill="#fff" />
      <circle cx="6" cy="22" r="2.5" fill="#fff" />
    </g>
  ),
  ForceAndTorque: () => (
    <g>
      <path d="M6 18 H30 M30 18 L24 14 M30 18 L24 22" strokeWidth="2" />
      <path d="M30 10 A8 8 0 1 1 42 16" strokeWidth="1.6" />
    </g>
  ),
  Accelerate: () => (
    <g>
      <path d="M6 22 C16 22 26 18 40 6" strokeWidth="2" />
      <path d="M40 6 L34 7 M40 6 L38 12" strokeWidth="2" />
    </g>
  ),
  PointMass: () => (
    <g>
      <path d="M4 14 H18" />
      <circle cx="26" cy="14" r="7" fill="currentColor" />
    </g>
  ),
  JointUSR: () => <Linkage ends={["U", "S"]} last="R" />,
  JointSSR: () => <Linkage ends={["S", "S"]} last="R" />,
  JointUSP: () => <Linkage ends={["U", "S"]} last="P" />,
  JointSSP: () => <Linkage ends={["S", "S"]} last="P" />,
  JointRRP: () => <Linkage ends={["R", "R"]} last="P" />,
  JointUPS: () => <Linkage ends={["U", "P"]} last="S" />,
  LineForceWithTwoMasses: () => (
    <g>
      <path d="M4 14 H10 M38 14 H44 M16 14 H32" />
      <circle cx="13" cy="14" r="3" />
      <circle cx="35" cy="14" r="3" />
      <circle cx="20" cy="14" r="2.5" fill="currentColor" />
      <circle cx="28" cy="14" r="2.5" fill="currentColor" />
    </g>
  ),
  Rotor1D: () => (
    <g>
      <path d="M4 14 H16 M32 14 H44" />
      <rect x="16" y="4" width="16" height="20" rx="2" fill="currentColor" opacity="0.25" />
      <rect x="16" y="4" width="16" height="20" rx="2" />
      <path d="M24 24 V27 M18 27 H30" />
    </g>
  ),
  RollingWheelJoint: () => (
    <g>
      <circle cx="24" cy="12" r="9" />
      <circle cx="24" cy="12" r="1.6" fill="currentColor" />
      <path d="M8 22 H40" />
    </g>
  ),
  RollingWheel: () => (
    <g>
      <circle cx="24" cy="12" r="9" fill="currentColor" opacity="0.25" />
      <circle cx="24" cy="12" r="9" />
      <path d="M24 3 V21 M15 12 H33" />
      <path d="M8 22 H40" />
    </g>
  ),
  BearingFriction: () => (
    <g>
      <path d="M4 14 H44" />
      <path d="M14 6 H34 M14 22 H34" strokeWidth="2.2" />
      {[16, 22, 28, 34].map((x) => <path key={x} d={`M${x} 22 L${x - 3} 26`} />)}
    </g>
  ),
  Brake: () => (
    <g>
      <path d="M4 14 H18 M30 14 H44" />
      <rect x="18" y="6" width="12" height="16" fill="currentColor" opacity="0.25" />
      <rect x="18" y="6" width="12" height="16" />
      <path d="M14 3 V8 M34 3 V8 M10 5 H18 M30 5 H38" strokeWidth="2" />
    </g>
  ),
  Clutch: () => (
    <g>
      <path d="M4 14 H18 M30 14 H44" />
      <rect x="18" y="5" width="5" height="18" fill="currentColor" />
      <rect x="25" y="5" width="5" height="18" fill="currentColor" />
      <path d="M24 2 V5" />
    </g>
  ),
  ElastoGap: () => (
    <g>
      <path d="M4 14 H10 M38 14 H44 M10 8 V20 M38 8 V20" />
      <Zigzag y={10} x0={10} x1={30} />
      <path d="M30 5 V15 M34 5 V15" />
      <Dashpot y={20} x0={10} x1={38} />
    </g>
  ),
  Stop: () => (
    <g>
      <path d="M4 14 H20 M28 14 H44" />
      <rect x="16" y="8" width="8" height="12" />
      <path d="M8 5 V23 M40 5 V23" strokeWidth="2.2" />
    </g>
  ),
  Rod: () => <path d="M4 14 H44" strokeWidth="3" />,
  Friction: () => (
    <g>
      <path d="M4 10 H14 M34 10 H44" />
      <rect x="14" y="4" width="20" height="12" fill="currentColor" opacity="0.25" />
      <rect x="14" y="4" width="20" height="12" />
      <path d="M8 19 H40" />
      {[12, 18, 24, 30, 36].map((x) => <path key={x} d={`M${x} 19 L${x - 4} 25`} />)}
    </g>
  ),
  Input: () => (
    <g>
      <path d="M8 6 H30 L38 14 L30 22 H8 Z" />
      <text x="21" y="18" textAnchor="middle" fontSize="10" fill="currentColor" stroke="none">u</text>
    </g>
  ),
  Pulse: () => <path d="M6 22 H12 V6 H20 V22 H28 V6 H36 V22 H42" strokeWidth="2" />,
  SawTooth: () => <path d="M6 22 L18 6 V22 L30 6 V22 L42 6" strokeWidth="2" />,
  Trapezoid: () => <path d="M4 22 L10 6 H18 L24 22 H26 L32 6 H40 L44 16" strokeWidth="2" />,
  Expression: () => <text x="24" y="19" textAnchor="middle" fontSize="12" fill="currentColor" stroke="none" fontStyle="italic">f(u)</text>,
  Table2D: () => (
    <g>
      <rect x="10" y="4" width="28" height="20" />
      <path d="M10 10 H38 M10 17 H38 M19 4 V24 M29 4 V24" />
      <rect x="10" y="4" width="9" height="6" fill="currentColor" opacity="0.3" stroke="none" />
    </g>
  ),
  KinematicPTP: () => <path d="M6 22 H12 C18 22 18 6 26 6 C32 6 32 22 36 22 H42" strokeWidth="2" />,
  Resistor: () => (
    <g>
      <path d="M4 14 H12 M36 14 H44" />
      <rect x="12" y="9" width="24" height="10" />
    </g>
  ),
  Conductor: () => (
    <g>
      <path d="M4 14 H12 M36 14 H44" />
      <rect x="12" y="9" width="24" height="10" />
      <text x="24" y="17.5" textAnchor="middle" fontSize="8" fill="currentColor" stroke="none">G</text>
    </g>
  ),
  NonlinearResistor: () => (
    <g>
      <path d="M4 14 H12 M36 14 H44" />
      <rect x="12" y="9" width="24" height="10" />
      <path d="M10 24 L16 24 L32 4" />
    </g>
  ),
  Diode: () => (
    <g>
      <path d="M4 14 H44" />
      <path d="M18 6 L30 14 L18 22 Z" fill="currentColor" opacity="0.25" />
      <path d="M18 6 L30 14 L18 22 Z M30 6 V22" />
    </g>
  ),
  Inductor: () => (
    <g>
      <path d="M4 14 H10 M38 14 H44" />
      <path d="M10 14 A4.67 4.67 0 0 1 19.3 14 A4.67 4.67 0 0 1 28.7 14 A4.67 4.67 0 0 1 38 14" />
    </g>
  ),
  Capacitor: () => (
    <g>
      <path d="M4 14 H21 M27 14 H44" />
      <path d="M21 5 V23 M27 5 V23" strokeWidth="2.4" />
    </g>
  ),
  "electrical.Ground": () => (
    <g>
      <path d="M24 3 V13 M12 13 H36 M16 18 H32 M20 23 H28" strokeWidth="2" />
    </g>
  ),
  VoltageSource: () => (
    <g>
      <path d="M4 14 H14 M34 14 H44" />
      <circle cx="24" cy="14" r="10" />
      <path d="M14 14 H34" />
      <text x="17" y="10" textAnchor="middle" fontSize="8" fill="currentColor" stroke="none">+</text>
    </g>
  ),
  CurrentSource: () => (
    <g>
      <path d="M4 14 H14 M34 14 H44" />
      <circle cx="24" cy="14" r="10" />
      <path d="M24 4 V24" />
    </g>
  ),
  VoltageSensor: () => <Meter letter="V" />,
  CurrentSensor: () => <Meter letter="A" />,
  IdealOpAmp: () => (
    <g>
      <path d="M14 3 L38 14 L14 25 Z" />
      <path d="M4 8 H14 M4 20 H14 M38 14 H44" />
      <text x="19" y="11" fontSize="7" fill="currentColor" stroke="none">+</text>
      <text x="19" y="22" fontSize="8" fill="currentColor" stroke="none">−</text>
    </g>
  ),
  EMF: () => (
    <g>
      <path d="M4 14 H14 M34 14 H44" />
      <circle cx="24" cy="14" r="10" />
      <path d="M19 14 H29" strokeWidth="3" />
    </g>
  ),
  DCMotor: () => (
    <g>
      <path d="M4 14 H10 M38 14 H44" />
      <rect x="10" y="5" width="22" height="18" rx="3" fill="currentColor" opacity="0.2" />
      <rect x="10" y="5" width="22" height="18" rx="3" />
      <path d="M32 14 H38" strokeWidth="3" />
      <text x="21" y="18" textAnchor="middle" fontSize="9" fill="currentColor" stroke="none">M</text>
    </g>
  ),
  Subsystem: () => (    <g>
      <rect x="8" y="4" width="32" height="20" rx="2" />
      <rect x="13" y="9" width="9" height="6" />
      <rect x="26" y="13" width="9" height="6" />
      <path d="M22 12 H24 V16 H26" />
    </g>
  ),
  Unknown: () => (
    <text x="24" y="19" textAnchor="middle" fontSize="13" fill="currentColor" stroke="none">?</text>
  ),
};

export const LIBRARY_COLORS = {
  multibody: "#5f5f5f",
  rotational: "#404040",
  translational: "#007f00",
  signals: "#00007f",
  probe: "#a15c00",
  electrical: "#0000ff",
  subsystem: "#6a3d9a",
};

export function libraryOf(type) {
  if (!type) return "subsystem";
  if (type === "Probe") return "probe";
  const i = type.indexOf(".");
  return i < 0 ? "subsystem" : type.slice(0, i);
}

/** The name of the drawing of a type: its own (by full name where two libraries share a class
 * name that looks different, as an electrical ground), else a family's; "Unknown" is the
 * fallback, which a test requires of no type of the palette. */
export function iconKey(type, subsystem) {
  if (subsystem) return "Subsystem";
  if (DRAW[type]) return type;
  const cls = String(type || "").split(".").pop();
  if (DRAW[cls]) return cls;
  if (cls === "IdealOpAmp3Pin") return "IdealOpAmp";
  if (/Sensor$/.test(cls)) return "Sensor";
  if (cls === "Force" && String(type).startsWith("multibody.")) return "WorldForce";
  if (cls === "Torque" && String(type).startsWith("multibody.")) return "WorldTorque";
  if (cls === "Speed") return "Position";
  return "Unknown";
}

export function TypeIcon({ type, subsystem, size = 1 }) {
  const key = iconKey(type, subsystem);
  const Draw = DRAW[key];
  const color = LIBRARY_COLORS[subsystem ? "subsystem" : libraryOf(type)] || "#444";
  return (
    <svg viewBox="0 0 48 28" width={48 * size} height={28 * size} style={{ color }} stroke="currentColor" {...S} aria-hidden="true" data-icon={key}>
      <Draw />
    </svg>
  );
}
