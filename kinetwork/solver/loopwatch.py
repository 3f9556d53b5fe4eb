"""The watch over kinematic loops: where the Jacobian of the closure in the dependent speeds
turns singular (a dead point: a four-bar that cannot go round, links folding flat), the
partition of the speeds no longer holds.

There the run re-partitions (``Partitions``). Where the Jacobian in the dependent speeds
worsens (its condition number grown REPARTITION_GROWTH-fold since its partition began, or its
determinant about to vanish within two outputs), the driver stops the chunk at that output,
asks ``_Loops.partitions_at`` for the partitions possible there (closure rows by pivoted QR,
every choice of dependent speeds), and takes the best-conditioned one if it is
REPARTITION_GAIN times better: the System of that partition (built once per partition a model
meets, on the same assembly, kept with the model's compiled functions), the state moved into
its variables (the same coordinates and speeds, so the velocities stay consistent: J u = 0
holds in any partition), its algebraic variables Newton-polished onto the closure, the method
started afresh there. At a change point, where the closure's Jacobian itself nears a lower
rank and every partition turns singular together (an equal-sided rhombus folding flat), the
run crosses in the projected formulation of the partition whose independent coordinates
describe the motion best, by CROSSING_STEPS fixed Runge-Kutta steps per output interval, and
goes back to the model's own formulation once the Jacobian is healthy again.

Each part of the run is polished and probed by its own partition's equations; the states the
results hold are those of the model's own partition (``System.state_names``), read from the
coordinates and speeds. Where the closure has lost rank outright, a failure repeats at the
same output, or with ``simulate(..., repartition=False)``, every formulation stops at the
singular configuration, saying so."""

import casadi as ca
import numpy as np

from ..equations.system import System, pointwise
from .buffers import PointsBySize
from .compiled import compiled
from .methods import METHODS, Failure

#: a kinematic loop whose Jacobian in the dependent speeds has a larger condition number is
#: at a singular configuration
SINGULAR_CONDITION = 1e8
#: ... and near one, for the message of a failure, beyond this
NEAR_SINGULAR_CONDITION = 1e4
#: a run looks for a better partition where the Jacobian in the dependent speeds has a
#: condition number this many times that at the start of its partition (and beyond
#: REPARTITION_CONDITION; where it finds none, next at TRIGGER_STEP times the present one) ...
REPARTITION_GROWTH = 2.0
REPARTITION_CONDITION = 5.0
TRIGGER_STEP = 1.5
#: ... or, beyond PREDICTED_GROWTH times, where its determinant, extrapolated from the last two
#: outputs, vanishes within PREDICTED_INTERVALS output intervals
PREDICTED_GROWTH = 1.5
PREDICTED_INTERVALS = 2.0
#: a new partition is taken when its condition number is this many times smaller ...
REPARTITION_GAIN = 3.0
#: ... or, after a failure or past a singular configuration, this many times
FORCED_GAIN = 2.0
#: the closure's Jacobian nears a change point where its health (smallest over largest
#: singular value) falls below this fraction of the healthiest met, and has crossed it where
#: the health is back above CROSSED of it
CHANGE_POINT = 0.125
CROSSED = 0.25
#: partitions whose quality is within this fraction of the best are as good
TIED = 0.9
#: a change point is crossed by the classical Runge-Kutta method with this many fixed steps
#: per output interval: no step size control to close in on the point, where the Newton
#: projection has the two branches within its reach
CROSSING_STEPS = 100
#: chunks of a run that has re-partitioned are at most this many output intervals
REPARTITIONED_CHUNK = 16


def conditioning(run, X):
    """(condition number, sign of the determinant) of the loops' Jacobian in the
    dependent speeds at each full state in X; None for a model without such loops."""
    f = run.system.f_dependent
    if f is None or not len(X):
        return None
    n = f.size1_out(0)
    J = pointwise(f, X, run.p)[0].reshape(len(X), n, n).transpose(0, 2, 1)
    with np.errstate(all="ignore"):
        s = np.linalg.svd(J, compute_uv=False)
        cond = np.where(s[:, -1] > 0, s[:, 0] / s[:, -1], np.inf)
        sign = np.linalg.slogdet(J)[0]
    return cond, sign


def singular(run, X, before):
    """Index of the first row of X at which the loops pass a singular configuration (the
    dependent Jacobian turns singular, or its determinant changes sign from the row
    ``before``), or None."""
    both = conditioning(run, np.vstack([before[None, :], X]))
    if both is None:
        return None
    cond, sign = both
    for i in range(1, len(cond)):
        if not np.isfinite(cond[i]) or cond[i] > SINGULAR_CONDITION or \
                (sign[i] * sign[i - 1] < 0):
            return i - 1
    return None


def singular_words(run, t):
    system = run.system
    loops = "; ".join(" - ".join(c.loop) for c in system.topology.cuts)
    return (f"the kinematic loop ({loops}) reaches a singular configuration (a dead "
            f"point) at about t = {t:g} s: the closure no longer fixes the dependent speeds "
            f"({', '.join(system.dependent_names)}), so the mechanism folds flat, locks or "
            f"branches there; choose other independent coordinates (give q0 of the joints "
            f"that drive it, or mark another joint cut), or stop before it")


def watch(run, X, new, failure):
    """(rows, failure): the new rows up to a singular configuration of the loops, and the
    failure that stops the run there, if any."""
    if not len(new):
        return new, failure
    i = singular(run, new, X[-1])
    if i is None:
        return new, failure
    return new[:i], singular_words(run, float(run.grid[len(X) + i]))


def near_singular(run, X, grid):
    """A note for a failure of a model with loops that ended at a singular configuration: the
    Jacobian in the dependent speeds is ill-conditioned at the last output, or its
    determinant, extrapolated from the last two outputs, vanishes before the next one (a
    dead point that the integrator could not pass)."""
    parts = getattr(run, "partitions", None)
    # the rows of the partition the run ended in (an earlier one's are other variables)
    last = X[-2:] if parts is None or parts.segments[-1][0] < len(X) - 1 else X[-1:]
    both = conditioning(run, last)
    if both is None:
        return ""
    cond, _ = both
    f, n = run.system.f_dependent, run.system.f_dependent.size1_out(0)
    det = [float(np.linalg.det(np.asarray(f(row, run.p)).reshape(n, n))) for row in last]
    folding = len(det) == 2 and det[0] * det[1] > 0 and abs(det[1]) < abs(det[0]) and \
        abs(det[1]) < abs(det[0] - det[1])
    if cond[-1] < NEAR_SINGULAR_CONDITION and not folding:
        return ""
    loops = "; ".join(" - ".join(c.loop) for c in run.system.topology.cuts)
    return (f"; there (t = {grid[len(X) - 1]:g} s) the kinematic loop ({loops}) is at a "
            f"singular configuration, a dead point: its Jacobian in the dependent speeds "
            f"({', '.join(run.system.dependent_names)}) has condition number "
            f"{cond[-1]:.2g} and its determinant goes to zero, so the mechanism folds flat, "
            f"locks or branches")




class Partitions:
    """The partitions of the speeds that one run of a model with loops goes through.

    Made by the driver at the start of each integration (it puts the model's own System back
    in the run); ``watch`` reads each chunk's rows and says where to re-partition, ``switch``
    does it, ``finish`` polishes and probes each part by its own equations, ``done`` says
    where the run re-partitioned.

    Near a change point (``_Loops.partitions_at``: the closure's Jacobian itself nears a
    lower rank, so every partition turns singular together) the run crosses it in the
    ``projected`` formulation of the partition whose independent coordinates describe the
    motion best: its Newton projection starts from the carried coordinates, so it stays on
    the branch the mechanism is on, where IDAS's Newton on the dependent coordinates fails.
    Past it (the Jacobian healthy again) the run goes back to the model's own formulation in
    the best-conditioned partition."""

    def __init__(self, run):
        base = run.__dict__.setdefault("base_system", run.system)
        self.run, self.base = run, base
        self.loops = base.eq.loops if base.f_dependent is not None else None
        # (not with friction or stops: their events restart the method on their own)
        events = getattr(run, "events", None)
        self.enabled = getattr(run, "repartition", True) and self.loops is not None and \
            (events is None or events.modes is None)
        self.segments = [(0, base)]         # (first row, System), in the order met
        self.events = []                    # times of the re-partitions
        self.c0 = None                      # condition number where the partition began
        self.trigger = None                 # condition number at which to look again
        self.health = None                  # the closure Jacobian's, at its healthiest
        self.crossing = None                # lowest health met while crossing a change point
        self.steps, self.jit = run.steps_per_interval, run.jit
        self._jacobians = PointsBySize()    # the Jacobians at a chunk's rows, one map a size
        self._use(base)
        run.partitions = self

    def _use(self, system, t=None, x=None):
        # compiled to C is the model's own partition only: the others, met for a while, run
        # in CasADi's virtual machine rather than wait for the C compiler
        run = self.run
        run.jit = self.jit if system is self.base else None
        changed = run.system is not system
        run.system, run.compiled = system, compiled(system)
        run.instructions = (system.f_rhs or system.f_dae).n_instructions()
        if changed and t is not None and getattr(run, "events", None) is not None:
            run.events.rebind(t, x)          # its relations, read at the switch

    # -- where ------------------------------------------------------------------------------
    def watch(self, X, new, failure):
        """(rows, failure, choice): the new rows up to where the run re-partitions or
        stops, what stops it if it does not re-partition there, and what to take there
        (None: go on, or stop with the failure)."""
        run = self.run
        if not self.enabled:
            return (*watch(run, X, new, failure), None)
        rows = np.vstack([X[-1][None, :], np.asarray(new).reshape(-1, len(X[-1]))])
        grid, first = run.grid, len(X) - 1             # grid index of rows[0]
        if self.health is None:
            self._analyse(grid[first], rows[0])
        if self.crossing is not None:
            return self._crossing(rows, new, failure, first)
        cond, det = self._conditioning(rows)
        if self.c0 is None:
            self.c0 = cond[0]
            self.trigger = max(REPARTITION_CONDITION, REPARTITION_GROWTH * self.c0)
        for i in range(1, len(rows)):
            t = float(grid[first + i])
            if not np.isfinite(cond[i]) or cond[i] > SINGULAR_CONDITION or \
                    det[i] * det[i - 1] < 0:
                # past a singular configuration between two outputs: from the one before
                return new[:i - 1], singular_words(run, t), \
                    self._choose(grid[first + i - 1], rows[i - 1], cond[i - 1], FORCED_GAIN)
            if first + i < len(grid) - 1 and self._near(cond, det, i):
                choice = self._choose(t, rows[i], cond[i], REPARTITION_GAIN)
                if choice is not None:
                    return new[:i], failure or singular_words(run, t), choice
                self.trigger = max(self.trigger, TRIGGER_STEP * cond[i])
        if failure is not None:
            return new, failure, self._choose(grid[first + len(rows) - 1], rows[-1],
                                              cond[-1], FORCED_GAIN)
        return new, failure, None

    def _crossing(self, rows, new, failure, first):
        """The watch while crossing a change point: back to the model's own formulation in
        the best partition once the closure's Jacobian is healthy again."""
        run, grid = self.run, self.run.grid
        for i in range(1, len(rows)):
            t = float(grid[first + i])
            health, choices = self._analyse(t, rows[i]) or (0.0, [])
            self.crossing = min(self.crossing, health)
            if health > max(CROSSED * self.health, 2 * self.crossing) and \
                    first + i < len(grid) - 1:
                best = min(choices, key=lambda c: c[2])
                return new[:i], failure or singular_words(run, t), \
                    (self.base.formulation, *best[:3], False)
        return new, failure, None

    def _analyse(self, t, row):
        """(health, choices) of ``_Loops.partitions_at`` at the full state ``row``; the
        healthiest Jacobian met is kept as the scale of a change point."""
        run = self.run
        q, _ = coordinates(run.system, [t], row[None, :], run.p)
        found = self.loops.partitions_at(q[0], run.p)
        if found is not None:
            self.health = max(self.health or 0.0, found[0])
        return found

    def _conditioning(self, rows):
        """Condition number and determinant of the Jacobian in the dependent speeds at each
        full state of ``rows``."""
        run = self.run
        n = run.system.f_dependent.size1_out(0)
        # compiled, through a map kept per number of rows (``pointwise`` of the VM's: its
        # arrays and map looked up at each call, 13 us a point: 35 of the watch's 72 ms a run
        # of EngineV6)
        J = self._jacobians(run.compiled.dependent(run.jit), np.zeros(len(rows)), rows, run.p)
        J = J.reshape(len(rows), n, n).transpose(0, 2, 1)
        # block by block (its singular values are the blocks', its determinant their
        # product): EngineV6's 18 x 18 is six loops' 3 x 3, 36 times fewer operations
        high, low, det = np.zeros(len(rows)), np.full(len(rows), np.inf), np.ones(len(rows))
        with np.errstate(all="ignore"):
            for idx in _blocks(run.system):        # (blocks, size): those of one size
                part = J[:, idx[:, :, None], idx[:, None, :]]       # (rows, blocks, k, k)
                s = np.linalg.svd(part, compute_uv=False)
                high = np.maximum(high, s[..., 0].max(axis=1))
                low = np.minimum(low, s[..., -1].min(axis=1))
                det = det * np.prod(np.linalg.det(part), axis=1)
            cond = np.where(low > 0, high / low, np.inf)
        return cond, det

    def _near(self, cond, det, i):
        """Whether the row i nears a singular configuration of the partition: its condition
        number grown well beyond the one where the partition began, or its determinant,
        extrapolated from the rows i-1 and i, vanishing before the next output."""
        if cond[i] > self.trigger:
            return True
        d0, d1 = det[i - 1], det[i]
        return bool(cond[i] > PREDICTED_GROWTH * self.c0 and d0 * d1 > 0 and abs(d1) < abs(d0)
                    and abs(d1) < PREDICTED_INTERVALS * abs(d0 - d1))

    def _choose(self, t, row, cond_now, gain):
        """What to take at the full state ``row`` (time t): near a change point, the
        partition whose independent coordinates describe the motion best, to cross it in
        the projected formulation; else the best-conditioned partition, if it is not the
        present one and is ``gain`` times better conditioned. After a failure or past a
        singular configuration (``gain`` FORCED_GAIN) where no partition is that much
        better, a crossing too: the integrator failed on the way to a singular
        configuration between two outputs (once per output: if it fails again, the run
        stops). (formulation, rows, dependent speeds, condition number, crossing) or
        None."""
        found = self._analyse(t, row)
        if found is None:
            return None
        health, choices = found
        rows, dep, c, _ = min(choices, key=lambda c: c[2])
        system = self.run.system
        better = (system.formulation, rows, dep) != (self.base.formulation,
                                                     *system.eq.partition) \
            and c * gain < cond_now
        forced = gain == FORCED_GAIN
        if health < CHANGE_POINT * self.health or (forced and not better):
            # of those that describe the motion (nearly) best, the best-conditioned; Baumgarte's
            # states are all coordinates and speeds already: it crosses as it is
            top = max(c[3] for c in choices)
            rows, dep, c, _ = min((c for c in choices if c[3] >= TIED * top),
                                  key=lambda c: c[2])
            crossing = "baumgarte" if self.base.formulation == "baumgarte" else "projected"
            return crossing, rows, dep, c, True
        return (self.base.formulation, rows, dep, c, False) if better else None

    # -- the switch -------------------------------------------------------------------------
    def switch(self, method, X, choice):
        """Re-partition at the last row of X: the stepper of ``method`` started there in the
        new partition's variables (the last row of X becomes them), or None when it cannot
        be (the run then stops with the failure ``watch`` gave)."""
        run = self.run
        k = len(X) - 1
        if choice is None or k >= len(run.grid) - 1 or \
                (self.events and self.segments[-1][0] == k):       # never twice at a row
            return None
        formulation, rows, dep, c, crossing = choice
        old, t = run.system, float(run.grid[k])
        new = self.system(formulation, rows, dep)
        row = new.polish(convert(old, new, [t], np.asarray(X[-1])[None, :], run.p), run.p)[0]
        self._use(new, t, row)
        steps = run.steps_per_interval
        run.steps_per_interval = max(self.steps, CROSSING_STEPS) if crossing else self.steps
        try:
            stepper = (METHODS["rk"] if crossing else method).start(run, t, row)
        except Failure:
            self._use(old, t, X[-1])
            run.steps_per_interval = steps
            return None
        X.replace_last(row)
        self.segments.append((k, new))
        self.events.append(t)
        self.c0 = None if crossing else c
        self.trigger = None if crossing else max(REPARTITION_CONDITION, REPARTITION_GROWTH * c)
        self.crossing = self.health if crossing else None
        return stepper

    def system(self, formulation, rows, dep):
        """The System of the model in ``formulation`` with the closure rows ``rows`` kept and
        the speeds ``dep`` dependent: the model's own where that is its partition, else
        built once per partition and kept with the model's compiled functions."""
        base = self.base
        if (formulation, list(rows), list(dep)) == (base.formulation, *base.eq.partition):
            return base
        return compiled(base).memo(
            ("partition", formulation, tuple(rows), tuple(dep)),
            lambda: System(base.model, formulation, base.eq.rate, base.topology,
                           partition=(rows, dep), assembly=base.asm))

    def limit(self, chunk):
        """The output intervals of the next chunk: at most REPARTITIONED_CHUNK once the run
        has re-partitioned (a chunk that fails near a singular configuration is integrated
        again an output at a time, an integrator each)."""
        return min(chunk, REPARTITIONED_CHUNK) if self.events else chunk

    # -- the results ------------------------------------------------------------------------
    def finish(self, t, X):
        """(states, outputs) of a run that re-partitioned: each part polished and probed by
        its own partition's equations, the states then read as the model's own partition
        has them."""
        run, base = self.run, self.base
        states, outputs = np.array(X, dtype=float), []
        ends = [start for start, _ in self.segments[1:]] + [len(X)]
        for (start, system), end in zip(self.segments, ends):
            if end <= start:
                continue
            part = system.polish(states[start:end], run.p)
            f_out = compiled(system).outputs(run.jit) if system is base else system.f_out
            outputs.append(system.outputs_p(t[start:end], part, run.p, f_out))
            states[start:end] = part if system is base else \
                convert(system, base, t[start:end], part, run.p)
        return states, np.vstack(outputs)

    def done(self):
        """At the end of the integration: the run's compiled functions are the model's own
        again, and what the results say of the partitions: re-partitions (count), their
        times, and the formulation and dependent speeds of each part of the run from the
        time it began."""
        self.run.jit = self.jit
        if self.loops is None:
            return {}
        parts = [{"t": float(self.run.grid[start]), "formulation": system.formulation,
                  "dependent": system.dependent_names} for start, system in self.segments]
        return {"repartitions": len(self.events), "repartition_times": list(self.events),
                "partitions": parts}


def coordinates(system, t, X, p):
    """The coordinates q and speeds u of every joint at the full states X (rows) at times t."""
    def build():
        a, eq = system.asm, system.eq
        q = a.q if eq.q is None else eq.q
        return ca.Function("coordinates", [a.t, ca.vertcat(eq.x, eq.z), a.p],
                           [ca.densify(q), ca.densify(eq.u)])
    f = compiled(system).memo("coordinates", build)
    q, u = pointwise(f, np.asarray(t, dtype=float)[:, None], X, p)
    return q, u


def convert(a, b, t, X, p):
    """Full states X of System ``a`` (rows, at times t) as System ``b`` of the same model
    holds them: coordinates and speeds by name from a's equations, other states (the 1-D
    network's, the clock) as they are."""
    q, u = coordinates(a, t, X, p)
    names_a = a.state_names + a.algebraic_names
    coordinate = {n: i for i, n in enumerate(a.coordinate_names)}
    speed = {n: i for i, n in enumerate(a.speed_names)}
    X = np.asarray(X, dtype=float)
    columns = []
    for name in b.state_names + b.algebraic_names:
        if name in coordinate:
            columns.append(q[:, coordinate[name]])
        elif name in speed:
            columns.append(u[:, speed[name]])
        else:
            columns.append(X[:, names_a.index(name)])
    return np.column_stack(columns) if columns else np.zeros((len(X), 0))


def _blocks(system):
    """The blocks of the Jacobian in the dependent speeds (``system.f_dependent``): index sets
    that its sparsity keeps apart (the rows and columns of each kinematic loop), as one
    (blocks, size) array per size, found once per System."""
    def find():
        import networkx as nx
        # the expression's own sparsity (the Function's output is densified)
        pattern = system.eq.dependent_jacobian.sparsity()
        graph = nx.Graph()
        graph.add_nodes_from(range(pattern.size1()))
        rows, cols = pattern.get_triplet()
        graph.add_edges_from(zip(rows, cols))
        sizes = {}
        for c in nx.connected_components(graph):
            sizes.setdefault(len(c), []).append(sorted(c))
        return [np.array(blocks) for _, blocks in sorted(sizes.items())]
    return compiled(system).memo("dependent blocks", find)
