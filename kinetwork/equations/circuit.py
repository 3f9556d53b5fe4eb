"""Electrical circuits (``kinetwork.components.electrical``), solved by structural analysis.

The unknowns are one potential per connection set of pins (the connection sets are the
alias elimination: every pin wired together shares one symbol), one current per pin and
the derivatives of the components' states (inductor currents, capacitor voltages). The
equations are Kirchhoff's current law at every set, each component's laws (one per pin)
and its states' rate equations (C v' = i, L i' = v); the speeds of EMF flanges, time and
the signals at the sources' u inputs are knowns.

A circuit whose laws fix a relation among its states (a capacitor across a voltage source,
a loop of capacitors, inductors in series, an inductor in series with a current source) is
of higher index: ``structure.reduce_index`` finds the equations to differentiate
(Pantelides), CasADi differentiates them, and the dummy derivatives pick the states those
constraints fix, which become algebraic (solved from the other states and the sources), as
a Modelica tool does. Where the choice is free, a state whose start the user gave (``v0``,
``i0``) stays a state, then the one placed first. A structurally singular circuit (no
ground, two voltage sources in parallel, an open current source) is refused naming the
components whose laws over-determine it, sorted.

The index-1 system left is solved block by block (``blocks.solve_blocks``): a linear
block symbolically, a nonlinear one (a diode and its resistor) torn, its tearing unknowns
left to IDAS as algebraic variables. Every current and potential so becomes an expression
of the states, the mechanism's speeds, t and placeholders for the signals at the sources'
u inputs (and their time derivatives, where a constraint was differentiated): the network
substitutes those once it has them (``Circuit.inputs``, ``Circuit.input_rates``).
"""

import casadi as ca
import networkx as nx
import numpy as np

from ..errors import ModelError, Problem
from . import circuit_report
from .circuit_dae import Candidate, Dae, couple
from .blocks import solve_blocks
from .structure import Singular, reduce_index

DOMAIN = "electrical"
#: a given start further than this (relative to 1 + |value|) from the value a constraint
#: fixes is refused
START_TOL = 1e-9


class _Pins:
    """What a component's ``laws``, ``rates`` and ``output`` read (see the library)."""

    def __init__(self, circuit, comp, x, u, w):
        self._c, self._comp, self.x, self.u, self.w = circuit, comp, x, u, w
        self.t = circuit.b.t
        self.parameters = circuit.parameters

    def v(self, pin):
        return self._c.potential[self._c.topo.set_of[self._comp.port_ref(pin)]]

    def i(self, pin):
        return self._c.current[self._comp.port_ref(pin)]

    def place(self, key):
        return self._c.model.place(self._comp, key)

    def fields(self, key):
        """The fields of a Problem about this component's parameter ``key``."""
        return self._c.model.fields(self._comp, key)


class Circuit:
    """The electrical part of a model, built into the 1-D network's builder ``b``."""

    def __init__(self, b):
        self.b, self.model, self.topo = b, b.model, b.topo
        self.comps = [c for c in self.model.components.values()
                      if any(port.domain == DOMAIN for port in c.ports.values())]
        self.potential, self.current = {}, {}      # set -> SX, PortRef -> SX
        self.inputs = {}                           # placeholder -> signal set of its u
        self.input_rates = {}                      # placeholder of du/dt -> signal set
        self.sources = {}                          # component name -> its placeholder
        self.source_rates = {}                     # component name -> placeholder of du/dt
        self.speeds = {}                           # EMF name -> (symbol of w, of dw/dt)
        #: free group index -> ``circuit_dae.Coupled``: rotors a constraint couples in
        self.coupled = {}
        self.views = {}
        self.parameters = ({name: b.p[i] for i, name in enumerate(self.model.parameters)}
                           if b.p is not None else {})
        self.summary = ""
        #: state name -> why it is no state (its value fixed by a differentiated constraint)
        self.demoted = {}

    # -- building ---------------------------------------------------------------------------
    def build(self):
        if not self.comps:
            return self
        self._check_sources()
        sets = sorted({self.topo.set_of[c.port_ref(pn)] for c in self.comps
                       for pn, port in c.ports.items() if port.domain == DOMAIN})
        self._check_grounds(sets)
        dae = self._equations(sets)
        try:
            reduced = self._reduce(dae)
            moving = self._moving(reduced.equations, derivative=True)
        except Singular as exc:
            # with the speeds as knowns, EMFs tied to each other look like voltage sources
            # in parallel: with the rotors' balances they may not be
            moving = self._moving([dae.equations[e] for e in exc.equations])
            if not moving:
                raise circuit_report.refusal(self, exc, dae) from None
        if moving:
            # a constraint reaches the speed of rotors (or masses) the EMFs turn: their
            # balances join the system, their speeds among its candidate states
            dae = couple(self, dae, moving)
            try:
                reduced = self._reduce(dae)
            except Singular as exc:
                raise circuit_report.refusal(self, exc, dae) from None
        try:
            solved = solve_blocks(reduced.equations, reduced.unknowns, self._regular,
                                  self._sample)
        except Singular as exc:
            raise circuit_report.refusal(self, exc, dae, reduced) from None
        self._apply(dae, reduced, solved, sets)
        return self

    def _equations(self, sets):
        """The circuit's DAE: Kirchhoff's current law at every set, the components' laws
        and their states' rate equations, in the unknown potentials and pin currents."""
        dae = Dae()
        for s in sets:
            self.potential[s] = ca.SX.sym(f"v{s}")
            dae.unknowns.append(self.potential[s])
            dae.names.append(f"the potential at {{{self._where(s)}}}")
        for c in self.comps:
            for pn, port in c.ports.items():
                if port.domain == DOMAIN:
                    ref = c.port_ref(pn)
                    self.current[ref] = ca.SX.sym(f"i_{c.name}_{pn}")
                    dae.unknowns.append(self.current[ref])
                    dae.names.append(f"the current into {ref.path}")
        for s in sets:
            dae.add(sum((self.current[r] for r in self.topo.sets[s] if r in self.current),
                        ca.SX(0)), None)
        for c in self.comps:
            view = self._view(c, dae.knowns)
            for eq in self.b.bound[c.name].laws(view):
                dae.add(ca.SX(eq), c)
        for c in self.comps:
            view = self.views[c.name]
            bound = self.b.bound[c.name]
            for k, (x, rate) in enumerate(zip(view.x, bound.rates(view))):
                key = _start_key(c, k)
                dae.candidate(Candidate(x, self.b.net.names[self.b.index_of(x)], c, key,
                                        bound.initial()[k]), rate, c)
        return dae

    def _reduce(self, dae):
        return reduce_index(dae.equations, dae.unknowns, [c.x for c in dae.candidates],
                            [c.dx for c in dae.candidates], dae.knowns, self.b.t,
                            # a start given keeps a state, then a rotor's speed (the
                            # mechanism's), then the first placed
                            [(c.key in c.comp.given, c.group is not None, -k)
                             for k, c in enumerate(dae.candidates)],
                            self._sample, self.b.p if self.b.p is not None else ca.SX(0, 1))

    def _moving(self, equations, derivative=False):
        """EMFs whose speed (with ``derivative``, the speed's derivative) ``equations``
        read, where their flange or support moves: the circuit may constrain the
        mechanism."""
        if not self.speeds or not equations:
            return []
        eqs = ca.vertcat(*equations)
        net = self.b.net
        out = []
        for name, (w, dw) in self.speeds.items():
            c = self.model.components[name]
            vel = ca.SX(net.vel[c.port_ref("flange")] - net.vel[c.port_ref("support")])
            if ca.depends_on(eqs, dw if derivative else w) and not vel.is_zero():
                out.append(c)
        return out

    def _view(self, comp, knowns):
        b = self.b
        bound = b.bound[comp.name]
        x = [b.add_state(f"{comp.name}.{label}", unit, start, 0) for label, unit, start in
             zip(bound.state_labels, bound.state_units, bound.initial())]
        u = self.sources.get(comp.name)
        if u is not None:
            du = self.source_rates[comp.name] = ca.SX.sym(f"du_{comp.name}")
            self.input_rates[du] = self.inputs[u]
            knowns.append((u, du))
        w = None
        if getattr(type(comp), "converter", False):
            # a symbol for the speed, its derivative the flange's relative acceleration:
            # both put in once the circuit is solved (``_apply``)
            w, dw = self.speeds[comp.name] = (ca.SX.sym(f"w_{comp.name}"),
                                               ca.SX.sym(f"dw_{comp.name}"))
            knowns.append((w, dw))
        view = _Pins(self, comp, x, u, w)
        self.views[comp.name] = view
        return view

    def _check_sources(self):
        """A source takes its value from its parameter or from its input u: one of them."""
        problems = []
        for c in self.comps:
            key = getattr(type(c), "reference_key", None)
            if key is None:
                continue
            s = self.topo.set_of[c.port_ref("u")]
            wired = s in self.topo.signal_source
            given = c._values[key] is not None
            if wired and given:
                problems.append(self.model.problem(
                    f"{c.name}.u is wired too; the value comes from one of them: remove {key} "
                    f"or the wire", c, key))
            elif not wired and not given:
                problems.append(self.model.problem(
                    f"no value: give {key} (an expression in time t) or wire a signal to "
                    f"{c.name}.u", c, key))
            elif wired:
                placeholder = ca.SX.sym(f"u_{c.name}")
                self.sources[c.name] = placeholder
                self.inputs[placeholder] = s
        if problems:
            raise ModelError(problems)

    def _check_grounds(self, sets):
        """Every circuit (connected through its components) needs a Ground."""
        g = nx.Graph()
        g.add_nodes_from(sets)
        for c in self.comps:
            pins = [self.topo.set_of[c.port_ref(pn)] for pn, port in c.ports.items()
                    if port.domain == DOMAIN]
            g.add_edges_from(zip(pins, pins[1:]))
        grounded = {self.topo.set_of[c.port_ref("p")] for c in self.comps
                    if c.type_name == "electrical.Ground"}
        problems = []
        for part in sorted(nx.connected_components(g), key=min):
            if not part & grounded:
                names = sorted({r.component.name for s in part for r in self.topo.sets[s]
                                if r.component.role != "probe"})
                # marked on its first component: the studio shows where to add the Ground
                problems.append(Problem(
                    f"circuit of {', '.join(names)} has no electrical.Ground: its potentials "
                    f"are not defined; wire a Ground to one of its pins",
                    **(self.model.fields(self.model.components[names[0]]) if names else {}),
                    hint="wire an electrical.Ground to one of its pins"))
        if problems:
            raise ModelError(problems)

    def _where(self, s):
        return ", ".join(r.path for r in self.topo.sets[s] if r.component.role != "probe")

    # -- numbers at the parameters' values --------------------------------------------------
    def _at_values(self, expr):
        b = self.b
        if b.p is not None and b.p.numel():
            expr = ca.substitute(expr, b.p, ca.DM(b.p_values))
        return expr

    def _sample(self, expr):
        """A Jacobian at the parameters' values and generic values of every other symbol
        (the same in every run): where the dummy derivatives' ranks are taken."""
        expr = self._at_values(ca.SX(expr))
        syms = ca.symvar(expr)
        if syms:
            rng = np.random.default_rng(20260527)
            expr = ca.substitute(expr, ca.vertcat(*syms),
                                 ca.DM(rng.uniform(0.5, 1.5, len(syms))))
        return np.array(ca.evalf(expr), dtype=float).reshape(expr.shape)

    def _regular(self, a):
        """Whether a block's matrix is regular at the parameters' values (a loop of zero
        resistances is not): its rank, numerically (a symbolic determinant costs
        exponential time in the block's size); one whose entries vary in time is taken as
        regular (IDAS or CVODES will say where it is not)."""
        a = self._at_values(ca.SX(a))
        if not a.is_constant():
            return True
        m = np.array(ca.evalf(a), dtype=float).reshape(a.shape)
        if not np.all(np.isfinite(m)):
            return False
        return m[0, 0] != 0 if m.shape == (1, 1) else np.linalg.matrix_rank(m) == m.shape[0]

    # -- the solution -----------------------------------------------------------------------
    def _apply(self, dae, reduced, solved, sets):
        """Put the solution in place: potentials, currents, the kept states' rates (a
        coupled rotor's acceleration), the demoted states' values (their states dropped),
        the algebraic variables."""
        b = self.b
        value = dict(zip((z.element_hash() for z in reduced.unknowns), solved.values))
        z = ca.vertcat(*dae.unknowns)
        vz = ca.vertcat(*[value[u.element_hash()] for u in dae.unknowns])
        demoted = [dae.candidates[i] for i in reduced.demoted]
        dx = ca.vertcat(*[d.x for d in demoted])
        vd = ca.vertcat(*[value[d.x.element_hash()] for d in demoted])
        known = self._knowns()

        def sub(e):
            e = ca.substitute(ca.SX(e), z, vz)
            if demoted:
                e = ca.substitute(e, dx, vd)
            return known(e)
        for s in sets:
            self.potential[s] = sub(self.potential[s])
        for ref in self.current:
            self.current[ref] = sub(self.current[ref])
        for cand in dae.candidates:
            rate = sub(value[cand.dx.element_hash()])
            if cand.group is not None:
                self.coupled[cand.group.index].acc = rate
            elif cand not in demoted:
                b.net.rate[b.index_of(cand.x)] = rate
        kept = [dae.candidates[i] for i in reduced.states]
        self._check_starts(dae, reduced, kept, demoted, [sub(v) for v in ca.vertsplit(vd)])
        for cand, v in zip(demoted, ca.vertsplit(vd)):
            if cand.group is not None:       # a rotor's speed: the network substitutes it
                b.pending[cand.x] = sub(v)
            self._drop(cand.x)
        if solved.kept:
            net = b.net
            owners = sorted({o.name for o in dae.owners if o is not None and any(
                ca.depends_on(r, k) for r in solved.residuals for k in solved.kept)})
            net.alg_z += solved.kept
            net.alg_res += [sub(r) for r in solved.residuals]
            net.alg_names += [circuit_report.label(self, k, dae.unknowns)
                              for k in solved.kept]
            net.alg_units += ["V" if k.name().startswith("v") else "A"
                              for k in solved.kept]
            net.loops_kept.append(owners)
        # the rates of the sources' signals are needed only where a constraint was
        # differentiated through a source (the network finds them: ``derivatives.input_rates``)
        used = ca.vertcat(*self.potential.values(), *self.current.values(),
                          *b.net.rate, *b.net.alg_res,
                          *[c.acc for c in self.coupled.values()])
        self.input_rates = {du: s for du, s in self.input_rates.items()
                            if ca.depends_on(used, du)}
        self.summary = circuit_report.summary(self, dae, reduced, solved)

    def _knowns(self):
        """The function putting the EMF speeds in, and their derivatives where a
        differentiated constraint reads them: zero on a flange that cannot turn (on one that
        turns freely, the rotor was coupled into the system: ``circuit_dae.couple``)."""
        net = self.b.net

        def known(e):
            for name, (w, dw) in self.speeds.items():
                c = self.model.components[name]
                f, s = c.port_ref("flange"), c.port_ref("support")
                if ca.depends_on(e, dw):
                    e = ca.substitute(e, dw, ca.SX(net.acc[f] - net.acc[s]))
                if ca.depends_on(e, w):
                    e = ca.substitute(e, w, ca.SX(net.vel[f] - net.vel[s]))
            return e
        return known

    def _check_starts(self, dae, reduced, kept, demoted, values):
        """Record why each demoted state is no state, and check a start the user gave it
        against the constraint (at t = 0 and the parameters' values): one that disagrees,
        or that depends on signals the network has not built yet, is refused."""
        problems = []
        xs = ca.vertcat(*[c.x for c in kept])
        starts = ca.vertcat(*[self._at_values(ca.SX(c.start)) for c in kept])
        for cand, v in zip(demoted, values):
            self.demoted[cand.name] = circuit_report.why_demoted(self, dae, reduced, cand, v,
                                                                 kept)
            if cand.key not in cand.comp.given:
                continue
            at0 = self._at_values(ca.substitute(v, self.b.t, ca.SX(0)))
            if kept:
                at0 = self._at_values(ca.substitute(at0, xs, starts))
            given = float(self._at_values(ca.SX(cand.start)))
            where = self.model.place(cand.comp, cand.key)
            why = self.demoted[cand.name]
            if not at0.is_constant():
                problems.append(Problem(
                    f"{where}: {cand.name} is no state ({why}); its start follows from "
                    f"signals, so it cannot be given: remove {cand.key}",
                    **self.model.fields(cand.comp, cand.key)))
                continue
            fixed = float(at0)
            if abs(fixed - given) > START_TOL * (1 + abs(fixed)):
                problems.append(Problem(
                    f"{where} = {given:g}: {cand.name} is no state ({why}), and the "
                    f"constraint gives {fixed:g} at the start: remove {cand.key} or make it "
                    f"agree", **self.model.fields(cand.comp, cand.key)))
        if problems:
            raise ModelError(problems)

    def _drop(self, x):
        """Take the state ``x`` out of the network: a constraint gives its value."""
        net = self.b.net
        at = self.b.index_of(x)
        for seq in (net.x, net.rate, net.start, net.names, net.units):
            del seq[at]

    # -- what the network reads -------------------------------------------------------------
    def output(self, comp):
        """A sensor's output, with the signals already known put in for the sources' inputs
        (inside an algebraic loop of blocks, those are the loop's unknowns)."""
        out = ca.SX(self.b.bound[comp.name].output(self.views[comp.name]))
        known = [(ph, self.b.net.signal[s]) for ph, s in self.inputs.items()
                 if s in self.b.net.signal]
        if known:
            out = ca.substitute(out, ca.vertcat(*[k for k, _ in known]),
                                ca.vertcat(*[ca.SX(v) for _, v in known]))
        return out

    def converter_current(self, comp):
        """The current through an EMF (into its pin p)."""
        return self.current[comp.port_ref("p")]

    def placeholders_in(self, expr):
        """Names of the sources whose signal input (or its rate) ``expr`` depends on."""
        expr = ca.SX(expr)
        return [name for name, ph in self.sources.items()
                if ca.depends_on(expr, ph) or ca.depends_on(expr, self.source_rates[name])]

    def fill(self, net):
        """Pins' potentials and currents into the network's ``pos`` and ``flow`` (what
        probes read)."""
        for ref, i in self.current.items():
            net.pos[ref] = self.potential[self.topo.set_of[ref]]
            net.flow[ref] = i


def _start_key(comp, k):
    """The parameter giving the start of ``comp``'s state k (``v0``, ``i0``), or None."""
    keys = getattr(type(comp), "start_params", ())
    return keys[k] if k < len(keys) else None
