"""Wiring diagrams: a port-aware layered layout of a model and its drawing as SVG.

``auto_layout(model)`` places the components a model's ``layout`` does not: the idea of ELK's
layered algorithm (Sugiyama's method) with ports on fixed sides. The flow runs left to right:
a wire from a port on a block's right side (``frame_b``, ``flange_b``, an output) to one on
another's left side (``frame_a``, ``flange_a``, an input) puts the second block one layer
further. Parts hanging only on a block's top or bottom ports (the spring-damper on a joint's
support and axis, a probe on an axis) stand above or below it in its layer, as in Modelica
diagrams. Cycles are broken where a depth-first walk from the model's inputs closes them (a
controller's measured feedback runs back), layers are given by the longest path, long wires
get placeholders in the layers they cross, the order within layers comes from barycentre
sweeps on the ports' heights and then swaps of neighbours, and the heights from an isotonic
fit that keeps that order while straightening wires. Components a layout places stay put;
the others are laid out by connected groups around them, each moved to the nearest free
room.

``svg(model)`` draws the blocks, their ports in Modelica's colours, and wires routed
orthogonally around the blocks (a shortest path with a price on bends, crossings and
overlaps on a grid of lines beside the blocks), then spread apart where they share a track.
Importing this module gives ``Model`` a ``_repr_svg_``: a model shows as its diagram in
Jupyter.
"""

import bisect
import heapq
import itertools
import math
import os
import re
from xml.sax.saxutils import escape, quoteattr

import networkx as nx

from .components.base import ANY
from .errors import ModelError
from .graph.model import Model
from .graph.subsystem import Subsystem
from .outputs import check, model_files, write

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
_OUT = {"left": (-1, 0), "right": (1, 0), "top": (0, -1), "bottom": (0, 1)}
_PRINCIPAL = re.compile(r"(?:frame|flange)_([ab])")


# -- blocks ------------------------------------------------------------------------------
def _text_width(text, size, bold=False):
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


def _library(comp):
    """What a block is dressed as: its library, "probe" or "subsystem"."""
    if isinstance(comp, Subsystem):
        return "subsystem"
    library, dot, _ = (comp.type_name or "").partition(".")
    return library if dot and library in LIBRARIES else \
        "probe" if comp.role == "probe" else "multibody"


def _domain(comp, port):
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


class _Box:
    """A component's block: its size, and where each of its ports sits on its sides.

    Inside, from the top: the name, the side ports' labels (a glyph between them), the
    type. Ports on the top and bottom have their labels outside, so that the side ports of
    all blocks are at one height and wires between blocks placed in a row run straight."""

    def __init__(self, comp):
        self.comp, self.name = comp, comp.name
        self.probe = comp.role == "probe" and not isinstance(comp, Subsystem)
        self.single = len(comp.ports) == 1 and not isinstance(comp, Subsystem)
        self.sides = {p: _side(comp, p) for p in comp.ports}
        self.kind = comp.definition.name if isinstance(comp, Subsystem) else \
            (comp.type_name or type(comp).__name__).rpartition(".")[2]
        if self.probe:
            self.w = max(48, math.ceil(_text_width(comp.name, 9) + 28))
            self.h, self.rows = PROBE_H, 1
        else:
            count = {s: [p for p in comp.ports if self.sides[p] == s] for s in _OUT}
            self.rows = max(len(count["left"]), len(count["right"]), 1)

            def label(ports):
                return max((_text_width(p, LABEL_PX) for p in ports), default=0)
            # ports on the top and bottom (all on one side in the worst case) have their
            # labels outside, beside them: outwards when there are two
            ends = len(count["top"]) + len(count["bottom"])
            ends_w = max(label(count["top"]), label(count["bottom"])) if ends > 2 else 10
            self.w = 2 * math.ceil(max(MIN_W, _text_width(comp.name, NAME_PX, True) + 18,
                                       _text_width(self.kind, TYPE_PX) + 14,
                                       label(count["left"]) + label(count["right"]) + 34,
                                       (ends + 1) * (ends_w + 10)) / 2)
            # room under the type for the markers of ports on the bottom
            self.h = 17 + self.rows * ROW + 14 + (4 if ends else 0)
        self.arrange()

    def arrange(self):
        """Spread the ports evenly along their sides (again after sides change)."""
        self.at = {}
        for side in _OUT:
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


def _links(model):
    """The connections as (component, port, component, port) names."""
    return [(a.component.name, a.name, b.component.name, b.name) for a, b in model.connections]


def _given(model):
    """The positions a model's layout gives: name -> (x, y), as written."""
    out = {}
    for name, spot in (model.layout or {}).items():
        if name in model.components and isinstance(spot, dict):
            x, y = spot.get("x"), spot.get("y")
            if all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                   for v in (x, y)):
                out[name] = (x, y)
    return out


# -- the layered layout ------------------------------------------------------------------
def auto_layout(model):
    """Where each component's block goes: ``{name: {"x", "y", "w", "h"}}``.

    ``x``, ``y`` are the block's top left corner (y downwards), ``w``, ``h`` its size, in
    the units of the model's ``layout``. A component the layout places keeps its position;
    the others are placed by a port-aware layered layout (see the module's docstring).
    The same model always gets the same layout.
    """
    boxes = {name: _Box(comp) for name, comp in model.components.items()}
    spots = _place(model, boxes)
    return {name: {"x": spots[name][0], "y": spots[name][1], "w": boxes[name].w,
                   "h": boxes[name].h} for name in model.components}


def _place(model, boxes):
    """Positions of every block: the given ones, and groups of the others around them."""
    spots = _given(model)
    order = {name: i for i, name in enumerate(model.components)}
    links = [link for link in _links(model) if link[0] != link[2]]
    free = [name for name in model.components if name not in spots]
    if not free:
        return spots
    graph = nx.Graph()
    graph.add_nodes_from(free)
    graph.add_edges_from((a, b) for a, _, b, _ in links if a not in spots and b not in spots)
    groups = sorted((sorted(c, key=order.get) for c in nx.connected_components(graph)),
                    key=lambda c: order[c[0]])
    loose = []
    for group in groups:
        members = set(group)
        anchors = {}
        for a, _, b, _ in links:
            for inside, outside in ((a, b), (b, a)):
                if inside in members and outside in spots:
                    anchors[outside] = anchors.get(outside, 0) + 1
        if len(group) == 1 and not anchors:
            loose.append(group[0])
            continue
        names = group + sorted(anchors, key=order.get)
        rel = _layered(names, boxes, [k for k in links if k[0] in names and k[2] in names],
                       fixed=set(anchors), order=order)
        if anchors:
            main = min(anchors, key=lambda n: (-anchors[n], order[n]))
            shift = (spots[main][0] - rel[main][0], spots[main][1] - rel[main][1])
        else:
            shift = _below(spots, boxes, rel, group)
        rects = [(rel[n][0], rel[n][1], boxes[n].w, boxes[n].h) for n in group]
        placed = [(x, y, boxes[n].w, boxes[n].h) for n, (x, y) in spots.items()]
        dx, dy = _free_room(rects, (round(shift[0]), round(shift[1])), placed)
        for name in group:
            spots[name] = (round(rel[name][0] + dx, 1), round(rel[name][1] + dy, 1))
    if loose:
        _row(loose, spots, boxes)
    return spots


def _bounds(spots, boxes):
    xs = [x for x, _ in spots.values()]
    return (min(xs), min(y for _, y in spots.values()),
            max(x + boxes[n].w for n, (x, _) in spots.items()),
            max(y + boxes[n].h for n, (_, y) in spots.items()))


def _below(spots, boxes, rel, group):
    """The shift that puts a group with no placed neighbour below what is placed."""
    left = min(rel[n][0] for n in group)
    top = min(rel[n][1] for n in group)
    if not spots:
        return -left, -top
    x0, _, _, y1 = _bounds(spots, boxes)
    return x0 - left, y1 + 2 * ROOM - top


def _free_room(rects, shift, placed):
    """The shift nearest to ``shift`` at which no rectangle comes within ROOM of a placed
    one: tried on a grid, nearest first (up and down a little before sideways)."""
    def clear(dx, dy):
        return not any(x + dx < px + pw + ROOM and px < x + dx + w + ROOM and
                       y + dy < py + ph + ROOM and py < y + dy + h + ROOM
                       for x, y, w, h in rects for px, py, pw, ph in placed)
    step = 20
    for radius in range(0, 400):
        ring = [(i, j) for i in range(-radius, radius + 1) for j in range(-radius, radius + 1)
                if max(abs(i), abs(j)) == radius]
        ring.sort(key=lambda ij: (math.hypot(1.3 * ij[0], ij[1]), ij[1], ij[0]))
        for i, j in ring:
            if clear(shift[0] + i * step, shift[1] + j * step):
                return shift[0] + i * step, shift[1] + j * step
    return shift


def _row(names, spots, boxes):
    """Unconnected blocks, in rows below the rest."""
    if spots:
        x0, _, x1, y1 = _bounds(spots, boxes)
        top, width = y1 + 2 * ROOM, max(x1 - x0, 640)
    else:
        x0, top, width = 0, 0, 640
    x, tallest = x0, 0
    for name in names:
        box = boxes[name]
        if x > x0 and x + box.w > x0 + width:
            x, top, tallest = x0, top + tallest + NODE_GAP, 0
        spots[name] = (x, top)
        x += box.w + NODE_GAP
        tallest = max(tallest, box.h)


def _satellites(names, boxes, links, fixed):
    """Parts wired only to the top or bottom ports of one other block: name -> (anchor,
    "top" or "bottom")."""
    found, meets = {}, {}
    for a, pa, b, pb in links:
        meets.setdefault(a, []).append((b, pb))
        meets.setdefault(b, []).append((a, pa))
    for name in names:
        if name in fixed or isinstance(boxes[name].comp, Subsystem):
            continue
        ends = meets.get(name, [])
        others = {other for other, _ in ends}
        if len(others) == 1:
            anchor = ends[0][0]
            sides = [boxes[anchor].sides[port] for _, port in ends]
            if all(s in ("top", "bottom") for s in sides):
                found[name] = (anchor, sides[0])
    return {n: v for n, v in found.items() if v[0] not in found}


def _layered(names, boxes, links, fixed, order):
    """Top left corners of ``names`` relative to one another, by the layered method."""
    sats = _satellites(names, boxes, links, fixed)
    units = [n for n in names if n not in sats]
    # a unit is a block with the parts stacked above and below it
    stack, size, hung = {}, {}, {}
    for n, anchor_side in sats.items():
        hung.setdefault(anchor_side, []).append(n)
    for unit in units:
        above, below = hung.get((unit, "top"), []), hung.get((unit, "bottom"), [])
        width = max(boxes[n].w for n in [unit, *above, *below])
        y, place = 0, {}
        for n in [*above, unit, *below]:
            place[n] = ((width - boxes[n].w) / 2, y)
            y += boxes[n].h + SAT_GAP
        stack[unit], size[unit] = place, (width, y - SAT_GAP)
    owner = {n: sats[n][0] if n in sats else n for n in names}

    # the wires between units, each with the heights of its ends in their units
    wires = []
    for a, pa, b, pb in links:
        ua, ub = owner[a], owner[b]
        if ua == ub:
            continue
        fa, fb = boxes[a].flow(pa), boxes[b].flow(pb)
        if boxes[a].single:            # a part with one port turns it to what it meets
            fa = -fb
        if boxes[b].single:
            fb = -fa
        ya = stack[ua][a][1] + boxes[a].at[pa][1]
        yb = stack[ub][b][1] + boxes[b].at[pb][1]
        signal = boxes[a].comp.ports[pa].domain in ("signal_in", "signal_out")
        wires.append((ua, ya, ub, yb, fa - fb, signal))

    dag = _direct(units, wires, order)
    layer = {}
    topo = list(nx.lexicographical_topological_sort(dag, key=order.get))
    for unit in topo:
        layer[unit] = max((layer[p] + 1 for p in dag.predecessors(unit)), default=0)
    for unit in reversed(topo):        # sources move up to just before what they feed
        succ = [layer[s] for s in dag.successors(unit)]
        if succ and not any(True for _ in dag.predecessors(unit)):
            layer[unit] = min(succ) - 1

    # placeholders where a wire passes a layer, so that nothing is put in its way
    height, edges = dict(size), []        # edges: (node, y, node, y), layer to layer + 1
    for k, (ua, ya, ub, yb, _, _) in enumerate(wires):
        if layer[ua] > layer[ub]:
            ua, ya, ub, yb = ub, yb, ua, ya
        chain, ys = [ua], [ya]
        for i in range(layer[ua] + 1, layer[ub]):
            dummy = ("~", k, i)
            layer[dummy], height[dummy] = i, (0, TRACK)
            chain.append(dummy)
            ys.append(TRACK / 2)
        chain.append(ub)
        ys.append(yb)
        if layer[ua] != layer[ub]:
            edges += [(chain[i], ys[i], chain[i + 1], ys[i + 1]) for i in range(len(chain) - 1)]
    count = max(layer.values()) + 1
    rank = {n: order.get(n, order.get(wires[n[1]][0]) if isinstance(n, tuple) else 0)
            for n in layer}
    layers = [[] for _ in range(count)]
    for n in layer:
        layers[layer[n]].append(n)
    for members in layers:
        members.sort(key=lambda n: (rank[n], str(n)))

    layers, near, between = _order(layers, edges, layer, height)

    # x: one column per layer, wider gaps where more wires cross
    xs, x = [], 0.0
    for i in range(count):
        xs.append(x)
        through = len(between[i])
        x += max(height[n][0] for n in layers[i]) + LAYER_GAP + TRACK * min(through, 14)

    top = _heights(layers, near, height)
    out = {}
    for unit in units:
        i = layer[unit]
        width = max(height[n][0] for n in layers[i])
        ux = xs[i] + (width - size[unit][0]) / 2
        for n, (dx, dy) in stack[unit].items():
            out[n] = (ux + dx, top[unit] + dy)
    return out


def _direct(units, wires, order):
    """The wires between units as a DAG: each from the flow's side to the other; cycles
    broken by a depth-first walk from the sources (a model's inputs: a reference signal,
    the ground), turning back the edges that close them (a measured feedback runs back)."""
    flows = {}
    for ua, _, ub, _, score, signal in wires:
        # mechanics first, then signals, then wires between like sides (frame_b to frame_b)
        u, v = (ub, ua) if score < 0 else (ua, ub)
        strength = (0 if not score else 1 if signal else 2, abs(score))
        if strength > flows.get((v, u), (-1, 0)):
            flows.pop((v, u), None)
            flows[(u, v)] = max(strength, flows.get((u, v), strength))
    after = {u: [] for u in units}
    for u, v in flows:
        after[u].append(v)
    for u in after:
        after[u].sort(key=lambda v: (-flows[(u, v)][0], order[v]))
    feeds = {v for (_, v), (rank, _) in flows.items() if rank}
    dag = nx.DiGraph()
    dag.add_nodes_from(units)
    state = {}                        # 1 while on the walk's path, 2 when done
    for root in [u for u in units if u not in feeds] + units:
        if root in state:
            continue
        state[root], path = 1, [(root, iter(after[root]))]
        while path:
            node, todo = path[-1]
            nxt = next(todo, None)
            if nxt is None:
                state[node] = 2
                path.pop()
            elif state.get(nxt) == 1:
                dag.add_edge(nxt, node)          # closes a cycle: turned back
            else:
                dag.add_edge(node, nxt)
                if nxt not in state:
                    state[nxt] = 1
                    path.append((nxt, iter(after[nxt])))
    return dag


def _order(layers, edges, layer, height):
    """The order within layers: barycentre sweeps on the ports' heights, keeping the order
    with the fewest crossings, then swaps of neighbours while they remove crossings.
    Returns the layers, each node's (left, right) neighbours and the edges by layer."""
    count = len(layers)
    near = {n: ([], []) for n in layer}               # (left neighbours, right neighbours)
    for a, ya, b, yb in edges:
        near[b][0].append((a, ya, yb))
        near[a][1].append((b, yb, ya))

    def position(n, y):
        return pos[n] + y / max(height[n][1], 1)

    between = [[] for _ in range(count)]
    for e in edges:
        between[layer[e[0]]].append(e)

    def crossings(gaps=None):
        total = 0
        for i in (range(count - 1) if gaps is None else gaps):
            ends = [(position(a, ya), position(b, yb)) for a, ya, b, yb in between[i]]
            total += sum(1 for (p, q), (r, s) in itertools.combinations(ends, 2)
                         if (p - r) * (q - s) < 0)
        return total

    pos = {n: i for members in layers for i, n in enumerate(members)}
    best = (crossings(), [list(m) for m in layers])
    for sweep in range(16):
        forward = sweep % 2 == 0
        for i in (range(1, count) if forward else range(count - 2, -1, -1)):
            side = 0 if forward else 1

            def key(n):
                others = near[n][side]
                if not others:
                    return pos[n], pos[n]
                return sum(position(m, ym) for m, ym, _ in others) / len(others), pos[n]
            layers[i].sort(key=key)
            pos.update({n: j for j, n in enumerate(layers[i])})
        score = crossings()
        if score < best[0]:
            best = (score, [list(m) for m in layers])
    layers = best[1]
    pos = {n: i for members in layers for i, n in enumerate(members)}
    # then neighbours in a layer trade places while that removes crossings
    improved = len(edges) <= 300
    while improved:
        improved = False
        for i, members in enumerate(layers):
            near_gaps = [g for g in (i - 1, i) if 0 <= g < count - 1]
            for j in range(len(members) - 1):
                before = crossings(near_gaps)
                members[j], members[j + 1] = members[j + 1], members[j]
                pos[members[j]], pos[members[j + 1]] = j, j + 1
                if crossings(near_gaps) < before:
                    improved = True
                else:
                    members[j], members[j + 1] = members[j + 1], members[j]
                    pos[members[j]], pos[members[j + 1]] = j, j + 1
    return layers, near, between


def _heights(layers, near, height):
    """The top of each node: stacked in its layer's order, then moved to straighten wires
    with the order kept (an isotonic fit, layer by layer, sweeping both ways), and last
    nearly straight wires made straight."""
    count = len(layers)
    top = {}
    for members in layers:
        y = 0.0
        for n in members:
            top[n] = y
            y += height[n][1] + NODE_GAP
    for sweep in range(40):
        for i in (range(count) if sweep % 2 == 0 else range(count - 1, -1, -1)):
            members = layers[i]
            want, weight = [], []
            for n in members:
                # long wires pull hardest, then blocks in a chain (wired on both sides),
                # then dead ends (a body, a probe)
                through = 3.0 if near[n][0] and near[n][1] else 1.0
                pulls = [(top[m] + ym - yn, 4.0 if isinstance(m, tuple) or isinstance(n, tuple)
                          else through) for side in near[n] for m, ym, yn in side]
                total = sum(w for _, w in pulls)
                if total:
                    want.append(sum(y * w for y, w in pulls) / total)
                    weight.append(total)
                else:
                    want.append(top[n])
                    weight.append(0.05)
            for n, y in zip(members, _ordered_fit(want, weight,
                                                  [height[n][1] for n in members],
                                                  _gaps(members))):
                top[n] = y
    # last, a wire that is nearly straight is made straight (blocks in chains first),
    # moving its neighbours in the layer aside if they are not straightened already
    for members in layers:
        gaps, locked = _gaps(members), set()
        for j in sorted(range(len(members)),
                        key=lambda j: (not (near[members[j]][0] and near[members[j]][1]), j)):
            n = members[j]
            for m, ym, yn in near[n][0]:
                target = top[m] + ym - yn
                if abs(target - top[n]) >= 16:
                    continue
                new, ok = {n: target}, True
                for k in range(j - 1, -1, -1):
                    limit = new[members[k + 1]] - height[members[k]][1] - gaps[k]
                    if top[members[k]] <= limit:
                        break
                    ok &= members[k] not in locked
                    new[members[k]] = limit
                for k in range(j + 1, len(members)):
                    limit = new[members[k - 1]] + height[members[k - 1]][1] + gaps[k - 1]
                    if top[members[k]] >= limit:
                        break
                    ok &= members[k] not in locked
                    new[members[k]] = limit
                if ok:
                    top.update(new)
                    locked.add(n)
                    break
    return top


def _gaps(members):
    """The room between neighbours in a layer: less beside a wire's placeholder."""
    return [NODE_GAP if not (isinstance(a, tuple) or isinstance(b, tuple)) else 10
            for a, b in zip(members, members[1:])]


def _ordered_fit(want, weight, heights, gaps):
    """Tops as near ``want`` as weighted least squares allows, each block below the one
    before it with its gap (isotonic regression by pooling adjacent violators)."""
    offset, acc = [], 0.0
    for i, h in enumerate(heights):
        offset.append(acc)
        acc += h + (gaps[i] if i < len(gaps) else 0)
    pools = []                                     # [weight, weighted sum, count]
    for target, w in zip((y - o for y, o in zip(want, offset)), weight):
        pools.append([w, w * target, 1])
        while len(pools) > 1 and pools[-2][1] / pools[-2][0] > pools[-1][1] / pools[-1][0]:
            w2, s2, c2 = pools.pop()
            pools[-1][0] += w2
            pools[-1][1] += s2
            pools[-1][2] += c2
    fitted = [s / w for w, s, c in pools for _ in range(c)]
    return [z + o for z, o in zip(fitted, offset)]


# -- wires -------------------------------------------------------------------------------
class _Router:
    """Orthogonal wires around the blocks: shortest paths on the grid of lines CLEAR beside
    every block's sides (and the middles between), with a price on bends, on crossing other
    wires and on running along them (none along a wire of the same net: they merge)."""

    def __init__(self, rects, stubs=()):
        self.blocks = [(x - 3, y - 3, x + w + 3, y + h + 3) for x, y, w, h in rects]
        self.xs = self._lines([x for bx, _, bw, _ in rects for x in (bx - CLEAR, bx + bw + CLEAR)],
                              [x for x, _ in stubs])
        self.ys = self._lines([y for _, by, _, bh in rects for y in (by - CLEAR, by + bh + CLEAR)],
                              [y for _, y in stubs])
        self.runs = ({}, {})          # (along y: [(x0, x1, net)], along x: [(y0, y1, net)])
        self._sorted = ([], [])       # the lines of runs[0] and runs[1], sorted
        self.cut = ({}, {})

    @staticmethod
    def _lines(values, stubs):
        """Grid lines: through every port's stub, beside every block unless a stub's line
        is within a few units (one track, so that wires of a net can merge on it), and
        down the middle of wide gaps."""
        lines = sorted(set(stubs))
        for v in sorted(set(values)):
            i = bisect.bisect_left(lines, v)
            if all(abs(v - lines[k]) >= 5 for k in (i - 1, i) if 0 <= k < len(lines)):
                lines.insert(i, v)
        middles = [(a + b) / 2 for a, b in zip(lines, lines[1:]) if b - a > 2 * CLEAR]
        return sorted(set(lines + middles))

    def _spans(self, axis, value):
        """The open intervals blocks cover along the line ``axis`` = ``value`` (axis 0: a
        horizontal line at y = value; 1: a vertical one at x = value)."""
        cache = self.cut[axis]
        if value not in cache:
            cache[value] = [(b[0], b[2]) if axis == 0 else (b[1], b[3]) for b in self.blocks
                            if (b[1] < value < b[3] if axis == 0 else b[0] < value < b[2])]
        return cache[value]

    def route(self, a, da, b, db, net):
        """Points of a wire from port ``a`` (leaving in direction ``da``) to port ``b``."""
        sa = (a[0] + da[0] * STUB, a[1] + da[1] * STUB)
        sb = (b[0] + db[0] * STUB, b[1] + db[1] * STUB)
        xs = sorted(set(self.xs) | {sa[0], sb[0]})
        ys = sorted(set(self.ys) | {sa[1], sb[1]})
        start = (xs.index(sa[0]), ys.index(sa[1]), 0 if da[1] == 0 else 1)
        goal, goal_o = (xs.index(sb[0]), ys.index(sb[1])), 0 if db[1] == 0 else 1
        found = self._search(xs, ys, start, goal, goal_o, net)
        if found is None:              # no way around (blocks overlap): a plain elbow
            middle = [(sb[0], sa[1])] if da[1] == 0 else [(sa[0], sb[1])]
            points = [a, sa, *middle, sb, b]
        else:
            points = [a, *found, b]
        points = _simplify(points)
        self._remember(points, net)
        return points

    def _search(self, xs, ys, start, goal, goal_o, net):
        gx, gy = xs[goal[0]], ys[goal[1]]
        heap = [(0.0, 0.0, start)]
        best, back = {start: 0.0}, {}
        while heap:
            _, cost, state = heapq.heappop(heap)
            if cost > best.get(state, math.inf):
                continue
            ix, iy, o = state
            if (ix, iy) == goal:
                path = [(xs[ix], ys[iy])]
                while state in back:
                    state = back[state]
                    path.append((xs[state[0]], ys[state[1]]))
                return path[::-1]
            for jx, jy in ((ix - 1, iy), (ix + 1, iy), (ix, iy - 1), (ix, iy + 1)):
                if not (0 <= jx < len(xs) and 0 <= jy < len(ys)):
                    continue
                step = self._step(xs[ix], ys[iy], xs[jx], ys[jy], net)
                if step is None:
                    continue
                turn = 0 if jy == iy else 1
                extra = step + (BEND if turn != o else 0)
                if (jx, jy) == goal and turn != goal_o:
                    extra += BEND
                nxt = (jx, jy, turn)
                total = cost + extra
                if total < best.get(nxt, math.inf):
                    best[nxt], back[nxt] = total, state
                    guess = abs(xs[jx] - gx) + abs(ys[jy] - gy)
                    heapq.heappush(heap, (total + guess, total, nxt))
        return None

    def _step(self, x0, y0, x1, y1, net):
        """The price of the segment between two neighbouring grid points, None if a block
        is in the way."""
        axis = 0 if y0 == y1 else 1
        line, lo, hi = (y0, min(x0, x1), max(x0, x1)) if axis == 0 else \
            (x0, min(y0, y1), max(y0, y1))
        for s0, s1 in self._spans(axis, line):
            if s0 < hi and s1 > lo:
                return None
        length = hi - lo
        price = length
        for r0, r1, other in self.runs[axis].get(line, ()):
            shared = min(hi, r1) - max(lo, r0)
            if shared > 0:
                price += (-0.8 if other == net else 3.0) * shared
        crossing = self.runs[1 - axis]
        keys = self._sorted[1 - axis]
        for k in keys[bisect.bisect_right(keys, lo):bisect.bisect_left(keys, hi)]:
            if any(r0 < line < r1 and other != net for r0, r1, other in crossing[k]):
                price += CROSS
        return max(price, 0.05 * length)

    def _remember(self, points, net):
        for (x0, y0), (x1, y1) in zip(points, points[1:]):
            if y0 == y1:
                self.runs[0].setdefault(y0, []).append((min(x0, x1), max(x0, x1), net))
            else:
                self.runs[1].setdefault(x0, []).append((min(y0, y1), max(y0, y1), net))
        self._sorted = (sorted(self.runs[0]), sorted(self.runs[1]))


def _simplify(points):
    """Drop repeated points and the middle of three in a line."""
    out = []
    for p in points:
        if out and p == out[-1]:
            continue
        if len(out) >= 2 and (out[-2][0] == out[-1][0] == p[0] or out[-2][1] == out[-1][1] == p[1]):
            out[-1] = p
        else:
            out.append(p)
    return out


def _inner(wires, axis):
    """The segments of wires that may move: [at, lo, hi, net, wire, index] of each inner
    segment along ``axis`` (1: vertical, at an x; 0: horizontal, at a y)."""
    out = []
    for w, (points, net) in enumerate(wires):
        for k in range(1, len(points) - 2):
            (x0, y0), (x1, y1) = points[k], points[k + 1]
            if (x0 == x1) == (axis == 1):
                out.append([x0, min(y0, y1), max(y0, y1), net, w, k] if axis == 1 else
                           [y0, min(x0, x1), max(x0, x1), net, w, k])
    return out


def _move(wires, blocks, axis, seg, new):
    """Move an inner segment to ``new`` unless a block is in the way there."""
    _, lo, hi, _, w, k = seg
    if any((b[0] < new < b[2] and b[1] < hi and b[3] > lo) if axis == 1 else
           (b[1] < new < b[3] and b[0] < hi and b[2] > lo) for b in blocks):
        return False
    points = wires[w][0]
    for j in (k, k + 1):
        x, y = points[j]
        points[j] = (new, y) if axis == 1 else (x, new)
    seg[0] = new
    return True


def _spread(wires, blocks):
    """Tidy the tracks: segments of one net a few units apart that meet are put on one
    track; segments of different nets on one track are moved apart, in the order that
    crosses least. Only inner segments move (a wire's ends stay on its ports)."""
    for axis in (1, 0):
        segs = _inner(wires, axis)
        for i, seg in enumerate(segs):
            for other in segs[:i]:
                if other[3] == seg[3] and 0 < abs(other[0] - seg[0]) <= 4 and \
                        seg[1] <= other[2] and other[1] <= seg[2]:
                    if _move(wires, blocks, axis, seg, other[0]):
                        break
        groups = {}
        for seg in _inner(wires, axis):
            groups.setdefault(seg[0], []).append(seg)
        for at, segs in sorted(groups.items()):
            segs.sort(key=lambda s: (s[1], s[2], s[4]))
            clusters, reach = [], -math.inf
            for seg in segs:
                if clusters and seg[1] < reach:
                    clusters[-1].append(seg)
                    reach = max(reach, seg[2])
                else:
                    clusters.append([seg])
                    reach = seg[2]
            for cluster in clusters:
                nets = list(dict.fromkeys(s[3] for s in cluster))
                if len(nets) > 1:
                    _spread_cluster(wires, blocks, axis, at, cluster, nets)


def _spread_cluster(wires, blocks, axis, at, cluster, nets):
    # arms: where each net's segments turn off the track, and to which side
    arms = {net: [] for net in nets}
    spans = {net: [math.inf, -math.inf] for net in nets}
    for _, lo, hi, net, w, k in cluster:
        points = wires[w][0]
        spans[net] = [min(spans[net][0], lo), max(spans[net][1], hi)]
        for end, other in ((k, k - 1), (k + 1, k + 2)):
            p, q = points[end], points[other]
            along = p[1] if axis == 1 else p[0]
            away = q[0] - p[0] if axis == 1 else q[1] - p[1]
            arms[net].append((along, 1 if away > 0 else -1))

    def crossings(arrangement):
        total = 0
        for i, n in enumerate(arrangement):
            for m in arrangement[i + 1:]:           # n before m
                total += sum(1 for y, s in arms[n] if s > 0 and spans[m][0] < y < spans[m][1])
                total += sum(1 for y, s in arms[m] if s < 0 and spans[n][0] < y < spans[n][1])
        return total
    if len(nets) <= 6:
        arrangement = min(itertools.permutations(nets), key=crossings)
    else:
        arrangement = sorted(nets, key=lambda n: sum(spans[n]))
    for i, net in enumerate(arrangement):
        shift = (i - (len(arrangement) - 1) / 2) * 6
        if shift:
            for seg in cluster:
                if seg[3] == net:
                    _move(wires, blocks, axis, seg, at + shift)


def _junctions(wires):
    """Points where wires of one net branch: three or more directions meet."""
    dots = []
    nets = {}
    for points, net in wires:
        nets.setdefault(net, []).append(points)
    for net, paths in nets.items():
        if len(paths) < 2:
            continue
        segments = {tuple(sorted((p, q))) for path in paths for p, q in zip(path, path[1:])}
        for point in dict.fromkeys(p for path in paths for p in path):
            ways = set()
            for p, q in segments:
                if point == p or point == q:
                    other = q if point == p else p
                    ways.add((_sign(other[0] - point[0]), _sign(other[1] - point[1])))
                elif (p[0] == q[0] == point[0] and p[1] < point[1] < q[1]) or \
                        (p[1] == q[1] == point[1] and p[0] < point[0] < q[0]):
                    ways.update({(0, 1), (0, -1)} if p[0] == q[0] else {(1, 0), (-1, 0)})
            if len(ways) >= 3:
                dots.append((point, net))
    return dots


def _sign(v):
    return (v > 0) - (v < 0)


# -- the drawing -------------------------------------------------------------------------
def svg(model):
    """The wiring diagram of ``model`` as SVG text: blocks where ``auto_layout`` puts them,
    ports on their sides in Modelica's colours, orthogonal wires. A model of subsystems is
    drawn one level deep (each subsystem a block with its exposed ports); a half-built
    model (ports left open, no layout) draws too."""
    boxes = {name: _Box(comp) for name, comp in model.components.items()}
    spots = _place(model, boxes)
    links = _links(model)
    _face_ports(boxes, spots, links)
    nets = _nets(model)
    ends = {}
    for name, box in boxes.items():
        x, y = spots[name]
        for port, (dx, dy) in box.at.items():
            ends[(name, port)] = ((x + dx, y + dy), _OUT[box.sides[port]])
    order = sorted(range(len(links)), key=lambda k: (_distance(ends, links[k]), k))
    routed = [None] * len(links)
    stubs = [(x + d[0] * STUB, y + d[1] * STUB) for (x, y), d in ends.values()]
    router = _Router([(spots[n][0], spots[n][1], b.w, b.h) for n, b in boxes.items()], stubs)
    for k in order:
        a, pa, b, pb = links[k]
        (pa_xy, da), (pb_xy, db) = ends[(a, pa)], ends[(b, pb)]
        net = nets[(a, pa)]
        if len(links) > ROUTED:
            stub_a = (pa_xy[0] + da[0] * STUB, pa_xy[1] + da[1] * STUB)
            stub_b = (pb_xy[0] + db[0] * STUB, pb_xy[1] + db[1] * STUB)
            points = _simplify([pa_xy, stub_a, (stub_b[0], stub_a[1]), stub_b, pb_xy])
        else:
            points = router.route(pa_xy, da, pb_xy, db, net)
        routed[k] = (points, net)
    _spread(routed, router.blocks)
    return _draw(model, boxes, spots, links, routed, nets)


def _distance(ends, link):
    (p, _), (q, _) = ends[(link[0], link[1])], ends[(link[2], link[3])]
    return abs(p[0] - q[0]) + abs(p[1] - q[1])


def _face_ports(boxes, spots, links):
    """Top and bottom ports face the blocks they are wired to (an axis wired only to a
    probe below moves to the bottom); a part with one port turns it to what it meets."""
    peers = {}
    for a, pa, b, pb in links:
        peers.setdefault((a, pa), []).append((b, pb))
        peers.setdefault((b, pb), []).append((a, pa))

    def centre(name):
        return spots[name][0] + boxes[name].w / 2, spots[name][1] + boxes[name].h / 2
    for name, box in boxes.items():
        if box.single:
            continue
        ends = [p for p, side in box.sides.items() if side in ("top", "bottom")]
        chosen = {}
        for port in ends:
            ys = [centre(other)[1] for other, _ in peers.get((name, port), ()) if other != name]
            if ys:
                mean, y = sum(ys) / len(ys), spots[name][1]
                chosen[port] = "top" if mean < y else "bottom" if mean > y + box.h else \
                    box.sides[port]
        # ports wired to nothing follow the others (an elbow's support follows its axis)
        if len(set(chosen.values())) == 1:
            side = next(iter(chosen.values()))
            chosen.update({p: side for p in ends if p not in chosen})
        if any(box.sides[p] != side for p, side in chosen.items()):
            box.sides.update(chosen)
            box.arrange()
    for name, box in boxes.items():
        if not box.single:
            continue
        for port in box.sides:
            others = [o for o in peers.get((name, port), ()) if o[0] != name]
            if not others:
                continue
            other, oport = others[0]
            ox, oy = spots[other][0] + boxes[other].at[oport][0], \
                spots[other][1] + boxes[other].at[oport][1]
            x, y = spots[name]
            beyond = {"left": x - ox, "right": ox - x - box.w,
                      "top": y - oy, "bottom": oy - y - box.h}
            if not box.probe and boxes[other].sides[oport] in ("left", "right"):
                beyond["top"] = beyond["bottom"] = -math.inf
            box.sides[port] = max(beyond, key=lambda s: (beyond[s], s in ("left", "right")))
        box.arrange()


def _nets(model):
    """Each port's connection set: (component, port) -> net number."""
    graph = nx.Graph()
    for a, b in model.connections:
        graph.add_edge((a.component.name, a.name), (b.component.name, b.name))
    out = {}
    components = sorted((sorted(c, key=str) for c in nx.connected_components(graph)),
                        key=lambda c: str(c[0]))
    for i, members in enumerate(components):
        for member in members:
            out[member] = i
    return out


def _net_domain(model, nets):
    domains = {}
    for (name, port), net in nets.items():
        domain = _domain(model.components[name], port)
        if domain != ANY:
            domains.setdefault(net, domain)
    return domains


def _f(v):
    """A coordinate as SVG text: short, exact for the halves layouts give."""
    return f"{round(v, 1):g}"


def _path(points, radius=4.0):
    """SVG path data: straight runs with rounded corners."""
    d = [f"M{_f(points[0][0])},{_f(points[0][1])}"]
    for p, c, n in zip(points, points[1:], points[2:]):
        r = min(radius, math.dist(p, c) / 2, math.dist(c, n) / 2)
        a = (c[0] + _sign(p[0] - c[0]) * r, c[1] + _sign(p[1] - c[1]) * r)
        b = (c[0] + _sign(n[0] - c[0]) * r, c[1] + _sign(n[1] - c[1]) * r)
        d.append(f"L{_f(a[0])},{_f(a[1])} Q{_f(c[0])},{_f(c[1])} {_f(b[0])},{_f(b[1])}")
    d.append(f"L{_f(points[-1][0])},{_f(points[-1][1])}")
    return " ".join(d)


def _draw(model, boxes, spots, links, routed, nets):
    domains = _net_domain(model, nets)
    xs, ys = [], []
    for name, (x, y) in spots.items():
        xs += [x - 30, x + boxes[name].w + 30]
        ys += [y - 16, y + boxes[name].h + 16]
    for points, _ in routed:
        xs += [p[0] for p in points]
        ys += [p[1] for p in points]
    if not xs:
        xs, ys = [0, 200], [0, 60]
    x0, y0 = math.floor(min(xs)) - 12, math.floor(min(ys)) - 12
    width, height = math.ceil(max(xs)) + 12 - x0, math.ceil(max(ys)) + 12 - y0
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="{x0} {y0} {width} {height}" '
           f'width="{width}" height="{height}" font-family="Helvetica, Arial, sans-serif">',
           f"<title>{escape(model.name)}</title>",
           f'<rect x="{x0}" y="{y0}" width="{width}" height="{height}" fill="#ffffff"/>',
           '<g class="wires" fill="none" stroke-linejoin="round">']
    for (a, pa, b, pb), (points, net) in zip(links, routed):
        colour, stroke = DOMAINS[domains.get(net, ANY)]
        out.append(f'<path class="wire" data-from="{a}.{pa}" data-to="{b}.{pb}" '
                   f'stroke="{colour}" stroke-width="{stroke}" d="{_path(points)}"/>')
    for (x, y), net in _junctions(routed):
        colour, stroke = DOMAINS[domains.get(net, ANY)]
        out.append(f'<circle class="junction" cx="{_f(x)}" cy="{_f(y)}" r="{stroke + 1.6:g}" '
                   f'fill="{colour}"/>')
    out.append("</g>")
    turns = {}                      # which way wires turn after leaving a port: labels avoid it
    for (a, pa, b, pb), (points, _) in zip(links, routed):
        for end, path in (((a, pa), points), ((b, pb), points[::-1])):
            if len(path) > 2:
                turns.setdefault(end, set()).add(_sign(path[2][0] - path[1][0]))
    for name, box in boxes.items():
        out += _block(box, *spots[name], domains, nets, turns)
    out.append("</svg>")
    return "\n".join(out) + "\n"


def _block(box, x, y, domains, nets, turns):
    comp = box.comp
    library = _library(comp)
    border, fill = LIBRARIES.get(library, LIBRARIES["multibody"])
    kind = comp.type_name if not isinstance(comp, Subsystem) else comp.definition.name
    out = [f'<g class="block" data-name="{box.name}" data-type={quoteattr(kind or "")} '
           f'data-x="{_f(x)}" data-y="{_f(y)}" data-w="{box.w}" data-h="{box.h}">',
           f"<title>{escape(box.name)}: {escape(kind or '')}</title>"]
    if library == "subsystem":        # a stack of sheets: a model inside
        out.append(f'<rect x="{_f(x + 3)}" y="{_f(y + 3)}" width="{box.w}" height="{box.h}" '
                   f'rx="5" fill="{fill}" stroke="{border}" stroke-width="1"/>')
    radius = box.h / 2 if box.probe else 5
    out.append(f'<rect class="body" x="{_f(x)}" y="{_f(y)}" width="{box.w}" height="{box.h}" '
               f'rx="{_f(radius)}" fill="{fill}" stroke="{border}" stroke-width="1.2"/>')
    cx = x + box.w / 2
    if box.probe:
        out.append(_glyph("probe", x + 12, y + box.h / 2, border))
        out.append(f'<text x="{_f(x + 22)}" y="{_f(y + box.h / 2 + 3.2)}" font-size="9" '
                   f'fill="#1a1a1a">{escape(box.name)}</text>')
    else:
        out.append(f'<text x="{_f(cx)}" y="{_f(y + 13)}" font-size="{NAME_PX}" '
                   f'font-weight="bold" text-anchor="middle" fill="#1a1a1a">'
                   f"{escape(box.name)}</text>")
        out.append(f'<text x="{_f(cx)}" y="{_f(y + 17 + box.rows * ROW + 10)}" '
                   f'font-size="{TYPE_PX:g}" '
                   f'text-anchor="middle" fill="#6e6e6e">{escape(box.kind)}</text>')
        labels = [p for p in comp.ports if box.sides[p] in ("left", "right")]
        room = box.w - 2 * max((_text_width(p, LABEL_PX) for p in labels), default=0) - 18
        if room >= 14:
            out.append(_glyph(library, cx, y + 17 + box.rows * ROW / 2, border))
    for port, (dx, dy) in box.at.items():
        px, py = x + dx, y + dy
        side = box.sides[port]
        domain = _domain(comp, port)
        if domain == ANY:
            domain = domains.get(nets.get((box.name, port)), ANY)
        out.append(_marker(comp, port, side, domain, px, py))
        if box.probe:
            continue
        # beside a top or bottom port: outwards when two share the side; else away from
        # where its wires turn
        pair = sum(1 for p in box.sides if box.sides[p] == side) == 2
        right = not (pair and dx < box.w / 2 - 1)
        taken = turns.get((box.name, port), set())
        if not pair and 1 in taken and -1 not in taken:
            right = False
        outward, shift = ("start", 5) if right else ("end", -5)
        anchor = {"left": ("start", px + 7, py + 2.5), "right": ("end", px - 7, py + 2.5),
                  "top": (outward, px + shift, py - 4), "bottom": (outward, px + shift, py + 8.5)}
        how, tx, ty = anchor[side]
        out.append(f'<text x="{_f(tx)}" y="{_f(ty)}" font-size="{LABEL_PX:g}" '
                   f'text-anchor="{how}" fill="#555555">{escape(port)}</text>')
    out.append("</g>")
    return out


def _marker(comp, port, side, domain, x, y):
    """A port's marker, centred on the block's edge: Modelica's shapes and colours."""
    colour = DOMAINS.get(domain, DOMAINS[ANY])[0]
    solid = port.endswith("_a") or comp.role == "world"
    head = f'<g class="port" data-port="{comp.name}.{port}" data-x="{_f(x)}" data-y="{_f(y)}">'
    if comp.ports[port].domain in ("signal_in", "signal_out"):
        inward = comp.ports[port].domain == "signal_in"
        ux, uy = _OUT[side]
        if inward:
            ux, uy = -ux, -uy
        tip = (x + ux * 4.5, y + uy * 4.5)
        back = (x - ux * 4.5, y - uy * 4.5)
        wing = (uy * 4.5, ux * 4.5)
        points = " ".join(f"{_f(px)},{_f(py)}" for px, py in
                          (tip, (back[0] + wing[0], back[1] + wing[1]),
                           (back[0] - wing[0], back[1] - wing[1])))
        fill = colour if inward else "#ffffff"
        shape = f'<polygon points="{points}" fill="{fill}" stroke="{colour}" stroke-width="1"/>'
    elif domain == "rotational":
        fill = colour if solid else "#ffffff"
        shape = (f'<circle cx="{_f(x)}" cy="{_f(y)}" r="4" fill="{fill}" stroke="{colour}" '
                 f'stroke-width="1.2"/>')
    elif domain in ("frame", "translational"):
        fill = colour if solid else "#ffffff" if domain == "translational" else "#c8c8c8"
        shape = (f'<rect x="{_f(x - 4)}" y="{_f(y - 4)}" width="8" height="8" fill="{fill}" '
                 f'stroke="{colour}" stroke-width="1.2"/>')
    else:
        shape = f'<circle cx="{_f(x)}" cy="{_f(y)}" r="3" fill="{colour}"/>'
    return head + shape + "</g>"


def _glyph(library, x, y, colour):
    """A small sign of the library, centred on (x, y)."""
    s = f'stroke="{colour}" stroke-width="1.1" fill="none"'
    if library == "multibody":          # a frame: two axes
        return (f'<path class="glyph" d="M{_f(x - 5)},{_f(y + 4)} h10 M{_f(x - 5)},{_f(y + 4)} '
                f'v-9 M{_f(x + 3)},{_f(y + 2)} l2,2 -2,2 M{_f(x - 7)},{_f(y - 3)} l2,-2 2,2" {s}/>')
    if library == "rotational":         # a turning arrow
        return (f'<path class="glyph" d="M{_f(x + 4)},{_f(y - 3)} A5,5 0 1 0 {_f(x + 5)},'
                f'{_f(y + 1)} M{_f(x + 2)},{_f(y - 4)} l2,1 1,-2.2" {s}/>')
    if library == "translational":      # a push both ways
        return (f'<path class="glyph" d="M{_f(x - 6)},{_f(y)} h12 M{_f(x - 3)},{_f(y - 3)} '
                f'l-3,3 3,3 M{_f(x + 3)},{_f(y - 3)} l3,3 -3,3" {s}/>')
    if library == "signals":            # a step
        return f'<path class="glyph" d="M{_f(x - 6)},{_f(y + 4)} h5 v-8 h7" {s}/>'
    if library == "probe":              # a dial
        return (f'<path class="glyph" d="M{_f(x - 5)},{_f(y + 3)} A5,5 0 0 1 {_f(x + 5)},'
                f'{_f(y + 3)} M{_f(x)},{_f(y + 3)} l3,-5" {s}/>')
    return (f'<path class="glyph" d="M{_f(x - 6)},{_f(y - 4)} h8 v6 h-8 z M{_f(x - 2)},'
            f'{_f(y)} h8 v6 h-8 z" {s}/>')


# -- faces -------------------------------------------------------------------------------
def cli_diagram(args, model):
    """``kinetwork diagram MODEL -o out.svg``: write the diagram; the exit code."""
    path = args.out
    if not str(path).lower().endswith(".svg"):
        raise ModelError(f"-o {path}: a diagram is written as SVG; name a .svg file")
    reads = model_files(model)
    check(path, "svg", what="-o", reads=reads, force=getattr(args, "force", False))
    text = svg(model)

    def fill(tmp):
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)
    try:
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        write(path, fill, "svg", what="-o", reads=reads, force=getattr(args, "force", False))
    except OSError as exc:
        raise ModelError(f"cannot write {path}: {exc.strerror or exc}") from None
    print(f"wrote the diagram of {model.name} ({len(model.components)} components, "
          f"{len(model.connections)} connections) to {path}")
    return 0


def _repr_svg_(model):
    """Jupyter shows a model as its diagram."""
    return svg(model)


Model._repr_svg_ = _repr_svg_
