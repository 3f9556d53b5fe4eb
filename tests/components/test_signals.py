"""Signal blocks (kinetwork/components/signals.py) on their own: ``evaluate`` (the output the
equations read), ``rates`` and ``initial`` of the blocks with states. The hooks are handed
CasADi values, as the equations hand them (constant ones here), and parameters as given."""

import math

import casadi as ca
import pytest

import kinetwork as kn

sig = kn.signals


def number(value):
    return float(ca.evalf(ca.SX(value)))


def sx(u, x, t):
    """Inputs, states and time as the equations pass them: CasADi values (None: unwired)."""
    return ({k: None if v is None else ca.SX(v) for k, v in u.items()},
            [ca.SX(v) for v in x], ca.SX(t))


def out(block, u=None, x=(), t=0.0):
    return number(block.evaluate(*sx(u or {}, x, t), None))


def rates(block, u, x, t=0.0):
    return [number(r) for r in block.rates(*sx(u, x, t))]


@pytest.mark.parametrize("block, u, t, expected", [
    (sig.Constant("c", k=2.5), {}, 0.0, 2.5),
    (sig.Step("s", height=2.0, offset=1.0, start_time=1.0), {}, 0.5, 1.0),
    (sig.Step("s", height=2.0, offset=1.0, start_time=1.0), {}, 1.0, 3.0),
    (sig.Ramp("r", height=4.0, duration=2.0, start_time=1.0), {}, 0.0, 0.0),
    (sig.Ramp("r", height=4.0, duration=2.0, start_time=1.0), {}, 1.5, 1.0),
    (sig.Ramp("r", height=4.0, duration=2.0, start_time=1.0), {}, 9.0, 4.0),
    (sig.Sine("s", amplitude=2.0, f=0.5, phase=0.3, offset=1.0), {}, 0.4,
     1.0 + 2.0 * math.sin(math.pi * 0.4 + 0.3)),
    (sig.Sine("s", amplitude=2.0, start_time=1.0, offset=1.0), {}, 0.9, 1.0),
    (sig.Gain("g", k=-3.0), {"u": 2.0}, 0.0, -6.0),
    (sig.Add("a", k1=2.0, k2=-1.0), {"u1": 3.0, "u2": 4.0}, 0.0, 2.0),
    (sig.Sum("s"), {"u1": 1.0, "u2": None, "u3": 2.0, "u4": None}, 0.0, 3.0),
    (sig.Product("p"), {"u1": 3.0, "u2": -2.0}, 0.0, -6.0),
    (sig.Limiter("l", u_max=1.0), {"u": -5.0}, 0.0, -1.0),
    (sig.Limiter("l", u_max=1.0, u_min=0.2), {"u": 0.0}, 0.0, 0.2),
    (sig.Limiter("l", u_max=1.0), {"u": 0.5}, 0.0, 0.5),
    (sig.Table("tb", table=[[0, 0], [1, 2], [3, 0]]), {"u": 2.0}, 0.0, 1.0),
    (sig.Table("tb", table=[[0, 0], [1, 2], [3, 0]]), {"u": None}, 0.5, 1.0),  # time
    (sig.Table("tb", table=[[0, 0], [1, 2]]), {"u": 3.0}, 0.0, 6.0),   # extrapolated
], ids=lambda v: getattr(v, "type_name", None))
def test_stateless_blocks(block, u, t, expected):
    assert out(block, u, t=t) == pytest.approx(expected)
    assert block.n_states == 0 and rates(block, u, []) == [] and block.initial() == []


def test_integrator_and_first_order_have_one_state():
    integ = sig.Integrator("i", k=2.0, y_start=0.5)
    assert integ.initial() == [0.5] and not integ.feedthrough
    assert out(integ, {"u": 3.0}, x=[1.25]) == 1.25                  # y is the state
    assert rates(integ, {"u": 3.0}, [1.25]) == [6.0]                  # k u
    lag = sig.FirstOrder("f", k=2.0, T=0.5)
    assert out(lag, {"u": 1.0}, x=[0.4]) == 0.4
    assert rates(lag, {"u": 1.0}, [0.4]) == [pytest.approx((2.0 - 0.4) / 0.5)]
    with pytest.raises(kn.ModelError, match=r"f\.T = 0 s: must be > 0"):
        sig.FirstOrder("f", T=0)


def test_derivative_filters_its_input():
    d = sig.Derivative("d", k=2.0, T=0.1, x_start=1.0)
    assert d.initial() == [1.0] and d.feedthrough
    assert out(d, {"u": 1.5}, x=[1.0]) == pytest.approx(2.0 * 0.5 / 0.1)
    assert rates(d, {"u": 1.5}, [1.0]) == [pytest.approx(0.5 / 0.1)]


def test_pid_clips_and_winds_back():
    pid = sig.PID("c", k=2.0, Ti=0.5, Td=0.1, Nd=10.0, y_max=3.0, xi_start=0.2)
    assert pid.initial() == [0.2, 0.0]
    u = {"u_s": 1.0, "u_m": 0.25}                      # e = 0.75
    e, deriv = 0.75, 10.0 * (0.75 - 0.5)
    unlimited = 2.0 * (e + 0.2 + deriv)
    assert out(pid, u, x=[0.2, 0.5]) == pytest.approx(min(unlimited, 3.0))
    di, dd = rates(pid, u, [0.2, 0.5])
    assert dd == pytest.approx((e - 0.5) * 10.0 / 0.1)
    assert di == pytest.approx((e + (3.0 - unlimited) / (2.0 * 0.9)) / 0.5)   # back-calculation
    proportional = sig.PID("p", k=2.0)                  # no I, no D, no limits
    assert out(proportional, u, x=[7.0, 7.0]) == pytest.approx(1.5)
    assert rates(proportional, u, [7.0, 7.0]) == [0.0, 0.0]    # Td = 0 divides nothing


class Mechanics:
    """What ``InverseDynamics.evaluate`` is handed: the model's inverse dynamics (here a
    stand-in recording what it is asked)."""

    def __init__(self, n, joints):
        self.n_speeds, self.joints, self.asked = n, joints, []

    def speed_of(self, name):
        return self.joints.get(name)

    def inverse(self, a):
        self.asked.append(list(a))
        return [10.0 * (i + 1) + sum(a) for i in range(self.n_speeds)]

    def refuse(self, block, key, message):
        return kn.ModelError(f"{block.name}.{key}: {message}")


def test_inverse_dynamics_reads_the_models_own_dynamics():
    block = sig.InverseDynamics("inv", joint="elbow")
    mechanics = Mechanics(2, {"shoulder": 0, "elbow": 1})
    u = {"a1": 0.5, "a2": None, "a3": None, "a4": None}
    assert block.evaluate(u, [], 0.0, mechanics) == 20.5
    assert mechanics.asked == [[0.5, 0]]                 # unwired accelerations are 0
    with pytest.raises(NotImplementedError):
        block.output(u, [], 0.0)                         # only evaluate knows the mechanics


@pytest.mark.parametrize("n, joints, message", [
    (5, {"elbow": 0}, "at most 4 joint coordinates; this model has 5"),
    (2, {"shoulder": 0}, "'elbow' is not a joint with one degree of freedom"),
])
def test_inverse_dynamics_refuses_what_it_cannot_do(n, joints, message):
    block = sig.InverseDynamics("inv", joint="elbow")
    u = {f"a{i}": 0.0 for i in range(1, 5)}
    with pytest.raises(kn.ModelError, match=message):
        block.evaluate(u, [], 0.0, Mechanics(n, joints))
