"""``kinetwork equations MODEL.json``: the equations of motion M(q) qdd + V(q, qd) + G(q) = 0
in closed form, as text, 2-D pretty print or LaTeX (the seed paper's M, V, G)."""

import argparse
import sys

from .common import add_library, load_model


def add(sub):
    """The ``equations`` subcommand's parser; {name: handler}."""
    parser = sub.add_parser(
        "equations", help="print the mass matrix M and force vectors V, G",
        description="Print the equations of motion M(q) qdd + V(q, qd) + G(q) = 0 of "
                    "MODEL.json in closed form, in its joint coordinates and parameters.")
    parser.add_argument("model", metavar="MODEL.json", help="model file")
    parser.add_argument("--format", choices=["text", "pretty", "latex"], default="text",
                        help="plain expressions, 2-D pretty print, or LaTeX (default: text)")
    parser.add_argument("--simplify", action=argparse.BooleanOptionalAction,
                        help="simplify into the paper's form, or print the Newton-Euler "
                             "expressions as built, with shared parts named (default: simplify "
                             "when that takes seconds, not hours)")
    add_library(parser)
    return {"equations": equations}


def equations(args):
    import sympy as sp

    from ..symbolic import equations_sympy

    model = load_model(args.model, args.library)
    system = model.compile()
    eq = equations_sympy(system, simplified=args.simplify)     # ModelError for a Table's call
    mats = {key: eq[key] for key in ("M", "V", "G")}
    shared = eq["shared"]
    if not eq["simplified"] and args.simplify is None:
        print(f"kinetwork: note: M, V, G have {eq['size']} operations, too many to simplify "
              f"quickly: printed as built, shared parts named w0, w1, ... (--simplify "
              f"forces it)", file=sys.stderr)
    coords = ", ".join(f"{s} = {c}" for s, c in zip(eq["q"], system.coordinate_names))

    if args.format == "latex":
        names = {s: _latex_name(s.name, prefix) for prefix in ("q", "qd") for s in eq[prefix]}

        def show(expr):
            return sp.latex(expr, symbol_names=names, mat_str="bmatrix", mat_delim="",
                            full_prec=False)
        print(f"% {model.name}: M(q) \\ddot q + V(q, \\dot q) + G(q) = 0; {coords}")
        for key, expr in [*shared, *mats.items()]:
            print(f"{show(sp.Symbol(str(key)))} = {show(expr)}")
        return 0

    print(f"{model.name}: M(q)*qdd + V(q, qd) + G(q) = 0")
    print(f"coordinates: {coords}" if coords else "coordinates: none (no degrees of freedom)")
    print("speeds: " + (", ".join(str(s) for s in eq["qd"]) or "none"))
    print("parameters: " + (", ".join(eq["params"]) or "none"))
    if system.topology.cuts:
        print(f"loops: cut at {', '.join(c.component.name for c in system.topology.cuts)}; "
              f"M, V, G are those of the open tree, and the {system.eq.loop_rows} independent "
              f"closure equations phi(q) = 0 add J(q)^T lambda to the right-hand side")
    blocks = [[(str(w), expr) for w, expr in shared]] if shared else []
    comma = "," if len(eq["q"]) > 9 else ""       # M1011 would be ambiguous: M10,11
    for key, mat in mats.items():
        blocks.append([(f"{key}{i + 1}{comma}{j + 1}" if key == "M" else f"{key}{i + 1}",
                        mat[i, j]) for i in range(mat.rows) for j in range(mat.cols)])
    for block in blocks:
        print()
        for label, expr in block:
            if args.format == "pretty":
                print(sp.pretty(sp.Eq(sp.Symbol(_subscript(label)), expr, evaluate=False),
                                use_unicode=True, wrap_line=False, full_prec=False))
            else:
                print(f"{label} = {sp.sstr(expr, full_prec=False)}")
    return 0


def _subscript(label):
    """M12 -> M_12, so pretty printing sets the index as a subscript."""
    return label[0] + "_" + label[1:]


def _latex_name(name, prefix):
    """q_shoulder -> q_{\\mathrm{shoulder}}, qd_shoulder -> \\dot{q}_{\\mathrm{shoulder}}."""
    rest = name[len(prefix) + 1:].replace("_", r"\_")
    base = r"\dot{q}" if prefix == "qd" else "q"
    return f"{base}_{{\\mathrm{{{rest}}}}}"
