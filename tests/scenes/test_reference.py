"""The seed reference's float right-hand side is ``seed_mvg``'s equations: at random states
and parameters the two give the same accelerations (the float one exists for speed only)."""

import numpy as np

from scenes.reference import PAPER, _seed_rhs, seed_mvg


def test_the_float_right_hand_side_is_the_closed_form():
    rng = np.random.default_rng(7)
    for _ in range(50):
        p = {k: v * rng.uniform(0.5, 2.0) for k, v in PAPER.items()}
        x = rng.uniform(-3, 3, 4)
        M, V, G = seed_mvg(x[:2], x[2:], **p)
        expected = np.concatenate([x[2:], np.linalg.solve(M, -(V + G))])
        np.testing.assert_allclose(_seed_rhs(**p)(0.0, x), expected, rtol=1e-12, atol=1e-12)
