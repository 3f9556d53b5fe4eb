"""An inertia tensor's physical sense, checked when a model is validated."""

import warnings

import numpy as np

from ..errors import IdealisedInertiaWarning, Problem


def check_inertias(model, bodies, values, problems, notes):
    """A body's inertia about its centre of mass must be symmetric and positive
    semi-definite: nothing else is possible for any use. Principal moments that break the
    triangle inequality (no rigid body has them) are an idealisation MSL's own examples use
    for parts that turn about one axis only (ActuatedDrive's diag(2, 0, 0), RobotR3's
    diag(0.001, 1.16, 0.001)): warned once per body, and simulated; a mass matrix they make
    singular is refused later, naming the joints. A tensor with a zero principal moment (a
    planar link given only its moment about the joint axis) is an idealisation too common to
    warn about."""
    for body in bodies:
        if "inertia" not in body.params:
            continue        # computed from a shape: physical by construction
        inertia = np.asarray(values[body.name]["inertia"], dtype=float)
        where, at = model.place(body, "inertia"), model.fields(body, "inertia")
        scale = max(np.max(np.abs(inertia)), 1e-300)
        if np.max(np.abs(inertia - inertia.T)) > 1e-9 * scale:
            problems.append(Problem(f"{where}: must be symmetric, got {inertia.tolist()}",
                                    **at))
            continue
        moments = np.linalg.eigvalsh(inertia)
        listed = ", ".join(f"{m:.6g}" for m in moments)
        if moments[0] < -1e-9 * scale:
            problems.append(Problem(f"{where}: must be positive semi-definite; its principal "
                                    f"moments are {listed}", **at))
        elif moments[0] > 1e-12 * scale and moments[0] + moments[1] < moments[2] - 1e-9 * scale:
            note = IdealisedInertiaWarning(
                f"{where}: its principal moments {listed} break the triangle inequality (the "
                f"largest exceeds the sum of the other two): no rigid body has them; "
                f"simulated as an idealisation", **at)
            notes.append(note.problem)
            warnings.warn(note, stacklevel=2)
