"""Electrical circuits (``kinetwork.components.electrical``), solved by structural analysis.

The unknowns are one potential per connection set of pins (the connection sets are the
alias elimination: every pin wired together shares one symbol) and one current per pin.
The equations are Kirchhoff's current law at every set and each component's laws, one per
pin, linear in the unknowns, with the components' states (inductor currents, capacitor
voltages), the speeds of EMF flanges, time and signal inputs as knowns. Matching equations to
unknowns (networkx's Hopcroft-Karp) finds a circuit that is structurally singular (no
ground, two voltage sources in parallel) or of higher index (a capacitor across a voltage
source, an inductor in series with a current source), refused with its components named;
the strongly connected components of the matched dependency graph (Tarjan), in topological
order, are the block-lower-triangular form: each block is solved symbolically in turn, a
scalar block by one division, a loop of resistors as one small linear system.

Every current and potential so becomes an expression of the states, the mechanism's speeds,
t and placeholders for the signals at the sources' u inputs (their values are substituted
when the network has them all: ``Circuit.inputs``).
"""

import casadi as ca
import networkx as nx

from ..errors import ModelError
from .matching import maximum_matching

DOMAIN = "electrical"


class _Pins:
    """What a component's ``laws``, ``rates`` and ``output`` read (see the library)."""

    def __init__(self, circuit, comp, x, u, w):
        self._c, self._comp, self.x, self.u, self.w = circuit, comp, x, u, w
        self.t = circuit.b.t

    def v(self, pin):
        return self._c.potential[self._c.topo.set_of[self._comp.port_ref(pin)]]

    def i(self, pin):
        return self._c.current[self._comp.port_ref(pin)]


class Circuit:
    """The electrical part of a model, built into the 1-D network's builder ``b``."""

    def __init__(self, b):
        self.b, self.model, self.topo = b, b.model, b.topo
        self.comps = [c for c in self.model.components.values()
                      if any(port.domain == DOMAIN for port in c.ports.values())]
        self.potential, self.current = {}, {}      # set -> SX, PortRef -> SX
        self.inputs = {}                           # placeholder -> signal set of its u
        self.sources = {}                          # component name -> its placeholder
        self.views = {}
        self.summary = ""

    # -- building ---------------------------------------------------------------------------
    def build(self):
        if not self.comps:
            return self
        self._check_sources()
        sets = sorted({self.topo.set_of[c.port_ref(pn)] for c in self.comps
                       for pn, port in c.ports.items() if port.domain == DOMAIN})
        self._check_grounds(sets)
        unknowns, names = [], []
        for s in sets:
            self.potential[s] = ca.SX.sym(f"v{s}")
            unknowns.append(self.potential[s])
            names.append(f"the potential at {{{self._where(s)}}}")
        for c in self.comps:
            for pn, port in c.ports.items():
                if port.domain == DOMAIN:
                    ref = c.port_ref(pn)
                    self.current[ref] = ca.SX.sym(f"i_{c.name}_{pn}")
                    unknowns.append(self.current[ref])
                    names.append(f"the current into {ref.path}")
        equations, owners = [], []
        for s in sets:                            # Kirchhoff's current law
            equations.append(sum((self.current[r] for r in self.topo.sets[s]
                                  if r in self.current), ca.SX(0)))
            owners.append(f"the currents at {{{self._where(s)}}}")
        for c in self.comps:
            view = self._view(c)
            for eq in self.b.bound[c.name].laws(view):
                equations.append(ca.SX(eq))
                owners.append(self.model.place(c))
        solved = self._solve(equations, owners, unknowns, names)
        values = ca.vertcat(*[solved[k] for k in range(len(unknowns))])
        z = ca.vertcat(*unknowns)

        def sub(e):
            return ca.substitute(ca.SX(e), z, values)
        for s in sets:
            self.potential[s] = sub(self.potential[s])
        for ref in self.current:
            self.current[ref] = sub(self.current[ref])
        for c in self.comps:
            view = self.views[c.name]
            for x, rate in zip(view.x, self.b.bound[c.name].rates(view)):
                self.b.net.rate[self.b._at(x)] = sub(rate)
        return self

    def _view(self, comp):
        b = self.b
        bound = b.bound[comp.name]
        x = [b._state(f"{comp.name}.{label}", unit, start, 0) for label, unit, start in
             zip(bound.state_labels, bound.state_units, bound.initial())]
        u = self.sources.get(comp.name)
        w = None
        if getattr(type(comp), "converter", False):
            w = (b.net.vel[comp.port_ref("flange")] - b.net.vel[comp.port_ref("support")])
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
                problems.append(f"{self.model.place(c, key)}: {c.name}.u is wired too; the "
                                f"value comes from one of them: remove {key} or the wire")
            elif not wired and not given:
                problems.append(f"{self.model.place(c, key)}: no value: give {key} (an "
                                f"expression in time t) or wire a signal to {c.name}.u")
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
        for part in nx.connected_components(g):
            if not part & grounded:
                names = sorted({r.component.name for s in part for r in self.topo.sets[s]
                                if r.component.role != "probe"})
                problems.append(f"circuit of {', '.join(names)} has no electrical.Ground: its "
                                f"potentials are not defined; wire a Ground to one of its "
                                f"pins")
        if problems:
            raise ModelError(problems)

    def _where(self, s):
        return ", ".join(r.path for r in self.topo.sets[s] if r.component.role != "probe")

    # -- structural analysis ----------------------------------------------------------------
    def _solve(self, equations, owners, unknowns, names):
        """Index of unknown -> its expression in the knowns: matching, then the blocks of
        the block-lower-triangular form, in order."""
        z = ca.vertcat(*unknowns)
        r = ca.vertcat(*equations)
        jac = ca.jacobian(r, z)
        if ca.depends_on(jac, z):
            bad = sorted({owners[k] for k in range(len(equations))
                          if ca.depends_on(ca.jacobian(r[k], z), z)})
            raise ModelError([f"{o}: its law is not linear in the currents and potentials"
                              for o in bad])
        sparsity = jac.sparsity()
        rows, cols = sparsity.get_triplet()
        # integer nodes: the same matching, so the same names in a refusal, in every run
        assigned = maximum_matching(len(equations), len(unknowns), zip(rows, cols))
        unmatched = [k for k in range(len(equations)) if k not in assigned]
        if unmatched or len(equations) != len(unknowns):
            matched = set(assigned.values())
            lost = [names[j] for j in range(len(unknowns)) if j not in matched]
            over = sorted({owners[k] for k in unmatched})
            raise ModelError(
                f"circuit: the equations of {', '.join(over) or 'the circuit'} leave "
                f"{', '.join(lost) or 'nothing'} undetermined and constrain the rest twice: "
                f"the circuit is structurally singular (two voltage sources in parallel, a "
                f"current source in series with another, an open current source) or of "
                f"higher index (a capacitor directly across a voltage source or another "
                f"capacitor loop, an inductor in series with a current source), which "
                f"kinetwork does not solve; add a resistor to the loop or the cut set")
        dep = nx.DiGraph()
        dep.add_nodes_from(range(len(equations)))
        owner_of = {j: k for k, j in assigned.items()}
        for i, j in zip(rows, cols):
            if assigned[i] != j:
                dep.add_edge(owner_of[j], i)      # equation i needs what owner_of[j] gives
        dag = nx.condensation(dep)
        sizes = sorted((len(dag.nodes[c]["members"]) for c in dag), reverse=True)
        loops = [n for n in sizes if n > 1]
        states = sum(len(v.x) for v in self.views.values())
        self.summary = (f"circuits: {len(unknowns) - len(self.current)} node potentials and "
                        f"{len(self.current)} pin currents in {len(sizes)} blocks solved "
                        f"symbolically" + (f" (linear loops of {', '.join(map(str, loops))})"
                                           if loops else "") + f", {states} states")
        solved = {}
        known_z, known_v = [], []
        for c in nx.topological_sort(dag):
            block = sorted(dag.nodes[c]["members"])
            zs = [assigned[k] for k in block]
            res = ca.vertcat(*[r[k] for k in block])
            if known_z:
                res = ca.substitute(res, ca.vertcat(*known_z), ca.vertcat(*known_v))
            zb = ca.vertcat(*[unknowns[j] for j in zs])
            a = ca.jacobian(res, zb)
            rest = ca.substitute(res, zb, ca.SX.zeros(len(zs)))
            self._regular(a, [owners[k] for k in block])
            values = -rest / a if len(zs) == 1 else -ca.solve(a, rest)
            for n, j in enumerate(zs):
                solved[j] = values[n]
                known_z.append(unknowns[j])
                known_v.append(values[n])
        return solved

    def _regular(self, a, owners):
        """Refuse a block whose matrix is singular at the parameters' values (a loop of
        zero resistances)."""
        b = self.b
        det = ca.det(a)
        if b.p is not None and b.p.numel():
            det = ca.substitute(det, b.p, ca.DM(b.p_values))
        if not det.is_constant():
            return                  # a coefficient varies in time: CVODES will say
        det = float(det)
        if abs(det) < 1e-300 or det != det:
            raise ModelError(f"circuit: the equations of {', '.join(sorted(set(owners)))} "
                             f"are singular at the parameters' values (det = {det:g}): a "
                             f"loop of zero resistances or of sources")

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
        """Names of the sources whose signal input ``expr`` depends on."""
        return [name for name, ph in self.sources.items() if ca.depends_on(ca.SX(expr), ph)]

    def fill(self, net):
        """Pins' potentials and currents into the network's ``pos`` and ``flow`` (what
        probes read)."""
        for ref, i in self.current.items():
            net.pos[ref] = self.potential[self.topo.set_of[ref]]
            net.flow[ref] = i
