"""What the tolerance means (issue 18): the default method's global error stays within 100 x
rtol against closed forms, and ``error_estimate=True`` says how large it is (within a factor
10 of the true error) and, on chaotic motion, from when the estimate means nothing.

Short horizons and CasADi's virtual machine (no C compiler): accuracy is what is checked;
the whole-range table (rtol 1e-4 .. 1e-10, 10 s, every bench scene) is
``bench/study_tolerance.py``'s."""

import numpy as np
import pytest
from scenes import chains, fourbar
from scenes import reference_loops as rl
from scenes.reference import seed_reference

import kinetwork as kn
from kinetwork.solver import tolerance
from kinetwork.solver.methods import METHODS

T_END = 3.0
N_POINTS = 151


@pytest.fixture(scope="module")
def seed_large():
    """The seed at large angles (damped: not chaotic), and its closed form."""
    system = chains.seed(q0=(2.5, 2.0)).compile()
    t = np.linspace(0.0, T_END, N_POINTS)
    return system, seed_reference(t, x0=(2.5, 2.0, 0.0, 0.0), rtol=1e-10, atol=1e-12)[:, :2]


@pytest.fixture(scope="module")
def four_bar():
    """The crank-rocker four-bar (the default: the projected ODE, CVODES Adams), and its
    sympy-derived reference."""
    system = fourbar(probes=False).compile()
    t = np.linspace(0.0, T_END, N_POINTS)
    return system, rl.fourbar_simulate(1.0, 0.0, t, rtol=1e-10, atol=1e-10)["theta"][:, None]


def _error(system, reference, rtol, names):
    res = kn.simulate(system, t_end=T_END, n_points=N_POINTS, rtol=rtol, atol=rtol / 100,
                      jit=False)
    return float(np.max(np.abs(np.column_stack([res[n] for n in names]) - reference)))


@pytest.mark.parametrize("rtol", [1e-5, 1e-8])
@pytest.mark.parametrize("scene, names", [("seed_large", ["shoulder.q", "elbow.q"]),
                                          ("four_bar", ["A.q"])])
def test_global_error_within_100_rtol(request, scene, names, rtol):
    """The default's global error against the closed form is within 100 x rtol; with the
    tolerances handed to the solvers as asked it was not (the four-bar by 900 x in 3 s, 9e4 x
    in 10 s), so the mapping is what keeps it."""
    system, reference = request.getfixturevalue(scene)
    assert _error(system, reference, rtol, names) <= 100 * rtol
    if scene == "four_bar":
        tolerance.ENABLED = False
        try:
            assert _error(system, reference, rtol, names) > 100 * rtol
        finally:
            tolerance.ENABLED = True


def test_adams_corrector_is_looser_on_large_equations_and_keeps_the_error(seed_large,
                                                                          monkeypatch):
    """CVODES Adams's corrector stops at LOOSE_CORRECTOR of the step's tolerance on equations
    over LOOSE_CORRECTOR_ABOVE instructions (fewer evaluations on 128-link chains:
    bench/work_precision_options.py), at CVODES's own test below, and BDF's Newton iteration
    is left alone. The seed made to count as large: CVODES gets the option (other
    evaluations) and the global error is still within 100 x rtol of the closed form."""
    adams, above = METHODS["cvodes-adams"], tolerance.LOOSE_CORRECTOR_ABOVE
    assert tolerance.corrector_test(adams, above) == {}
    assert tolerance.corrector_test(adams, above + 1) == {
        "nonlin_conv_coeff": tolerance.LOOSE_CORRECTOR}
    assert tolerance.corrector_test(METHODS["cvodes"], 10 * above) == {}
    reference = seed_large[1]

    def run():      # a System of its own: a run again replays the last one's integrator
        res = kn.simulate(chains.seed(q0=(2.5, 2.0)).compile(), t_end=T_END,
                          n_points=N_POINTS, rtol=1e-6, atol=1e-8, jit=False)
        error = np.max(np.abs(np.column_stack([res["shoulder.q"], res["elbow.q"]])
                              - reference))
        return res.method, res.stats["rhs_evaluations"], error

    method, evaluations, _ = run()
    assert method == "cvodes-adams"
    monkeypatch.setattr(tolerance, "LOOSE_CORRECTOR_ABOVE", 0)
    method, loose, error = run()
    assert method == "cvodes-adams" and loose != evaluations
    assert error <= 100 * 1e-6


def test_solver_tolerances_tighten_and_stop_at_the_floor(seed_large, four_bar):
    tree, loops = seed_large[0], four_bar[0]
    adams, idas = METHODS["cvodes-adams"], METHODS["idas"]
    assert tolerance.solver_tolerances(adams, tree, 1e-6, 1e-8)[:2] == \
        pytest.approx((1e-6 / tolerance.TIGHTEN["cvodes-adams", False],
                       1e-8 / tolerance.TIGHTEN["cvodes-adams", False]))
    rtol, atol = tolerance.solver_tolerances(idas, loops, 1e-6, 1e-8)
    factor = tolerance.TIGHTEN["idas", True]
    assert (rtol, atol) == pytest.approx((1e-6 / factor, 1e-8 / factor))
    assert tolerance.step_budget(idas, loops, 10.0) == int(tolerance.RUN_STEPS * factor ** 0.2)
    floor = tolerance.RTOL_FLOOR["idas"]
    assert tolerance.solver_tolerances(idas, loops, 1e-10, 1e-12)[:2] == \
        pytest.approx((floor, 1e-12 * floor / 1e-10))
    # loops under Adams (the default): rtol 1e-10 runs at 1e-14, above Adams' floor, so the
    # error estimate's repetition still runs tighter
    assert tolerance.solver_tolerances(adams, loops, 1e-10, 1e-12)[0] == pytest.approx(
        1e-10 / tolerance.TIGHTEN["cvodes-adams", True])
    assert tolerance.RTOL_FLOOR["cvodes-adams"] < 1e-10 / tolerance.TIGHTEN["cvodes-adams", True]
    # asked below the floor: as asked, never looser
    assert tolerance.solver_tolerances(idas, loops, 1e-14, 1e-16) == \
        pytest.approx((1e-14, 1e-16))


def test_a_longer_run_gets_tighter_tolerances_by_the_square_of_its_length(seed_large):
    """Over 100 s (ten times the calibrated horizon) 100 times tighter; never looser below
    it; the step budget grows with the length and the tightening."""
    tree, adams = seed_large[0], METHODS["cvodes-adams"]
    ten = tolerance.solver_tolerances(adams, tree, 1e-6, 1e-8, 10.0)
    assert tolerance.solver_tolerances(adams, tree, 1e-6, 1e-8, 1.0) == pytest.approx(ten)
    assert tolerance.solver_tolerances(adams, tree, 1e-6, 1e-8, 100.0) == \
        pytest.approx((ten[0] / 100, ten[1] / 100))
    assert tolerance.step_budget(adams, tree, 100.0) == \
        int(tolerance.RUN_STEPS * 10 * (tolerance.TIGHTEN["cvodes-adams", False] * 100) ** 0.2)
    assert tolerance.step_budget(METHODS["rk45"], tree, 1.0) == tolerance.RUN_STEPS


@pytest.mark.parametrize("rtol", [1e-4, 1e-7])
def test_error_estimate_within_a_factor_10_of_the_closed_form(seed_large, rtol):
    system, reference = seed_large
    res = kn.simulate(system, t_end=T_END, n_points=N_POINTS, rtol=rtol, atol=rtol / 100,
                      jit=False, error_estimate=True)
    estimate = res.stats["error_estimate"]
    assert estimate["valid_until"] is None
    for j, name in enumerate(["shoulder.q", "elbow.q"]):
        true = float(np.max(np.abs(res[name] - reference[:, j])))
        guess = estimate["signals"][name]["error"]
        assert true / 10 <= guess <= 10 * true, (name, guess, true)
    # probe signals get theirs too, in their own units
    assert estimate["signals"]["probe1.torque"]["error"] > 0


def test_error_estimate_says_when_chaos_makes_it_meaningless():
    """The undamped seed at large angles: errors grow tenfold every ~2.2 s. At rtol 1e-2 the
    run's angles part from the closed form's by the size of the motion within 6 s; the
    estimate must say so before then, and hold before it."""
    system = chains.chaotic().compile()
    res = kn.simulate(system, t_end=6.0, n_points=301, rtol=1e-2, atol=1e-4, jit=False,
                      error_estimate=True)
    estimate = res.stats["error_estimate"]
    until = estimate["valid_until"]
    assert until is not None and until < 6.0
    assert "means nothing after" in estimate["note"]
    reference = seed_reference(res.t, x0=(2.5, 2.0, 0.0, 0.0), rtol=1e-8, atol=1e-10,
                               d=0.0)[:, :2]
    true = np.abs(res.states[:, :2] - reference).max(axis=1)
    assert true.max() > 0.5                      # the answer is lost by the end ...
    before = res.t < until
    guess = max(estimate["signals"][n]["error"] for n in ("shoulder.q", "elbow.q"))
    assert true[before].max() < guess            # ... and the estimate bounds it before


def test_error_estimate_on_the_command_line(seed_file, capsys):
    from kinetwork.cli import main
    assert main(["run", str(seed_file), "--t-end", "1", "--no-jit", "--error-estimate"]) == 0
    out = capsys.readouterr().out
    assert "estimated global error" in out and "probe1.angle: " in out
    assert "the estimate holds over the whole run" in out


def test_error_estimate_of_the_default_loop_run(four_bar):
    """The four-bar under the default (projected ODE, Adams) at rtol 1e-8: the estimate of the
    crank angle within a factor 10 of its error against the sympy reference."""
    system, reference = four_bar
    res = kn.simulate(system, t_end=T_END, n_points=N_POINTS, rtol=1e-8, atol=1e-10,
                      jit=False, error_estimate=True)
    assert res.settings["method"] == "cvodes-adams"
    true = float(np.max(np.abs(res["A.q"] - reference[:, 0])))
    guess = res.stats["error_estimate"]["signals"]["A.q"]["error"]
    assert true / 10 <= guess <= 10 * true, (guess, true)


LONG = 100.0


@pytest.fixture(scope="module")
def long_four_bar():
    """The four-bar of models/fourbar.json over 100 s (its crank goes round: a conservative
    motion whose period depends on its energy), and its sympy-derived reference by DOP853 at
    3e-14."""
    t = np.linspace(0.0, LONG, 1001)
    return fourbar(probes=False).compile(), \
        rl.fourbar_simulate(1.0, 0.0, t, rtol=3e-14, atol=3e-14)["theta"][:, None]


@pytest.mark.parametrize("rtol", [1e-5, 1e-8])
def test_global_error_within_100_rtol_over_100_s(long_four_bar, rtol):
    """Issue 30 item 5: over 100 s the four-bar's error grows as the square of the horizon
    (tolerance.py); the map tightens by as much. Before it, 360 x and 555 x rtol."""
    system, reference = long_four_bar
    res = kn.simulate(system, t_end=LONG, n_points=1001, rtol=rtol, atol=rtol / 100)
    assert np.max(np.abs(res["A.q"] - reference[:, 0])) <= 100 * rtol
