// Palette search: a ranked list of component types for what a user types, over type names,
// the words people use for them (hinge, link, pendulum, motor ...), the library, the docs
// and the parameter and port names. A name match ranks above a synonym, a synonym above a
// mention in a doc, so "body" lists the bodies first.

const MB = "multibody.";
const ROT = "rotational.";
const TR = "translational.";
const SIG = "signals.";
const EL = "electrical.";

/** Words people use -> the types they mean, most likely first. */
export const SYNONYMS = {
  hinge: [`${MB}Revolute`],
  pin: [`${MB}Revolute`],
  pivot: [`${MB}Revolute`, `${MB}Spherical`],
  axle: [`${MB}Revolute`, `${ROT}Inertia`],
  joint: [`${MB}Revolute`, `${MB}Prismatic`, `${MB}Spherical`, `${MB}Universal`, `${MB}Cylindrical`, `${MB}Planar`, `${MB}FreeMotion`],
  slider: [`${MB}Prismatic`, `${TR}Mass`],
  slide: [`${MB}Prismatic`],
  rail: [`${MB}Prismatic`],
  linear: [`${MB}Prismatic`],
  ball: [`${MB}Spherical`, `${MB}BodySphere`],
  link: [`${MB}FixedTranslation`, `${MB}BodyShape`, `${MB}BodyCylinder`, `${MB}BodyBox`],
  rod: [`${MB}FixedTranslation`, `${MB}BodyCylinder`, `${MB}BodyShape`, `${MB}SphericalSpherical`],
  bar: [`${MB}FixedTranslation`, `${MB}BodyBox`, `${MB}BodyShape`],
  beam: [`${MB}BodyBox`, `${MB}BodyShape`],
  arm: [`${MB}FixedTranslation`, `${MB}BodyShape`, `${MB}BodyCylinder`],
  offset: [`${MB}FixedTranslation`, `${MB}FixedRotation`],
  translate: [`${MB}FixedTranslation`],
  rotate: [`${MB}FixedRotation`],
  pendulum: [`${MB}Revolute`, `${MB}BodyShape`, `${MB}RigidBody`, `${MB}FixedTranslation`, `${MB}Ground`],
  mass: [`${MB}RigidBody`, `${TR}Mass`, `${MB}BodySphere`],
  weight: [`${MB}RigidBody`, `${TR}Mass`],
  inertia: [`${ROT}Inertia`, `${MB}RigidBody`, `${MB}Rotor1D`],
  flywheel: [`${ROT}Inertia`, `${MB}Rotor1D`],
  rotor: [`${MB}Rotor1D`, `${ROT}Inertia`],
  shaft: [`${ROT}Inertia`, `${ROT}Spring`],
  wheel: [`${MB}RollingWheel`, `${MB}RollingWheelJoint`],
  spring: [`${ROT}Spring`, `${TR}Spring`, `${MB}Spring`, `${ROT}SpringDamper`, `${TR}SpringDamper`, `${MB}SpringDamper`, `${MB}LineForceWithTwoMasses`, `${ROT}ElastoGap`, `${TR}ElastoGap`],
  stiffness: [`${ROT}Spring`, `${TR}Spring`, `${MB}Spring`],
  elastic: [`${ROT}Spring`, `${TR}Spring`, `${ROT}ElastoGap`, `${TR}ElastoGap`],
  damper: [`${ROT}Damper`, `${TR}Damper`, `${MB}Damper`, `${ROT}SpringDamper`, `${TR}SpringDamper`, `${MB}SpringDamper`],
  dashpot: [`${ROT}Damper`, `${TR}Damper`, `${MB}Damper`],
  damping: [`${ROT}Damper`, `${TR}Damper`, `${MB}Damper`],
  shock: [`${TR}SpringDamper`, `${MB}SpringDamper`],
  motor: [`${EL}DCMotor`, `${ROT}Torque`, `${EL}EMF`, `${MB}Torque`, `${ROT}Speed`],
  actuator: [`${ROT}Torque`, `${TR}Force`, `${MB}Torque`, `${MB}Force`, `${EL}DCMotor`],
  drive: [`${ROT}Torque`, `${ROT}Speed`, `${ROT}Position`, `${EL}DCMotor`],
  servo: [`${ROT}Position`, `${SIG}PID`, `${EL}DCMotor`],
  push: [`${TR}Force`, `${MB}Force`, `${MB}WorldForce`],
  load: [`${TR}Force`, `${MB}WorldForce`, `${ROT}Torque`],
  gravity: [`${MB}Ground`],
  world: [`${MB}Ground`, `${MB}WorldForce`, `${MB}WorldTorque`],
  ground: [`${MB}Ground`, `${ROT}Fixed`, `${TR}Fixed`, `${EL}Ground`],
  base: [`${MB}Ground`, `${ROT}Fixed`, `${TR}Fixed`],
  earth: [`${MB}Ground`, `${EL}Ground`],
  fixed: [`${MB}Ground`, `${ROT}Fixed`, `${TR}Fixed`],
  wall: [`${TR}Fixed`, `${ROT}Fixed`, `${TR}Stop`],
  sensor: ["Probe", `${ROT}AngleSensor`, `${ROT}SpeedSensor`, `${TR}PositionSensor`, `${TR}SpeedSensor`, `${ROT}TorqueSensor`, `${TR}ForceSensor`, `${EL}VoltageSensor`, `${EL}CurrentSensor`],
  measure: ["Probe", `${ROT}AngleSensor`, `${TR}PositionSensor`],
  scope: ["Probe"],
  meter: ["Probe", `${EL}VoltageSensor`, `${EL}CurrentSensor`],
  plot: ["Probe"],
  encoder: [`${ROT}AngleSensor`],
  tachometer: [`${ROT}SpeedSensor`],
  gear: [`${ROT}IdealGear`],
  gearbox: [`${ROT}IdealGear`],
  transmission: [`${ROT}IdealGear`, `${ROT}Clutch`],
  reducer: [`${ROT}IdealGear`],
  friction: [`${ROT}BearingFriction`, `${TR}Friction`, `${ROT}Brake`, `${ROT}Clutch`],
  stiction: [`${ROT}BearingFriction`, `${TR}Friction`],
  coulomb: [`${ROT}BearingFriction`, `${TR}Friction`],
  stop: [`${ROT}Stop`, `${TR}Stop`, `${ROT}ElastoGap`, `${TR}ElastoGap`],
  contact: [`${TR}Stop`, `${ROT}Stop`, `${ROT}ElastoGap`, `${TR}ElastoGap`],
  collision: [`${TR}Stop`, `${ROT}Stop`],
  limit: [`${ROT}Stop`, `${TR}Stop`, `${SIG}Limiter`],
  bounce: [`${TR}Stop`],
  controller: [`${SIG}PID`, `${SIG}Gain`, `${SIG}InverseDynamics`],
  control: [`${SIG}PID`, `${SIG}InverseDynamics`],
  feedback: [`${SIG}PID`, `${SIG}Gain`],
  source: [`${SIG}Constant`, `${SIG}Step`, `${SIG}Sine`, `${SIG}Ramp`, `${EL}VoltageSource`, `${EL}CurrentSource`],
  input: [`${SIG}Input`, `${SIG}Constant`, `${SIG}Step`],
  setpoint: [`${SIG}Constant`, `${SIG}Step`, `${SIG}KinematicPTP`],
  trajectory: [`${SIG}KinematicPTP`, `${SIG}Table`],
  profile: [`${SIG}KinematicPTP`, `${SIG}Table`],
  lookup: [`${SIG}Table`, `${SIG}Table2D`],
  interpolation: [`${SIG}Table`, `${SIG}Table2D`],
  filter: [`${SIG}FirstOrder`, `${SIG}Derivative`],
  lag: [`${SIG}FirstOrder`],
  sum: [`${SIG}Add`, `${SIG}Sum`],
  multiply: [`${SIG}Product`, `${SIG}Gain`],
  formula: [`${SIG}Expression`],
  sinusoid: [`${SIG}Sine`],
  oscillator: [`${SIG}Sine`],
  battery: [`${EL}VoltageSource`],
  voltage: [`${EL}VoltageSource`, `${EL}VoltageSensor`],
  current: [`${EL}CurrentSource`, `${EL}CurrentSensor`],
  coil: [`${EL}Inductor`],
  opamp: [`${EL}IdealOpAmp`],
  brake: [`${ROT}Brake`],
  clutch: [`${ROT}Clutch`],
  gyroscope: [`${MB}Rotor1D`],
  free: [`${MB}FreeMotion`],
  floating: [`${MB}FreeMotion`],
  subsystem: [],
};

const WEIGHTS = { name: 100, prefix: 80, inName: 60, synonym: 70, library: 30, sentence: 20, doc: 10, field: 8 };

function words(text) {
  return String(text || "").toLowerCase().split(/[^a-z0-9_]+/).filter(Boolean);
}

/** The forms of a typed word a search tries: "springs" -> ["springs", "spring"]. */
function forms(w) {
  const out = [w];
  if (w.length > 3 && w.endsWith("es")) out.push(w.slice(0, -2));
  if (w.length > 3 && w.endsWith("s")) out.push(w.slice(0, -1));
  return out;
}

function firstSentence(doc) {
  const line = String(doc || "").trim().split("\n")[0];
  const m = /\.(\s|$)/.exec(line);
  return m ? line.slice(0, m.index + 1) : line;
}

/** How well one typed word names a type: 0 when it does not. */
function wordScore(info, w) {
  const full = info.type.toLowerCase();
  const cls = full.split(".").pop();
  const lib = full.includes(".") ? full.split(".")[0] : "probe";
  let best = 0;
  for (const f of forms(w)) {
    if (cls === f) best = Math.max(best, WEIGHTS.name);
    else if (cls.startsWith(f)) best = Math.max(best, WEIGHTS.prefix);
    else if (cls.includes(f)) best = Math.max(best, WEIGHTS.inName);
    const syn = SYNONYMS[f];
    const at = syn ? syn.indexOf(info.type) : -1;
    if (at >= 0) best = Math.max(best, WEIGHTS.synonym - at);
    if (lib === f) best = Math.max(best, WEIGHTS.library);
    if (best) continue;
    if (words(firstSentence(info.doc)).includes(f)) best = WEIGHTS.sentence;
    else if (f.length >= 4 && String(info.doc || "").toLowerCase().includes(f)) best = WEIGHTS.doc;
    else if ((info.params || []).some((p) => p.name.toLowerCase() === f) || (info.ports || []).some((p) => p.name.toLowerCase() === f)) best = WEIGHTS.field;
  }
  return best;
}

/** How well a query names a type: the sum over its words, 0 unless every word matches. */
export function score(info, query) {
  const ws = words(query);
  if (!ws.length) return 0;
  let total = 0;
  for (const w of ws) {
    const s = wordScore(info, w);
    if (!s) return 0;
    total += s;
  }
  return total;
}

/**
 * The types matching ``query``, best first (ties in the palette's order).
 * @param {any[]} types TypeInfo list, in palette order
 * @param {string} query
 * @returns {any[]}
 */
export function search(types, query) {
  const ranked = [];
  types.forEach((t, i) => {
    const s = score(t, query);
    if (s > 0) ranked.push({ t, s, i });
  });
  ranked.sort((a, b) => b.s - a.s || a.i - b.i);
  return ranked.map((r) => r.t);
}
