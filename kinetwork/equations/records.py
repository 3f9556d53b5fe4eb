"""The records the build of the 1-D network fills, and the names of its states.

``Network`` is what the Assembly gets (``network.build``); ``Hybrid``, ``Prescribed`` and
``Motion`` are what the build's steps (``network``, ``balance``, ``blockflow``,
``derivatives``) hand each other about elements with modes, prescribed joint coordinates and
motion sources.
"""

from dataclasses import dataclass, field

import casadi as ca


@dataclass
class Network:
    """What the 1-D network and the blocks give the Assembly."""
    pos: dict
    vel: dict
    acc: dict
    flow: dict                      # PortRef -> flow into its component
    Q: ca.SX                        # generalized forces on the joint speeds
    armature: ca.SX                 # inertia added to each joint speed
    axis_flow: ca.SX                # flow into the joint axes (drive torques, with inertia)
    x: list = field(default_factory=list)        # extra states (SX scalars)
    rate: list = field(default_factory=list)     # their rates
    start: list = field(default_factory=list)    # their initial values
    names: list = field(default_factory=list)
    units: list = field(default_factory=list)
    signal: dict = field(default_factory=dict)   # signal set -> value
    loops_solved: list = field(default_factory=list)   # algebraic loops solved symbolically
    loops_kept: list = field(default_factory=list)     # nonlinear ones: algebraic variables
    alg_z: list = field(default_factory=list)          # their outputs, unknowns ...
    alg_res: list = field(default_factory=list)        # ... and their equations z - f(z)
    alg_names: list = field(default_factory=list)
    alg_units: list = field(default_factory=list)
    block_states: int = 0
    no_acceleration: set = field(default_factory=set)  # sets of massless groups
    #: speed index -> Prescribed, for joints whose coordinate a motion source gives
    prescribed: dict = field(default_factory=dict)
    #: elements with modes (friction, stops), in the order placed: ``Hybrid`` records
    hybrid: list = field(default_factory=list)
    #: what structural analysis made of the circuits (``circuit.Circuit.summary``)
    circuit: str = ""
    #: state name -> why it is no state: index reduction found a constraint that fixes it
    demoted: dict = field(default_factory=dict)
    #: joint starts the inertias on joint axes give: (``"q"`` or ``"u"``, index, value)
    claims: list = field(default_factory=list)

    def summary(self, topo):
        """A line on what structural analysis made of the 1-D network and the blocks."""
        kinds = {}
        for g in topo.oned:
            kind = "driven" if g.motion else g.kind
            kinds[kind] = kinds.get(kind, 0) + 1
        blocks = self.block_states
        parts = [f"{kinds[k]} {what}" for k, what in (
            ("joint", "on joint axes (no state: any inertia adds to the joint's)"),
            ("driven", "moving a joint by a prescribed motion (its coordinate is no state)"),
            ("free", "free (an angle and a speed each)"),
            ("massless", "massless (solved from their balance)"),
            ("prescribed", "prescribed"), ("fixed", "fixed")) if kinds.get(k)]
        out = f"1-D rigid groups: {', '.join(parts)}" if parts else ""
        if blocks or self.loops_solved or self.loops_kept:
            out += ("; " if out else "") + f"signal block states: {blocks}" + (
                f"; algebraic loops solved symbolically: {len(self.loops_solved)}"
                if self.loops_solved else "") + (
                f"; nonlinear algebraic loops kept as algebraic variables: "
                f"{len(self.loops_kept)} ({len(self.alg_z)} variables)" if self.loops_kept
                else "")
        if self.circuit:
            out += ("; " if out else "") + self.circuit
        return out


@dataclass
class Hybrid:
    """An element with modes while the network is built: the model's component, its bound
    twin, its mode state, the symbol of its holding force, its flanges a and b (their
    PortRefs) and the set of its signal input u (or None)."""
    comp: object
    bound: object
    mode: ca.SX
    F: ca.SX
    a: object
    b: object
    u: object


@dataclass
class Prescribed:
    """A joint coordinate a motion source gives: its value, speed and acceleration (in t,
    p, the network's states and, for a filtered reference, the mechanism's q and u), and
    ``drive``, the symbol of the generalized force the source applies to the joint."""
    coordinate: int
    pos: ca.SX
    vel: ca.SX
    acc: ca.SX
    drive: ca.SX
    source: str
    joint: str


@dataclass
class Motion:
    """A motion source while the network is built: its group, ratio, states, reference."""
    comp: object                     # bound to the parameters' symbols
    source: object                   # the model's component, whose ports are wired
    group: object
    k: ca.SX
    x: list
    coord: tuple                     # placeholders (or the joint's q, u, udot)
    reference: ca.SX = None
    drive: ca.SX = None              # on a joint: the symbol of the generalized force
    offset: ca.SX = 0                # the source's flange is at k theta + offset


def position_label(group):
    """The name of a 1-D group's position state: ``phi`` (rotational) or ``s``."""
    return "phi" if group.domain == "rotational" else "s"


def speed_label(group):
    """The name of a 1-D group's speed state: ``w`` (rotational) or ``v``."""
    return "w" if group.domain == "rotational" else "v"


def state_units(group):
    """The units of a 1-D group's position and speed."""
    return ("rad", "rad/s") if group.domain == "rotational" else ("m", "m/s")
