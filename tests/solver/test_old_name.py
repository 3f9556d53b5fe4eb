"""``kinetwork.simulation``, the solver's name before, still works for a release: its modules
are the ``kinetwork.solver`` modules themselves, reached with one deprecation warning that is a
``KinetworkWarning`` like every other. Run in a fresh interpreter: pytest's own imports could
have loaded the alias already, and a warning is given once per process."""

import os
import subprocess
import sys

PROGRAM = """
import warnings
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    import kinetwork.simulation.driver as old_driver
    from kinetwork.simulation import results as old_results
    from kinetwork.simulation.methods import METHODS as old_methods
import kinetwork as kn
import kinetwork.solver.driver, kinetwork.solver.results, kinetwork.solver.methods
assert old_driver is kinetwork.solver.driver
assert old_results is kinetwork.solver.results
assert old_methods is kinetwork.solver.methods.METHODS
ours = [w for w in caught if issubclass(w.category, kn.KinetworkWarning)]
assert len(ours) == 1, [str(w.message) for w in caught]
w = ours[0]
assert issubclass(w.category, DeprecationWarning)
assert str(w.message) == ("kinetwork.simulation is now kinetwork.solver; the old name goes in "
                          "the next release")
assert w.message.problem.severity == "warning"
assert w.message.problem.hint == "import kinetwork.solver instead"
print("ok")
"""


def test_the_old_name_is_the_solver_with_one_deprecation_warning(tmp_path):
    done = subprocess.run([sys.executable, "-c", PROGRAM], capture_output=True, text=True,
                          cwd=tmp_path, env=dict(os.environ, MPLBACKEND="Agg"))
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr[-3000:]
