"""Blocks of a wiring diagram: their sizes and colours (Modelica's), the side each port sits
on, and the wiring read from a model. What the layout, the router and the drawing share."""

import math
import re

from ..components.base import ANY
from ..graph.subsystem import Subsystem


NAME_PX, TYPE_PX, LABEL_PX = 10.5, 8.0, 7.0      # font sizes
ROW = 11           # height of one row of side ports
MIN_W = 88         # narrowest block
PROBE_H = 20       # probes are drawn small
STUB = 10          # a wire leaves its port straight for this long
CLEAR = 10         # wires run this far from blocks
LAYER_GAP = 56     # between layers, before the room for wires
TRACK = 8          # room for each wire that crosses a gap between layers
NODE_GAP = 30      # between blocks of one layer
SAT_GAP = 24       # between a block and the parts stacked on it
ROOM = 32          # kept free around a group placed beside given positions
BEND = 20          # a bend in a wire costs as much as this much length
CROSS = 20         # and a crossing this much
ROUTED = 400       # more wires than this are drawn as plain elbows (routing is quadratic)

#: wire colour and width of each domain (Modelica's colours)
DOMAINS = {"frame": ("#5f5f5f", 2.0), "rotational": ("#404040", 1.3),
           "translational": ("#007f00", 1.3), "signal": ("#00007f", 1.0),
           "electrical": ("#0000ff", 1.2), ANY: ("#8c8c8c", 1.0)}
#: border and fill of a block, by library
LIBRARIES = {"multibody": ("#5f5f5f", "#f5f5f5"), "rotational": ("#404040", "#f7f7f7"),
             "translational": ("#007f00", "#f2f9f2"), "signals": ("#00007f", "#f3f3fb"),
             "probe": ("#a86b00", "#fff8e8"), "subsystem": ("#3a3a3a", "#fffdf2"),
             "electrical": ("#0000ff", "#f2f2ff")}
OUTWARD = {"left": (-1, 0), "right": (1, 0), "top": (0, -1), "bottom": (0, 1)}
_CLOCKWISE = ("left", "top", "right", "bottom")
_PRINCIPAL = re.compile(r"(?:frame|flange)_([ab])")


def text_width(text, size, bold=False):
    """An estimate of the width of ``text`` in a sans-serif font (no font is at hand)."""
    units = 0.0
    for ch in text:
        if ch in "ijlI.,:;'|!":
            units += 0.3
        elif ch in "frt()[]- ":
            units += 0.4
        elif ch in "mwMW":
            units += 0.9
        elif ch.isupper():
            units += 0.7
        else:
            units += 0.6
    return units * size * (1.08 if bold else 1.0)


def library_of(comp):
    """What a block is dressed as: its library, "probe" or "subsystem"."""
    if isinstance(comp, Subsystem):
        return "subsystem"
    library, dot, _ = (comp.type_name or "").partition(".")
    return library if dot and library in LIBRARIES else \
        "probe" if comp.role == "probe" else "multibody"


def port_domain(comp, port):
    domain = comp.ports[port].domain
    return "signal" if domain in ("signal_in", "signal_out") else domain


def _side(comp, port, depth=0):
    """The side of its block a port is drawn on, before a layout is known."""
    domain = comp.ports[port].domain
    if domain == "signal_in":
        return "left"
    if domain == "signal_out":
        return "right"
    if isinstance(comp, Subsystem):
        if port.endswith("_a"):
            return "left"
        if port.endswith("_b"):
            return "right"
        inner = comp.definition.exposed[port]
        side = _side(inner.component, inner.name, depth + 1) if depth < 16 else "top"
        return side if side in ("left", "right") else "top"
    if (found := _PRINCIPAL.fullmatch(port)):
        return "left" if found.group(1) == "a" else "right"
    if comp.role == "world":
        return "right"
    if comp.role == "probe":
        return "left"
    if port == "flange":
        return {"sensor": "left", "fixed": "top"}.get(comp.role, "right")
    if port.startswith("support") and comp.role != "joint":
        return "bottom"
    return "top"                       # a joint's axis and support, as in Modelica


def placed_side(side, rotation=0, flip=False):
    """The side a port on ``side`` is drawn on once its block is mirrored left to right
    (``flip``) and then turned ``rotation`` degrees clockwise, as the studio keeps them in a
    model's ``layout``: the left side of a block turned by 90 is its top."""
    if flip and side in ("left", "right"):
        side = "right" if side == "left" else "left"
    return _CLOCKWISE[(_CLOCKWISE.index(side) + round(rotation / 90)) % 4]


def placement(model, name):
    """``(rotation, flip)`` of a component's block, from the model's layout: a quarter turn
    in degrees (0, 90, 180 or 270; another angle counts as the nearest quarter) and whether
    it is mirrored."""
    spot = (model.layout or {}).get(name)
    if not isinstance(spot, dict):
        return 0, False
    turn = spot.get("rotation", 0)
    ok = isinstance(turn, (int, float)) and not isinstance(turn, bool) and math.isfinite(turn)
    return (round(turn / 90) % 4) * 90 if ok else 0, spot.get("flip") is True


class Block:
    """A component's block: its size, and where each of its ports sits on its sides.

    Inside, from the top: the name, the side ports' labels (a glyph between them), the
    type. Ports on the top and bottom have their labels outside, so that the side ports of
    all blocks are at one height and wires between blocks placed in a row run straight."""

    def __init__(self, comp, rotation=0, flip=False):
        self.comp, self.name = comp, comp.name
        self.probe = comp.role == "probe" and not isinstance(comp, Subsystem)
        self.single = len(comp.ports) == 1 and not isinstance(comp, Subsystem)
        #: turned or mirrored by the user: its ports stay on the sides that gives them
        self.rotation, self.flip = rotation, flip
        self.turned = bool(rotation) or flip
        self.sides = {p: placed_side(_side(comp, p), rotation, flip) for p in comp.ports}
        self.kind = comp.definition.name if isinstance(comp, Subsystem) else \
            (comp.type_name or type(comp).__name__).rpartition(".")[2]
        if self.probe:
            self.w = max(48, math.ceil(text_width(comp.name, 9) + 28))
            self.h, self.rows = PROBE_H, 1
        else:
            count = {s: [p for p in comp.ports if self.sides[p] == s] for s in OUTWARD}
            self.rows = max(len(count["left"]), len(count["right"]), 1)

            def label(ports):
                return max((text_width(p, LABEL_PX) for p in ports), default=0)
            # ports on the top and bottom (all on one side in the worst case) have their
            # labels outside, beside them: outwards when there are two
            ends = len(count["top"]) + len(count["bottom"])
            ends_w = max(label(count["top"]), label(count["bottom"])) if ends > 2 else 10
            self.w = 2 * math.ceil(max(MIN_W, text_width(comp.name, NAME_PX, True) + 18,
                                       text_width(self.kind, TYPE_PX) + 14,
                                       label(count["left"]) + label(count["right"]) + 34,
                                       (ends + 1) * (ends_w + 10)) / 2)
            # room under the type for the markers of ports on the bottom
            self.h = 17 + self.rows * ROW + 14 + (4 if ends else 0)
        self.arrange()

    def arrange(self):
        """Spread the ports evenly along their sides (again after sides change)."""
        self.at = {}
        for side in OUTWARD:
            ports = [p for p in self.comp.ports if self.sides[p] == side]
            if side in ("top", "bottom"):      # a support left of its axis, as in Modelica
                ports.sort(key=lambda p: not p.startswith("support"))
            for i, port in enumerate(ports):
                if side in ("left", "right"):
                    top, span = (0, self.h) if self.probe else (17, self.rows * ROW)
                    y = top + (i + 0.5) * span / len(ports)
                    self.at[port] = (0 if side == "left" else self.w, round(y, 1))
                else:
                    x = self.w * (i + 1) / (len(ports) + 1)
                    self.at[port] = (round(x, 1), 0 if side == "top" else self.h)

    def flow(self, port):
        """+1 for a port the flow leaves by (right), -1 for one it enters by (left)."""
        return {"right": 1, "left": -1}.get(self.sides[port], 0)


def connections_of(model):
    """The connections as (component, port, component, port) names."""
    return [(a.component.name, a.name, b.component.name, b.name) for a, b in model.connections]


def given_positions(model):
    """The positions a model's layout gives: name -> (x, y), as written."""
    out = {}
    for name, spot in (model.layout or {}).items():
        if name in model.components and isinstance(spot, dict):
            x, y = spot.get("x"), spot.get("y")
            if all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                   for v in (x, y)):
                out[name] = (x, y)
    return out
