"""Cut force and torque through a frame connection, from the wrench balance of the motion.

The flow into a component through one of its frame ports (Modelica's sign: positive into
the component) is what the rest of the model exerts on it there:

- a rigid body takes its inertial wrench, m (a_c - g) and I alpha + w x I w; a joint or
  rigid part with mass (a body with a shape) takes its own at frame_a, besides what it passes
  on;
- a force element (line force, world force) takes minus the force it applies;
- a cut joint takes minus the constraint wrench it applies, from the loops' multipliers;
- an assembly that closes its loop in closed form has no mass and no multiplier: at its
  inner frames it takes what the rest exerts there, and at frame_a and frame_b the wrench that
  makes its power vanish with those (virtual work through its kinematics: MSL computes the
  same by hand, its f_rod), its point masses' inertia and weight and its axis's force
  included;
- a joint or rigid part of the spanning tree passes on everything behind it: through its
  port away from the ground flows minus the sum of the flows into every body, force element
  and cut joint of the subtree beyond it, less the drives of the joints there (the inward
  pass of Newton-Euler, per frame connection); through its port towards the ground, that
  sum less its own drive;
- a joint's drive (the flow into its 1-D axis flanges) acts on its frame_b and reacts, through
  the support flange, on the world (Modelica's convention), so a revolute's frames carry no
  torque about its axis;
- the ground takes minus everything else on its frame.

All wrenches are resolved in the world frame, with moments about the world origin; the
probe reports the torque about the frame's own origin.
"""

import casadi as ca

from ..spatial import skew, vee
from .applied import element_wrench
from .newton_euler import motion_subspace


def cut_wrench(asm, topo, target, bound):
    """(force, moment about the world origin) flowing into ``target``'s component there."""
    return _Balance(asm, topo, bound).flow(target.component, target.name)


class _Balance:
    def __init__(self, asm, topo, bound):
        self.asm, self.topo, self.bound = asm, topo, bound
        self.children = {}
        self.edge_of = {}
        for e in topo.tree:
            self.children.setdefault(e.parent, []).append(e.child)
            self.edge_of[e.component.name] = e
        self.cut_of = {c.component.name: (i, c) for i, c in enumerate(topo.cuts)}
        self.assembly_of = {c.component.name: c for c in topo.assemblies}
        for e in topo.placements:          # rigid parts hanging from an assembly's frames
            if e.component.name not in self.assembly_of:
                self.children.setdefault(e.parent, []).append(e.child)
                self.edge_of[e.component.name] = e
        self.rows = {}
        start = 0
        for i, (_, r) in enumerate(asm.cuts):
            self.rows[i] = (start, start + r.shape[0])
            start += r.shape[0]

    def flow(self, comp, port):
        f, m = self._flow(comp, port)
        if _massive(comp) and port == "frame_a":
            df, dm = self._inertial(comp)
            f, m = f + df, m + dm
        return f, m

    def _flow(self, comp, port):
        """The flow into ``comp`` at ``port``, less the inertia of a part with mass."""
        name = comp.name
        set_ = self.topo.set_of[comp.port_ref(port)]
        if comp.role == "body":
            return self._inertial(comp)
        if comp.role == "frame_force":
            f, m = self._applied(comp, port)
            return -f, -m
        if comp.role == "world":
            return self._minus_rest(set_, comp)
        if name in self.assembly_of:
            if port in ("frame_a", "frame_b"):
                return self._assembly(self.assembly_of[name], port)
            if port in getattr(type(comp), "placed_frames", ()):
                return self._minus_rest(set_, comp)
            return ca.SX.zeros(3), ca.SX.zeros(3)
        if name in self.cut_of:
            if port not in ("frame_a", "frame_b"):     # a frame it places: for probes only
                return ca.SX.zeros(3), ca.SX.zeros(3)
            f, m = self._constraint(*self.cut_of[name], port)
            if port == "frame_b":              # a cut joint's drive acts there too
                df, dm = self._drive(comp)
                f, m = f + df, m + dm
            return -f, -m
        edge = self.edge_of[name]
        f, m = self._subtree(edge.child, skip=name)
        if set_ != edge.parent:
            return -f, -m
        # towards the ground the joint passes on what it transmits, less its own drive:
        # that acts on frame_b (beyond, or on this side when the joint is reversed) and
        # reacts on the world
        df, dm = self._drive(comp)
        return f - df, m - dm

    def _minus_rest(self, set_, comp):
        f, m = ca.SX.zeros(3), ca.SX.zeros(3)
        for ref in self.topo.sets[set_]:
            if ref.component is comp or ref.component.role == "probe":
                continue
            df, dm = self.flow(ref.component, ref.name)
            f, m = f + df, m + dm
        return -f, -m

    def _subtree(self, root, skip=None):
        """What the subtree beyond ``root`` takes: the flows into its bodies, force elements
        and cut joints, less the drives of its joints (but ``skip``'s)."""
        f, m = ca.SX.zeros(3), ca.SX.zeros(3)
        stack = [root]
        while stack:
            s = stack.pop()
            stack.extend(self.children.get(s, []))
            for ref in self.topo.sets[s]:
                comp = ref.component
                if comp.role in ("body", "frame_force") or comp.name in self.cut_of or (
                        comp.name in self.assembly_of and ref.name in ("frame_a", "frame_b")):
                    df, dm = self._flow(comp, ref.name)
                    f, m = f + df, m + dm
                if _massive(comp) and ref.name == "frame_a":
                    df, dm = self._inertial(comp)
                    f, m = f + df, m + dm
                if comp.role == "joint" and ref.name == "frame_b" and comp.name != skip \
                        and comp.name not in self.cut_of:
                    df, dm = self._drive(comp)
                    f, m = f - df, m - dm
        return f, m

    def _assembly(self, cut, port):
        """Flow into an assembly at its frame_a or frame_b: minus d(power of its loads)/d(twist
        of that end), the other end held. Its loads are what the rest exerts at its inner
        frames, its axis's force and its point masses' inertia and weight; the twist (w, v)
        is the world angular velocity and the velocity of the point at the world origin,
        whose dual is (moment about the world origin, force)."""
        asm, comp = self.asm, self.bound[cut.component.name]
        Ra, pa, Rb, pb = asm.relative_poses(cut.set_a, cut.set_b)
        R0, p0 = asm.base
        R_s, p_s = ca.SX.sym("R", 3, 3), ca.SX.sym("p", 3)
        w, v = ca.SX.sym("w", 3), ca.SX.sym("v", 3)
        if port == "frame_a":
            rel, (Rf, pf), actual = (R_s.T @ Rb, R_s.T @ (pb - p_s)), (R_s, p_s), (Ra, pa)
        else:
            rel, (Rf, pf), actual = (Ra.T @ R_s, Ra.T @ (p_s - pa)), (Ra, pa), (Rb, pb)
        placement = comp.place(*rel, asm.placed.branches[comp.name])
        moving = ca.vertcat(ca.vec(R_s), p_s)
        # in the shared body's axes the end turns at R0^T w and its origin moves at
        # R0^T (v + w x its world position)
        rate = ca.vertcat(ca.vec(skew(R0.T @ w) @ R_s),
                          R0.T @ (v + ca.cross(w, p0 + R0 @ p_s)))

        def world(R, p):
            return R0 @ Rf @ R, p0 + R0 @ (pf + Rf @ p)
        power = ca.SX(0)
        for pname, (R, p) in placement.frames.items():
            Rw, pw = world(R, p)
            f, m = self._minus_rest(self.topo.set_of[cut.component.port_ref(pname)],
                                    cut.component)
            omega = vee(ca.reshape(ca.jtimes(ca.vec(Rw), moving, rate), 3, 3) @ Rw.T)
            power += ca.dot(m - ca.cross(pw, f), omega) + ca.dot(f, ca.jtimes(pw, moving, rate))
        if placement.coordinate is not None:
            axis = asm.net.flow.get(cut.component.port_ref("axis"), 0)
            power += axis * ca.jtimes(placement.coordinate, moving, rate)
        for mass, r in placement.masses:
            rw = world(ca.SX.eye(3), r)[1]
            real = ca.substitute(rw, moving, ca.vertcat(ca.vec(actual[0]), actual[1]))
            f = -mass * (asm.rate(asm.rate(real)) - asm.applied.field(real))
            power += ca.dot(f, ca.jtimes(rw, moving, rate))
        G = ca.substitute(ca.jacobian(power, ca.vertcat(w, v)), moving,
                          ca.densify(ca.vertcat(ca.vec(actual[0]), actual[1])))
        return -G[3:].T, -G[:3].T

    def _drive(self, comp):
        """Wrench the 1-D flanges of a joint apply on its frame_b (force, moment about the
        world origin): the generalized force times the motion subspace."""
        asm = self.asm
        if not comp.coordinate_ports or comp.name not in asm.uindex:
            return ca.SX.zeros(3), ca.SX.zeros(3)
        c = self.bound[comp.name]
        qj = asm.q[asm.qindex[comp.name]]
        uj = asm.u[asm.uindex[comp.name]]
        S = motion_subspace(c, qj, uj, *c.transform(qj))
        wrench = S @ asm.Q_drive[asm.uindex[comp.name]]
        R, p = asm.pose(self.topo.set_of[comp.port_ref("frame_b")])
        force = R @ wrench[3:]
        return force, R @ wrench[:3] + ca.cross(p, force)

    def _inertial(self, body):
        asm = self.asm
        R, p = asm.pose(self.topo.set_of[body.port_ref("frame_a")])
        m, c, Ic = self.bound[body.name].mass_properties()
        cw = p + R @ c
        a = asm.rate(asm.rate(cw))
        w = asm.angular_velocity(R)
        alpha = asm.rate(w)
        Iw = R @ Ic @ R.T
        force = m * (a - asm.applied.field(cw))
        return force, ca.cross(cw, force) + Iw @ alpha + ca.cross(w, Iw @ w)

    def _applied(self, comp, port):
        """Force applied by a force element at ``port`` (its point masses' share of inertia
        and weight included) and its moment about the origin."""
        return element_wrench(self.asm, self.topo, self.bound, comp, port)

    def _constraint(self, i, cut, port):
        """Constraint wrench a cut joint applies on the frame at ``port``: the dual of the
        closure rows' rate under a world twist of that frame, times the multipliers."""
        asm = self.asm
        comp = self.bound[cut.component.name]
        Ra, pa, Rb, pb = asm.relative_poses(cut.set_a, cut.set_b)
        R0, p0 = asm.base
        qj = asm.q[asm.qindex[comp.name]] if comp.dof and comp.regular else ca.SX(0, 1)
        R_s, p_s = ca.SX.sym("R", 3, 3), ca.SX.sym("p", 3)
        w, v = ca.SX.sym("w", 3), ca.SX.sym("v", 3)
        if port == "frame_a":
            rows, pose = comp.closure(R_s.T @ Rb, R_s.T @ (pb - p_s), qj), (Ra, pa)
        else:
            rows, pose = comp.closure(Ra.T @ R_s, Ra.T @ (p_s - pa), qj), (Rb, pb)
        # (w, v): world twist, v the velocity of the point at the world origin; in the
        # shared body's axes the frame turns at R0^T w and its origin moves at R0^T v_origin
        origin_velocity = v + ca.cross(w, p0 + R0 @ p_s)
        rate = ca.jtimes(rows, ca.vertcat(ca.vec(R_s), p_s),
                         ca.vertcat(ca.vec(skew(R0.T @ w) @ R_s), R0.T @ origin_velocity))
        G = ca.substitute(ca.jacobian(rate, ca.vertcat(w, v)),
                          ca.vertcat(ca.vec(R_s), p_s),
                          ca.densify(ca.vertcat(ca.vec(pose[0]), pose[1])))
        lo, hi = self.rows[i]
        wrench = G.T @ asm.lam[lo:hi]
        # the dual of (w, v) is (moment about the world origin, force)
        return wrench[3:], wrench[:3]


def _massive(comp):
    """A joint or rigid part with mass: a body on its frame_a as well."""
    return comp.role in ("joint", "part") and comp.has_mass
