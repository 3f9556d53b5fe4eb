"""How the cost of sympy's Kane derivation grows with the number of links.

For planar chains (``chain_spec(N)``, all axes z) and spatial ones (``spatial_spec(N)``, skew
axes, full inertia tensors), prints per N the derivation time (in the spawned process), the
lambdify time (``cse=True``) and the whole ``build``, stopping a family at its first timeout.

    python bench/peers/sympy_growth.py [timeout_s] [max_N]
"""

import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

import common  # noqa: E402, F401  (puts tests/ on the path, for the scenes)
from scenes import chains as scenes  # noqa: E402
from peers import sympy_peer  # noqa: E402


def main(timeout=600.0, max_n=16):
    print(f"{'scene':10s} {'derive s':>9s} {'lambdify s':>10s} {'build s':>8s}")
    for family, make in (("chain", scenes.chain_spec), ("spatial", scenes.spatial_spec)):
        for n in range(2, max_n + 1):
            start = time.perf_counter()
            try:
                built = sympy_peer.build(make(n), timeout=timeout)
            except TimeoutError:
                print(f"{family}{n:<5d} {'> ' + str(int(timeout)):>9s}", flush=True)
                break
            print(f"{family}{n:<5d} {built.derive_s:9.2f} {built.lambdify_s:10.2f} "
                  f"{time.perf_counter() - start:8.2f}", flush=True)


if __name__ == "__main__":
    main(*(float(a) for a in sys.argv[1:2]), *(int(a) for a in sys.argv[2:3]))
