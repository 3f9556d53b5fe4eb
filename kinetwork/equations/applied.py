"""What acts on the tree besides its bodies' inertia and a uniform gravity: the force
elements on frames, a gravity field that varies in space, and the point masses that ride on
line forces.

- A force element's ``wrenches`` (force at a frame's origin and torque, in the world) enter
  as generalized forces J^T f + J_w^T t, J and J_w the Jacobians of that frame's velocity and
  angular velocity in the speeds (reverse mode: O(size of the expressions)).
- A uniform gravity is an upward acceleration of the world in the Newton-Euler passes; a
  point gravity field (the Ground's ``gravity_type`` "point") is not uniform, so it enters as
  the force m g(c) on every body at its centre of mass c, a generalized force J_c^T m g(c).
- A point mass m at r = sum(w_i r_i) of its element's frame origins (weights fixed) is no
  body of the tree: it moves with two frames that may hang from different branches. Its
  kinetic energy m |J u|^2 / 2 (J = d(dr/dt)/du) adds m J^T J to the mass matrix, and its
  equation m (J udot + (dJ/dt) u - g(r)) = its share of the forces adds the generalized forces
  m J^T (g(r) - (dJ/dt) u). The forward dynamics stay O(n) per point mass: with Y = M^-1 J^T
  from the articulated-body algorithm (3 columns per mass) and W = diag(m),
  (M + J^T W J)^-1 = M^-1 - Y W (I + J Y W)^-1 J M^-1 (Woodbury; I + J Y W is regular for
  any m >= 0, so a mass that is a parameter may be zero). A point mass may also sit where its
  element's ``position(origins)`` puts it (at a fixed distance along a line): J and the
  shares of its inertial force on the frames, (dr/dr_port)^T m (a - g), follow by AD.
"""

from dataclasses import dataclass

import casadi as ca

from ..errors import ModelError
from ..spatial import vee
from .newton_euler import aba


@dataclass
class Frame:
    """A frame as a force element sees it: world orientation, origin, velocity of the origin
    and angular velocity (all in the world)."""
    R: ca.SX
    r: ca.SX
    v: ca.SX
    w: ca.SX


@dataclass
class Rider:
    """Inertia that moves with the tree without being one of its bodies: a point mass of a
    force element, or a body (or an assembly's point mass) on a frame an assembly places.
    Its velocity rows are J u (3 for a point: the velocity; 6 for a body: the angular
    velocity, then the velocity of its centre of mass, in the world), its inertia W in those
    rows (m I, or diag(I_world, m I)); ``bias`` is (dJ/dt) u."""
    element: str
    W: ca.SX
    J: ca.SX
    bias: ca.SX


class Extra:
    """The gravity field and the point masses of a model, over the tree ``bodies``.

    ``uniform`` is the uniform gravity the Newton-Euler passes take (zero under a point
    field); ``field(r)`` the gravity acceleration at a world point; ``Q_gravity`` the
    generalized forces of the gravity the passes do not take (a point field on the bodies,
    any field on the point masses) and ``Q_inertia`` those of the point masses' velocity
    terms, -m J^T (dJ/dt) u; ``Q`` their sum.
    """

    def __init__(self, topo, bound, bodies, place, q, u, qdot, placing=None):
        n = u.shape[0]
        self.bodies, self.u = bodies, u
        world = bound[topo.world.name] if topo.world else None
        uniform = world.uniform_gravity() if world is not None else ca.SX.zeros(3)
        self.uniform = ca.SX.zeros(3) if uniform is None else ca.SX(uniform)
        self.field = world.gravity_at if world is not None else (lambda r: ca.SX.zeros(3))
        self.masses = []
        self.Q_gravity, self.Q_inertia = ca.SX.zeros(n), ca.SX.zeros(n)
        self.Q = ca.SX.zeros(n)
        if not n:
            return
        poses = _body_poses(bodies)

        def position(s):
            return _set_pose(poses, place, s)[1]

        def rate(x):
            return ca.jtimes(x, q, qdot)
        inner = placing.sets if placing is not None else set()
        if uniform is None:
            for body, s in topo.bodies:
                if place[s][0] < 0 or s in inner:
                    continue            # welded to the ground: it takes what it weighs
                m, c, _ = bound[body.name].mass_properties()
                R, p = _set_pose(poses, place, s)
                cw = p + R @ c
                self.Q_gravity += ca.jtimes(rate(cw), u, m * self.field(cw), True)
        for body, s in topo.bodies:
            if s in inner:
                self._body(body.name, bound[body.name].mass_properties(),
                           _set_pose(poses, place, s), q, u, qdot)
        for name, m, k, r in placing.masses if placing is not None else ():
            R, p = poses[k] if k >= 0 else (ca.SX.eye(3), ca.SX.zeros(3))
            self._point(name, m, p + R @ r, q, u, qdot)
        for comp in topo.forces:
            for m, weights in bound[comp.name].point_masses():
                if ca.SX(m).is_zero() or set(topo.junctions) & {
                        topo.set_of[comp.port_ref(port)] for port in weights}:
                    continue            # no mass: nothing to add, not even a solve
                r = mass_position(weights, {port: position(topo.set_of[comp.port_ref(port)])
                                            for port in weights})
                self._point(comp.name, m, r, q, u, qdot)
        self.Q = self.Q_gravity + self.Q_inertia

    def _point(self, name, m, r, q, u, qdot):
        """A point mass m at the world point r(q)."""
        J = ca.jacobian(ca.jtimes(r, q, qdot), u)
        bias = ca.jtimes(J @ u, q, qdot)
        self.masses.append(Rider(name, m * ca.SX.eye(3), J, bias))
        self.Q_gravity += J.T @ (m * self.field(r))
        self.Q_inertia -= J.T @ (m * bias)

    def _body(self, name, properties, pose, q, u, qdot):
        """A body (mass, centre of mass and inertia in its frame) on a frame at the world
        ``pose`` (R, p in q) that is no body of the tree: Newton and Euler's equations
        m (a_c - g) and I alpha + w x I w, taken to the speeds by J^T."""
        m, c, Ic = properties
        R, p = pose
        cw = p + R @ c
        w = vee(ca.reshape(ca.jtimes(ca.vec(R), q, qdot), 3, 3) @ R.T)
        J = ca.jacobian(ca.vertcat(w, ca.jtimes(cw, q, qdot)), u)
        Iw = R @ Ic @ R.T
        W = ca.diagcat(Iw, m * ca.SX.eye(3))
        bias = ca.jtimes(J @ u, q, qdot)
        self.masses.append(Rider(name, W, J, bias))
        self.Q_gravity += J[3:, :].T @ (m * self.field(cw))
        self.Q_inertia -= J.T @ (W @ bias) + J[:3, :].T @ ca.cross(w, Iw @ w)

    def mass_matrix(self):
        """sum J^T W J over the riders (None without any)."""
        if not self.masses:
            return None
        return sum((r.J.T @ r.W @ r.J for r in self.masses),
                   ca.SX.zeros(self.u.shape[0], self.u.shape[0]))

    def mass_times(self, w):
        """sum J^T W J w over the riders (O(n) each)."""
        return sum((r.J.T @ (r.W @ (r.J @ w)) for r in self.masses),
                   ca.SX.zeros(self.u.shape[0]))

    def forward(self, a0, armature):
        """The speeds' rates with the riders, from ``a0``, those of the tree alone under all
        the generalized forces (Q included): a0 - Y W (I + J Y W)^-1 J a0."""
        if not self.masses:
            return a0
        n = self.u.shape[0]
        zero = ca.SX.zeros(n)
        J = ca.vertcat(*[r.J for r in self.masses])
        W = ca.diagcat(*[r.W for r in self.masses])
        # M^-1 J^T column by column: the articulated-body algorithm with no speed, no gravity
        Y = ca.horzcat(*[ca.substitute(aba(self.bodies, zero, J[i, :].T, ca.SX.zeros(6),
                                           armature), self.u, zero)
                         for i in range(J.shape[0])])
        S = ca.SX.eye(J.shape[0]) + J @ Y @ W
        return a0 - Y @ (W @ ca.solve(S, J @ a0))


def element_forces(asm, topo, bound):
    """Generalized forces of the force elements' wrenches (their point masses aside)."""
    Q = ca.SX.zeros(asm.u.shape[0])
    if not asm.u.shape[0]:
        return Q
    junctions = asm.junctions.elements if asm.junctions is not None else set()
    for comp in topo.forces:
        if comp.name in junctions:
            continue            # a line force with an end at a junction: junctions.py
        frames = _frames(asm, topo, comp)
        out = bound[comp.name].wrenches(frames, _inputs(asm, topo, comp))
        for port, (force, torque) in out.items():
            Q += (ca.jtimes(frames[port].v, asm.u, ca.SX(force), True)
                  + ca.jtimes(frames[port].w, asm.u, ca.SX(torque), True))
        if ca.depends_on(Q, asm.udot):
            raise ModelError(f"algebraic loop through {comp.name} and the mechanics: a "
                             f"signal input of {comp.name} reads an acceleration or a force "
                             f"at the same instant; break it with a state (an Integrator, a "
                             f"FirstOrder or a filtered Derivative)", component=comp.name)
    return Q + asm.junctions.Q if junctions else Q


def element_wrench(asm, topo, bound, comp, port):
    """(force, moment about the world origin) that force element ``comp`` applies on the
    frame at ``port``: its wrench there and the share of its point masses' inertia and
    weight, -w m (a - g) (in q, u and udot)."""
    if asm.junctions is not None and comp.name in asm.junctions.lines:
        force = asm.junctions.lines[comp.name].force[port]
        return force, ca.cross(asm.pose(topo.set_of[comp.port_ref(port)])[1], force)
    frames = _frames(asm, topo, comp)
    if frames.get(port) is None:
        return ca.SX.zeros(3), ca.SX.zeros(3)
    c = bound[comp.name]
    force, torque = c.wrenches(frames, _inputs(asm, topo, comp)).get(
        port, (ca.SX.zeros(3), ca.SX.zeros(3)))
    force, torque = ca.SX(force), ca.SX(torque)
    for m, weights in c.point_masses():
        if port not in weights or ca.SX(m).is_zero():
            continue
        origins = {p: frames[p].r for p in weights}
        r = mass_position(weights, origins)
        force = force - share(weights, origins, port).T @ (
            m * (asm.rate(asm.rate(r)) - asm.applied.field(r)))
    return force, ca.cross(frames[port].r, force) + torque


def mass_position(weights, origins):
    """Where a force element's point mass sits, from its element's frame origins
    (port -> r): sum(w r) for fixed weights, or the placement's own ``position(origins)``
    (a mass at a fixed distance along a line, as MSL's LineForceWithTwoMasses)."""
    if hasattr(weights, "position"):
        return weights.position(origins)
    return sum((w * origins[p] for p, w in weights.items()), ca.SX.zeros(3))


def share(weights, origins, port):
    """d(position)/d(origin of ``port``), 3 x 3: its transpose takes the point mass's
    inertial force and weight to ``port`` (virtual work), w I for fixed weights."""
    if not hasattr(weights, "position"):
        return weights[port] * ca.SX.eye(3)
    stand_in = {p: ca.SX.sym(f"r_{p}", 3) for p in origins}
    J = ca.jacobian(weights.position(stand_in), stand_in[port])
    return ca.substitute(J, ca.vertcat(*stand_in.values()), ca.vertcat(*origins.values()))


def _frames(asm, topo, comp):
    """port -> Frame of a component's frame ports (None for one left unwired)."""
    out = {}
    for name, port in comp.ports.items():
        if port.domain != "frame":
            continue
        s = topo.set_of[comp.port_ref(name)]
        if s not in asm.place and (asm.junctions is None or s not in asm.junctions.position):
            out[name] = None
            continue
        R, r = asm.pose(s)
        out[name] = Frame(R, r, asm.rate(r, False), asm.angular_velocity(R, False))
    return out


def _inputs(asm, topo, comp):
    """port -> value of a component's signal inputs (None for one left unwired)."""
    out = {}
    for name, port in comp.ports.items():
        if port.domain == "signal_in":
            s = topo.set_of[comp.port_ref(name)]
            out[name] = asm.net.signal.get(s) if s in topo.signal_source else None
    return out


def _body_poses(bodies):
    """World orientation and origin of every body (parents come first)."""
    poses = []
    for b in bodies:
        if b.parent < 0:
            poses.append((b.R, b.p))
        else:
            R, p = poses[b.parent]
            poses.append((R @ b.R, p + R @ b.p))
    return poses


def _set_pose(poses, place, s):
    """World orientation and origin of frame set ``s``."""
    k, R, p = place[s]
    if k < 0:
        return R, p
    Rk, pk = poses[k]
    return Rk @ R, pk + Rk @ p

