"""The scenes the tests and the benchmarks share: builders of kinetwork models, and the
independent references they are checked against.

Builders (re-exported here: ``from scenes import double_pendulum, chain, fourbar``):

``pendulum``      the seed paper's double pendulum built through the API (``double_pendulum``,
                  ``SEED_PARAMS``)
``chains``        the scenes of the speed and accuracy studies: ``seed`` (from
                  ``models/double_pendulum.json``), ``chaotic``, ``stiff``, ``chain``,
                  ``spatial``, and their plain data (``chain_spec``...) for the peer libraries
``loops``         kinematic loops, free bodies, line forces (``fourbar``, ``slider_crank``...)
``drives``        drives, gears, sensors, feedback (``arm_pid``, ``drive_train``...)
``random_trees``  random spatial chains and trees (``random_mechanism``, ``build_kinetwork``)
``oscillator``    a mass on a spring without model parameters, alone and in a subsystem: the
                  scene of component parameters by path, with its closed form (imported by
                  module: ``from scenes.oscillator import oscillator``)

References (nothing of kinetwork in them; imported by module: ``from scenes import
reference``):

``reference``        the paper's closed-form M, V, G of the seed, integrated with DOP853
``reference_loops``  the four-bar and slider-crank, reduced to their crank angle with sympy

``python tests/scenes/loops.py`` and ``python tests/scenes/drives.py`` write the example files
in ``models/``. The benchmarks (``bench/``) put ``tests/`` on their path to import these.
"""

from .chains import chain, chaotic, seed, spatial, stiff
from .drives import arm_computed_torque, arm_pid, drive_train
from .loops import (dzhanibekov, fourbar, fourbar_chain, fourbar_guesses, slider_crank,
                    spatial_fourbar, spring_pendulum)
from .pendulum import SEED_PARAMS, double_pendulum
from .random_trees import build_kinetwork, random_mechanism, random_state

__all__ = ["SEED_PARAMS", "arm_computed_torque", "arm_pid", "build_kinetwork", "chain",
           "chaotic", "double_pendulum", "drive_train", "dzhanibekov", "fourbar",
           "fourbar_chain", "fourbar_guesses", "random_mechanism", "random_state", "seed",
           "slider_crank", "spatial", "spatial_fourbar", "spring_pendulum", "stiff"]
