"""The layered layout of a wiring diagram (``auto_layout``): the idea of ELK's layered
algorithm (Sugiyama's method) with ports on fixed sides.

The flow runs left to right: a wire from a port on a block's right side (``frame_b``,
``flange_b``, an output) to one on another's left side (``frame_a``, ``flange_a``, an
input) puts the second block one layer further. Parts hanging only on a block's top or
bottom ports (the spring-damper on a joint's support and axis, a probe on an axis) stand
above or below it in its layer, as in Modelica diagrams. Cycles are broken where a
depth-first walk from the model's inputs closes them (a controller's measured feedback runs
back), layers are given by the longest path, long wires get placeholders in the layers they
cross, the order within layers comes from barycentre sweeps on the ports' heights and then
swaps of neighbours, and the heights from an isotonic fit that keeps that order while
straightening wires. Components a layout places stay put; the others are laid out by
connected groups around them, each moved to the nearest free room.
"""

import itertools
import math

import networkx as nx

from ..graph.subsystem import Subsystem
from .blocks import (LAYER_GAP, NODE_GAP, ROOM, SAT_GAP, TRACK, Block, connections_of,
                     given_positions, placement)


def auto_layout(model):
    """Where each component's block goes: ``{name: {"x", "y", "w", "h"}}``.

    ``x``, ``y`` are the block's top left corner (y downwards), ``w``, ``h`` its size, in
    the units of the model's ``layout``. A component the layout places keeps its position;
    the others are placed by a port-aware layered layout (see the module's docstring).
    The same model always gets the same layout.
    """
    boxes = {name: Block(comp, *placement(model, name)) for name, comp in model.components.items()}
    spots = place_blocks(model, boxes)
    return {name: {"x": spots[name][0], "y": spots[name][1], "w": boxes[name].w,
                   "h": boxes[name].h} for name in model.components}


def place_blocks(model, boxes):
    """Positions of every block: the given ones, and groups of the others around them."""
    spots = given_positions(model)
    order = {name: i for i, name in enumerate(model.components)}
    links = [link for link in connections_of(model) if link[0] != link[2]]
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
